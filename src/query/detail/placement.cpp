#include "placement.h"

#include "delta/mesh/coordinate_range.h"

#include "query_mesh_data.h"

namespace delta::detail {

/// A sufficient test, one rotation instead of movedBox's eight: every point of `box` moved by
/// `motion` lies within the ball about the moved centre of the box's half diagonal, so within
/// the range when that ball's reach from the origin is (with a factor of two to spare for the
/// rounding of these few operations). False also where it overflows or meets a NaN.
bool surelyInRange(const Aabb& box, const RigidTransform& motion) noexcept {
  if (box.empty()) return true;
  const double reach =
      length(motion.apply((box.lower + box.upper) * 0.5)) + 0.5 * length(box.upper - box.lower);
  return reach <= 0.5 * kLargestCoordinate;
}

RigidTransform checkPlacedPair(const QueryMesh& first, const QueryMesh& second, const char* query) {
  const RigidTransform secondToFirst = first.inversePose() * second.pose();
  if (!first.moved() && !second.moved()) return secondToFirst;  // checked when prepared
  // Called for every pair of a DEM step: each mesh's own quick test made once a pose, the exact
  // boxes and the messages only where the quick tests cannot tell.
  if (first.placedSurelyInRange() && second.placedSurelyInRange() &&
      surelyInRange(second.bounds(), secondToFirst))
    return secondToFirst;
  const Aabb placed[3] = {movedBox(first.bounds(), first.pose()),
                          movedBox(second.bounds(), second.pose()),
                          movedBox(second.bounds(), secondToFirst)};
  constexpr const char* kWhich[3] = {": the first mesh", ": the second mesh",
                                     ": the second mesh, carried into the first's frame,"};
  for (std::size_t i = 0; i < 3; ++i)
    if (!boxInCoordinateRange(placed[i]))
      checkCoordinateRange(placed[i], std::string(query) + kWhich[i]);
  return secondToFirst;
}

void requireTrianglesSpan(const QueryMesh& mesh, const std::string& what) {
  if (const auto& tiny = mesh.data().tinyTriangle) [[unlikely]]
    checkTriangleExtent(tiny->second, tiny->first, what);
}

}  // namespace delta::detail
