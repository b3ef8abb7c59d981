#include "delta/query/pair_cache.h"

#include <limits>

#include "detail/dual_traversal.h"

namespace delta::contactdetection {

double PairCache::moveSince(const QueryMesh& first, const QueryMesh& second, const Mat3& rotation,
                            const Vec3& translation) const noexcept {
  if (!valid_ || firstData_ != first.sharedData() || secondData_ != second.sharedData())
    return std::numeric_limits<double>::infinity();
  return detail::relativeMove(first.data(), second.data(), {rotation, translation}, rotation_,
                              translation_);
}

void PairCache::keep(const QueryMesh& first, const QueryMesh& second, const Mat3& rotation,
                     const Vec3& translation, double allowance) {
  valid_ = true;
  firstData_ = first.sharedData();
  secondData_ = second.sharedData();
  rotation_ = rotation;
  translation_ = translation;
  allowance_ = allowance;
  budget_ = skin_ - allowance;
  ++made_;
}

}  // namespace delta::contactdetection
