#include "delta/kernels/segment_segment.h"

#include "detail/robust_geometry.h"

namespace delta::kernels {

SegmentSegmentResult closestPointsOnSegments(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                             const Vec3& q1) noexcept {
  // In the frame of p0, so that far from the origin the differences stay exact.
  const detail::SegmentPair local = detail::closestOnSegments({}, p1 - p0, q0 - p0, q1 - p0);
  return {local.distanceSquared, local.p + p0, local.q + p0, local.s, local.t};
}

}  // namespace delta::kernels
