#pragma once

#include <cstddef>
#include <numeric>
#include <vector>

namespace delta::detail {

/// Disjoint sets over the indices [0, count) (union–find with path halving), held in a buffer of
/// the caller's, so that a query that makes sets again and again reuses one allocation (the
/// overlap query's faces and regions, recycled per thread). Which element of a set is its root
/// depends on the order of the joins; the callers name sets by something else (their first
/// element in an order of their own), so their answers do not.
///
/// Threading: one thread at a time, as its buffer.
template <typename Index>
class UnionFind {
 public:
  explicit UnionFind(std::vector<Index>& parent) noexcept : parent_(parent) {}

  /// `count` singletons.
  void reset(std::size_t count) {
    parent_.resize(count);
    std::iota(parent_.begin(), parent_.end(), Index{0});
  }
  Index find(Index i) noexcept {
    while (parent_[i] != i)
      i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  /// Joins the sets of `i` and `j`.
  void join(Index i, Index j) noexcept {
    const Index a = find(i), b = find(j);
    parent_[a] = b;
  }

 private:
  std::vector<Index>& parent_;
};

}  // namespace delta::detail
