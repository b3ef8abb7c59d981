// The overlap query's first filter (query/detail/dual_traversal.h's movedLeafBoxes): a leaf's
// triangles' boxes, moved in single precision from the mesh's single-precision copy, hold every
// corner as the queries move it (in double, less a reference point), for small, far, tiny and
// huge meshes at random poses; and they stay tight (a filter that passes everything is no filter).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "delta/core/rotation.h"
#include "delta/mesh/primitives.h"
#include "delta/query/query_mesh.h"

#include "query/detail/dual_traversal.h"
#include "query/detail/query_mesh_data.h"

namespace delta::detail {
namespace {

/// Checks every leaf of `mesh` at its pose against `reference`; returns the largest width of a
/// box beyond its triangle's own, relative to `scale`.
double checkLeaves(const QueryMesh& mesh, const Vec3& reference, double scale,
                   const std::string& what) {
  const QueryMeshData& data = mesh.data();
  const MatrixMotion motion = matrixMotion(mesh.pose());
  double loosest = 0.0;
  for (std::size_t leaf = 0; leaf < data.levels[0].size(); ++leaf) {
    const std::size_t count = std::min(kFanout, data.size() - leaf * kFanout);
    const FloatOctet boxes =
        movedLeafBoxes(data.lanes, leaf, count, mesh.moved() ? &motion : nullptr, reference);
    for (std::size_t lane = 0; lane < kFanout; ++lane)
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const double lower = boxes.lower[axis][lane], upper = boxes.upper[axis][lane];
        if (lane >= count) {  // padding: empty
          EXPECT_GT(lower, upper) << what << ", leaf " << leaf << ", lane " << lane;
          continue;
        }
        double low = INFINITY, high = -INFINITY;
        for (std::size_t corner = 0; corner < 3; ++corner) {
          const Vec3 v = data.vertices[data.corners[leaf * kFanout + lane][corner]];
          const double x = ((mesh.moved() ? motion.apply(v) : v) - reference)[axis];
          low = std::min(low, x);
          high = std::max(high, x);
        }
        EXPECT_LE(lower, low) << what << ", leaf " << leaf << ", lane " << lane;
        EXPECT_GE(upper, high) << what << ", leaf " << leaf << ", lane " << lane;
        loosest = std::max(loosest, ((upper - lower) - (high - low)) / scale);
      }
  }
  return loosest;
}

TEST(MovedLeafBoxes, HoldEveryCornerWhereverTheMeshIs) {
  std::mt19937_64 random(26);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  // (size, where it was prepared, how far its pose moves it)
  const double cases[][3] = {{1.0, 0.0, 0.0},   {1.0, 0.0, 3.0},     {1.0, 1e6, 0.0},
                             {1.0, 0.0, 1e6},   {1e-9, 1e3, 1e3},    {1e-30, 0.0, 1e-29},
                             {1e30, 0.0, 1e30}, {1e20, 1e25, -1e25}, {1.0, 1e15, 0.0}};
  for (const auto& [size, prepared, moved] : cases) {
    for (int round = 0; round < 4; ++round) {
      Mesh shape = primitives::granulate(static_cast<std::uint64_t>(round + 1),
                                         {size, 0.5 * size, 0.8 * size});
      shape.transform(RigidTransform::translationBy(Vec3{1, -2, 3} * prepared));
      QueryMesh mesh(shape);
      const Quaternion turn =
          Quaternion::fromComponents(unit(random), unit(random), unit(random), unit(random));
      mesh.setPose(RigidTransform{turn, Vec3{unit(random), unit(random), unit(random)} * moved});
      // Near the moved mesh, as the overlap query's reference point is.
      const Vec3 reference =
          mesh.pose().apply(mesh.data().bounds.center()) + Vec3{0.3, 0.1, -0.2} * size;
      const std::string what = "size " + std::to_string(size) + ", prepared at " +
                               std::to_string(prepared) + ", moved by " + std::to_string(moved);
      const double loosest = checkLeaves(mesh, reference, size, what);
      // Tight: far from the origin the boxes widen by the rounding of the coordinates there,
      // about 2⁻¹⁹ of them (the limit below allows that, and 10⁻⁵ of the mesh's size).
      const double far = std::max(std::abs(prepared), std::abs(moved)) / size;
      EXPECT_LT(loosest, 1e-5 + 1e-5 * far) << what;
      // Not moved: the same boxes through the identity.
      mesh.setPose(RigidTransform{});
      checkLeaves(mesh, mesh.data().bounds.center(), size, what + ", at rest");
    }
  }
}

TEST(MovedLeafBoxes, AreUnboundedBeyondSinglePrecision) {
  Mesh shape = primitives::granulate(3);
  QueryMesh mesh(shape);
  mesh.setPose(RigidTransform::translationBy({1e40, 0, 0}));
  const MatrixMotion motion = matrixMotion(mesh.pose());
  const FloatOctet boxes = movedLeafBoxes(mesh.data().lanes, 0, kFanout, &motion, Vec3{});
  for (std::size_t axis = 0; axis < 3; ++axis)
    for (std::size_t lane = 0; lane < kFanout; ++lane) {
      EXPECT_EQ(boxes.lower[axis][lane], -INFINITY);
      EXPECT_EQ(boxes.upper[axis][lane], INFINITY);
    }
  // And correct again once the reference point is near: moved by 1e40, less 1e40.
  checkLeaves(mesh, Vec3{1e40, 0, 0}, 1.0, "moved by 1e40, reference there");
}

}  // namespace
}  // namespace delta::detail
