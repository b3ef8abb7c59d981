#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "delta/core/aligned_allocator.h"
#include "delta/core/vec3.h"
#include "delta/kernels/detail/batch_views.h"

namespace delta::kernels {

/// Per-pair results of the batched triangle–triangle solvers (bruteForceDistances,
/// penaltyDistances, hybridDistances), structure of arrays: one stream per quantity, each
/// 64-byte aligned. The caller allocates it once (`PairResults results(n)`) and reuses it, so no
/// solver allocates; a call writes pairs [0, size()) and leaves the rest of the capacity as it was.
/// The solvers are noexcept and never grow it: a call over more pairs than capacity() computes
/// only the first capacity() of them (size() says how many) — reserve the batch size first.
///
/// Per pair i: the squared distance, the closest points p (on the first triangle) and q (on the
/// second), `intersect`, and, for the penalty solver, a certified error bound, the Newton step and
/// a `converged` flag (see penaltyDistances). The exact solvers write errorBound = 0 and
/// converged = true.
///
/// Threading: a value type; a const PairResults may be read from any number of threads, a
/// solver writing into it needs exclusive access.
class PairResults {
 public:
  PairResults() = default;
  explicit PairResults(std::size_t capacity) { reserve(capacity); }

  /// Makes room for `capacity` pairs (allocates, and may throw std::bad_alloc; never shrinks;
  /// keeps size() and the pairs written).
  void reserve(std::size_t capacity);
  std::size_t capacity() const noexcept { return capacity_; }
  /// The pairs written by the last solver call.
  std::size_t size() const noexcept { return size_; }

  // Per pair i < size(), unchecked.

  double distanceSquared(std::size_t i) const noexcept { return stream(kDistanceSquared)[i]; }
  double distance(std::size_t i) const noexcept { return std::sqrt(distanceSquared(i)); }
  /// The closest point on the first triangle.
  Vec3 p(std::size_t i) const noexcept {
    return {stream(kPx)[i], stream(kPx + 1)[i], stream(kPx + 2)[i]};
  }
  /// The closest point on the second triangle.
  Vec3 q(std::size_t i) const noexcept {
    return {stream(kQx)[i], stream(kQx + 1)[i], stream(kQx + 2)[i]};
  }
  /// The triangles share a point (then distance 0 and p = q, a point of both).
  bool intersect(std::size_t i) const noexcept { return flags_[i] != 0; }
  /// The solver vouches for this pair's answer (always true but for the penalty solver).
  bool converged(std::size_t i) const noexcept { return flags_[capacity_ + i] != 0; }
  /// An upper bound of distance(i) − (true distance), certified (up to rounding); 0 for the
  /// exact solvers.
  double errorBound(std::size_t i) const noexcept { return stream(kErrorBound)[i]; }
  /// The last Newton step, max |Δa| over the four barycentric unknowns, or the constraint
  /// violation of the Newton point if larger (dimensionless: relative to the triangles' size);
  /// 0 for the brute force.
  double newtonStep(std::size_t i) const noexcept { return stream(kNewtonStep)[i]; }

  /// The streams, for consumers that read them with SIMD: size() values each.
  const double* distanceSquaredData() const noexcept { return stream(kDistanceSquared); }
  const double* pData(int axis) const noexcept { return stream(kPx + axis); }
  const double* qData(int axis) const noexcept { return stream(kQx + axis); }
  const std::uint8_t* intersectData() const noexcept { return flags_.data(); }
  const std::uint8_t* convergedData() const noexcept { return flags_.data() + capacity_; }

  /// For the solvers: sets size() to min(count, capacity()) and returns where to write.
  detail::PairStreams prepare(std::size_t count) noexcept;

 private:
  enum Stream { kDistanceSquared, kPx, kQx = kPx + 3, kErrorBound = kQx + 3, kNewtonStep, kCount };
  const double* stream(int s) const noexcept { return doubles_.data() + s * stride_; }

  std::size_t size_ = 0;
  std::size_t capacity_ = 0;
  std::size_t stride_ = 0;  ///< capacity rounded up to whole 64-byte lines
  AlignedDoubles doubles_;
  std::vector<std::uint8_t> flags_;  ///< intersect, then converged, capacity_ each
};

/// What one batched call did.
///
/// Threading: a value type; no shared state.
struct BatchStatistics {
  std::size_t pairs = 0;        ///< pairs computed (= results.size())
  std::size_t rechecked = 0;    ///< hybrid: pairs its first stage left to its exhaustive stage
  std::size_t fallbacks = 0;    ///< hybrid: pairs the scalar brute force recomputed
  std::size_t unconverged = 0;  ///< penalty: pairs with converged = false

  double fallbackRate() const noexcept {
    return pairs == 0 ? 0.0 : static_cast<double>(fallbacks) / static_cast<double>(pairs);
  }
};

}  // namespace delta::kernels
