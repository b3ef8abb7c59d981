#pragma once

#include <cmath>
#include <cstddef>
#include <memory>

#include "delta/core/mat3.h"
#include "delta/core/vec3.h"
#include "delta/query/query_mesh.h"

/// @file
/// What the caches of a pair of prepared meshes share (ContactCache, query/contacts.h;
/// OverlapCache, query/overlap.h): the skin, the meshes and the relative pose they were made at,
/// how far the pair may move from it, and their counts.

namespace delta::contactdetection {

/// The common part of a mesh pair's cache; not used alone. It was made for two prepared meshes
/// (held, so that no other mesh comes to their addresses) with the second at (R₀, t₀) in the
/// first's prepared frame, and holds while the two have moved less than the skin, less the
/// rounding allowed for, against each other: the smaller of the second's move in the first's
/// frame and the first's in the second's, each bounded by its box centre's move plus ‖R − R₀‖
/// times its radius about that centre (a particle turning next to a large obstacle moves little
/// in the obstacle's frame, while the obstacle's far corners swing round in its own).
///
/// Threading: a value type; one cache belongs to one pair, used by one thread at a time.
class PairCache {
 public:
  /// The skin it was given.
  double skin() const noexcept { return skin_; }
  /// How many calls made it anew, and how many it answered; for statistics.
  std::size_t made() const noexcept { return made_; }
  std::size_t reused() const noexcept { return reused_; }
  /// Forgets what it holds: the next call makes it anew.
  void clear() noexcept {
    valid_ = false;
    firstData_.reset();
    secondData_.reset();
  }

 protected:
  explicit PairCache(double skin) noexcept : skin_(skin) {}
  ~PairCache() = default;
  PairCache(const PairCache&) = default;
  PairCache(PairCache&&) noexcept = default;
  PairCache& operator=(const PairCache&) = default;
  PairCache& operator=(PairCache&&) noexcept = default;

  /// Whether a skin was asked for (finite and positive); without one every call is a fresh
  /// query.
  bool keeps() const noexcept { return std::isfinite(skin_) && skin_ > 0.0; }
  /// How far the pair has moved against each other since the cache was made, the second now at
  /// (`rotation`, `translation`) in the first's prepared frame; +∞ where it was made for other
  /// meshes, or not made.
  double moveSince(const QueryMesh& first, const QueryMesh& second, const Mat3& rotation,
                   const Vec3& translation) const noexcept;
  /// Whether a move (moveSince) leaves what the cache holds valid: no more than the skin less
  /// the rounding allowed for.
  bool holds(double move) const noexcept { return valid_ && move <= budget_; }
  /// Now made for (first, second), the second at (`rotation`, `translation`) in the first's
  /// prepared frame, allowing `allowance` for the rounding of what the caller kept and of the
  /// move's measure; counts it made.
  void keep(const QueryMesh& first, const QueryMesh& second, const Mat3& rotation,
            const Vec3& translation, double allowance);
  /// The allowance keep() was given.
  double allowance() const noexcept { return allowance_; }
  /// Counts a call the cache answered.
  void answered() noexcept { ++reused_; }
  /// Counts a fresh query made without keeping anything (no skin).
  void madeWithoutKeeping() noexcept { ++made_; }

 private:
  double skin_ = 0.0;
  bool valid_ = false;
  std::shared_ptr<const void> firstData_, secondData_;
  Mat3 rotation_;
  Vec3 translation_;
  double budget_ = 0.0;     ///< how far the pair may move: the skin less the allowance
  double allowance_ = 0.0;  ///< the rounding allowed for
  std::size_t made_ = 0, reused_ = 0;
};

}  // namespace delta::contactdetection
