#include "delta/mesh/coordinate_range.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "delta/core/error.h"
#include "delta/core/format.h"

namespace delta {

double magnitude(const Aabb& box) noexcept {
  if (box.empty()) return 0.0;
  const Vec3 corners[2] = {box.lower, box.upper};
  double largest = 0.0;
  for (const Vec3& corner : corners)
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (std::isnan(corner[axis])) return std::numeric_limits<double>::quiet_NaN();
      largest = std::max(largest, std::fabs(corner[axis]));
    }
  return largest;
}

std::string coordinateRangeText() {
  return "±2^200 (" + toString(kLargestCoordinate) + ")";
}

void checkCoordinateRange(const Aabb& box, const std::string& what) {
  if (magnitude(box) <= kLargestCoordinate) return;
  throw Error(what + " reaches a coordinate of " + toString(magnitude(box)) + " (its box is " +
              toString(box.lower) + " to " + toString(box.upper) +
              "): Δ answers exactly only for coordinates within " + coordinateRangeText() +
              ", beyond which squared distances and the kernels' products overflow; move the "
              "geometry nearer the origin");
}

void checkMeshScale(const Aabb& box, const std::string& what) {
  checkCoordinateRange(box, what);
  if (magnitude(box) >= kSmallestMeshScale) return;
  throw Error(what + " lies within " + toString(magnitude(box)) +
              " of the origin: Δ needs a mesh's largest |coordinate| to be at least 2^-200 (" +
              toString(kSmallestMeshScale) +
              "), below which the kernels' products underflow; scale it up by a power of two "
              "(exact) and the answers down");
}

Aabb boundsOf(const TriangleSoA& mesh) noexcept {
  Aabb box;
  bool finite = true;
  for (std::size_t t = 0; t < mesh.size(); ++t) {
    const Triangle triangle = mesh.triangle(t);
    for (const Vec3& vertex : {triangle.a, triangle.b, triangle.c}) {
      finite = finite && isFinite(vertex);
      box.extend(vertex);
    }
  }
  // A NaN extends a box unpredictably: a mesh with a non-finite coordinate gets a NaN box,
  // which every range check refuses.
  if (!finite) box.lower.x = std::numeric_limits<double>::quiet_NaN();
  return box;
}

void checkMeshScale(const TriangleSoA& mesh, const std::string& what) {
  checkMeshScale(boundsOf(mesh), what);
  for (std::size_t t = 0; t < mesh.size(); ++t)
    checkTriangleExtent(mesh.triangle(t), t, what);
}

double triangleExtent(const Triangle& triangle) noexcept {
  return std::max({maxAbs(triangle.b - triangle.a), maxAbs(triangle.c - triangle.a),
                   maxAbs(triangle.c - triangle.b)});
}

void checkTriangleExtent(const Triangle& triangle, std::size_t index, const std::string& what) {
  // Differences this small are of coordinates near the origin (elsewhere two corners either
  // coincide or lie an ulp of theirs apart), where they are exact.
  const double extent = triangleExtent(triangle);
  if (extent == 0.0 || extent >= kSmallestTriangleExtent) return;
  throw Error(what + "'s triangle " + std::to_string(index) + " spans only " + toString(extent) +
              " (its corners " + toString(triangle.a) + ", " + toString(triangle.b) + ", " +
              toString(triangle.c) + "): Δ needs a triangle to be one point or at least 2^-200 (" +
              toString(kSmallestTriangleExtent) +
              ") across, below which the kernels' products underflow and the mesh–mesh queries "
              "would take it for flat; scale the mesh up by a power of two (exact) and the "
              "answers down, or merge its corners");
}

void checkPointRange(const Vec3& point, const std::string& what) {
  if (inCoordinateRange(point)) return;
  throw Error(what + " " + toString(point) + " has a coordinate beyond " + coordinateRangeText() +
              ", the range in which Δ's distances are exact (squared distances and the kernels' "
              "products would overflow)");
}

}  // namespace delta
