// The distance-bound grid's sieve of a batch (query/detail/grid_sieve.h), in every ISA's lanes:
// the points it keeps are those BoundGrid::lowerBoundSquared does not put beyond the limit, one
// at a time, whatever the ISA, for points anywhere (on cell walls, on the box's faces, far
// outside, NaN, infinite), and it flags every point out of the coordinate range.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "delta/kernels/isa.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/mesh/primitives.h"
#include "delta/query/query_mesh.h"

#include "query/detail/query_mesh_data.h"
#include "query/probe_points.h"

namespace delta::detail {
namespace {

using test::unit;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// The scalar reference: the offsets of the points whose bound is not above `limit`.
std::vector<std::uint32_t> keptOneAtATime(const BoundGrid& grid, const std::vector<Vec3>& points,
                                          double limit) {
  std::vector<std::uint32_t> kept;
  for (std::size_t i = 0; i < points.size(); ++i)
    if (!(grid.lowerBoundSquared(points[i]) > limit)) kept.push_back(static_cast<std::uint32_t>(i));
  return kept;
}

/// Points around `mesh`'s grid: uniform in its box grown by a fifth, on the walls between cells
/// and on the box's faces (where the truncation to a cell and the clamp decide), and far away.
std::vector<Vec3> pointsAround(const QueryMesh& mesh, std::size_t count, std::uint64_t seed) {
  const BoundGrid& grid = mesh.data().boundGrid;
  const GridView view = grid.view();
  const Aabb box = mesh.data().bounds;
  const Vec3 lower = box.lower - box.extent() * 0.2, size = box.extent() * 1.4;
  std::mt19937_64 random(seed);
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < count; ++i) {
    Vec3 p = lower + Vec3{size.x * unit(random), size.y * unit(random), size.z * unit(random)};
    switch (i % 4) {
      case 1: {  // on a wall between cells along a random axis
        const std::size_t axis = random() % 3;
        const double cells = std::floor((p[axis] - view.lower[axis]) * view.inverseCellSize);
        p[axis] = view.lower[axis] + cells * grid.cellSize();
        break;
      }
      case 2: {  // on a face of the grid's box, or a hair beyond it
        const std::size_t axis = random() % 3;
        p[axis] = random() % 2 ? view.upper[axis] : view.lower[axis];
        if (random() % 2) p[axis] = std::nextafter(p[axis], p[axis] > 0 ? kInfinity : -kInfinity);
        break;
      }
      default:
        break;
    }
    points.push_back(p);
  }
  points.push_back(box.lower);
  points.push_back(box.upper);
  points.push_back({-0.0, 0.0, -0.0});
  points.push_back(box.center() + Vec3{1e12, -1e12, 3e11});
  points.push_back({kLargestCoordinate, -kLargestCoordinate, kLargestCoordinate});
  return points;
}

void expectEveryIsaLikeOneAtATime(const QueryMesh& mesh, const std::vector<Vec3>& points,
                                  double limit, bool expectInRange) {
  const BoundGrid& grid = mesh.data().boundGrid;
  const std::vector<std::uint32_t> expected = keptOneAtATime(grid, points, limit);
  for (const kernels::Isa isa : kernels::supportedIsas()) {
    // Every length up to a few lanes past the ends of the vector loops, and the whole.
    for (const std::size_t count :
         {std::size_t{0}, std::size_t{1}, std::size_t{3}, std::size_t{7}, std::size_t{8},
          std::size_t{9}, std::size_t{17}, points.size()}) {
      if (count > points.size()) continue;
      std::vector<std::uint32_t> kept(count + 1, 0xdeadbeef);
      bool inRange = true;
      const std::size_t held =
          sieveByGrid(grid.view(), points.data(), count, limit, kept.data(), inRange, isa);
      std::vector<std::uint32_t> want;
      for (const std::uint32_t i : expected)
        if (i < count) want.push_back(i);
      ASSERT_EQ(held, want.size()) << kernels::name(isa) << ", " << count << " points";
      kept.resize(held);
      EXPECT_EQ(kept, want) << kernels::name(isa) << ", " << count << " points";
      bool allInRange = true;
      for (std::size_t i = 0; i < count; ++i)
        allInRange = allInRange && inCoordinateRange(points[i]);
      EXPECT_EQ(inRange, allInRange) << kernels::name(isa) << ", " << count << " points";
      if (count == points.size()) {
        EXPECT_EQ(inRange, expectInRange);
      }
    }
  }
}

TEST(GridSieve, EveryIsaKeepsThePointsTheScalarBoundKeeps) {
  Mesh granulate = primitives::granulate(4, {1.0, 0.5, 0.3}, 300);
  granulate.translate({1e5, -2e5, 3e4});  // far from the origin: the box's offset rounds
  // Two spheres far apart: the cells between them lie beyond 11.3 cells (codes of 128 and more,
  // where the table's steps are no longer one cell²).
  const Mesh sphere = primitives::icosphere(2);
  std::vector<Vec3> vertices(sphere.vertices().begin(), sphere.vertices().end());
  std::vector<TriangleIndices> triangles(sphere.triangles().begin(), sphere.triangles().end());
  for (const Vec3& v : sphere.vertices())
    vertices.push_back(v + Vec3{40.0, 3.0, 0.0});
  const auto offset = static_cast<std::uint32_t>(sphere.vertexCount());
  for (const TriangleIndices& t : sphere.triangles())
    triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const Mesh apart(std::move(vertices), std::move(triangles));
  const Mesh sphere3 = primitives::icosphere(3), quad = primitives::quad(2.0, 1.0);
  for (const Mesh* meshPointer : {&sphere3, static_cast<const Mesh*>(&granulate), &quad, &apart}) {
    const Mesh& mesh = *meshPointer;
    const QueryMesh query(mesh);
    ASSERT_FALSE(query.data().boundGrid.empty());
    if (meshPointer == &apart) {  // it has the far cells it is here for
      const BoundGrid& grid = query.data().boundGrid;
      const std::uint8_t* cells = grid.view().cells;
      ASSERT_GE(*std::max_element(cells, cells + grid.cellCount()), 128);
    }
    const std::vector<Vec3> points = pointsAround(query, 2003, 11);
    const double diagonal = mesh.bounds().diagonal();
    const double cell = query.data().boundGrid.cellSize();
    // Limits on either side of the table's turn from one cell² a code to wider steps (128).
    const double turn = kSquaredCellsOfCode[128] * query.data().boundGrid.view().cellSquaredShrunk;
    for (const double limit : {0.0, 1e-30, cell * cell, 4 * cell * cell, 0.01 * diagonal * diagonal,
                               kSquaredCellsOfCode[127] * cell * cell, std::nextafter(turn, 0.0),
                               turn, diagonal * diagonal, kInfinity})
      expectEveryIsaLikeOneAtATime(query, points, limit, true);
  }
}

TEST(GridSieve, EveryIsaFlagsPointsOutOfRangeAndStaysInTheGrid) {
  const QueryMesh query(primitives::icosphere(2));
  const std::vector<Vec3> good = pointsAround(query, 61, 5);
  // One bad point at each place a lane can be: the first and last lanes of a step and the tail.
  for (const Vec3 bad : {Vec3{kNaN, 0.0, 0.0}, Vec3{0.0, kNaN, kNaN}, Vec3{0.0, 0.0, kInfinity},
                         Vec3{-kInfinity, 1.0, 1.0}, Vec3{0.0, 0x1p201, 0.0}})
    for (const std::size_t at : {0u, 7u, 8u, 15u, 31u, 64u}) {
      std::vector<Vec3> points = good;
      points.insert(points.begin() + static_cast<std::ptrdiff_t>(at), bad);
      expectEveryIsaLikeOneAtATime(query, points, 0.01, false);
      expectEveryIsaLikeOneAtATime(query, points, kInfinity, false);
    }
}

}  // namespace
}  // namespace delta::detail
