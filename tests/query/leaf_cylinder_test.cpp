// The leaves' cylinders (query_mesh_data.h's CylinderOctet, node_bounds.h's PlainBounds,
// Avx512Bounds and Avx2Bounds): a cylinder bound never exceeds the exact kernel's squared distance
// to any triangle of its leaf, on real meshes and on adversarial ones (a tilted flat grid far from
// the origin, a tiny sphere, slivers, zero-area and repeated-vertex triangles), for points on the
// triangles, just off them, straight above their interiors, far away; and it rejects most of the
// leaves the boxes admit above a tilted patch (what it is for).
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "delta/core/format.h"
#include "delta/core/rotation.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/primitives.h"
#include "delta/query/query_mesh.h"

#include "kernels/triangle_pairs.h"
#include "query/detail/node_bounds.h"
#include "query/detail/point_kernels.h"
#include "query/detail/query_mesh_data.h"

namespace delta::detail {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// An n × n grid of squares on the unit square, turned about (1, 2, 3) and moved to `offset`:
/// flat, but its leaves' boxes are as thick as they are wide.
Mesh tiltedGrid(int n, const Vec3& offset) {
  const RigidTransform pose =
      RigidTransform::translationBy(offset) *
      RigidTransform::rotationAbout(Quaternion::fromAxisAngle({1, 2, 3}, 0.7), {0, 0, 0});
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      vertices.push_back(pose.apply(Vec3{double(i) / n, double(j) / n, 0.0}));
  const auto at = [n](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  return Mesh(std::move(vertices), std::move(triangles));
}

/// A disc of radius 1 about `centre` in the plane z = centre.z, triangulated as a fan of `n`
/// slivers from its centre (as CAD exports a cylinder's cap): every leaf's triangles reach from
/// the centre to the rim.
Mesh fan(int n, const Vec3& centre) {
  std::vector<Vec3> vertices{centre};
  std::vector<TriangleIndices> triangles;
  for (int i = 0; i < n; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / n;
    vertices.push_back(centre + Vec3{std::cos(angle), std::sin(angle), 0.0});
    triangles.push_back(
        {0u, static_cast<std::uint32_t>(1 + i), static_cast<std::uint32_t>(1 + (i + 1) % n)});
  }
  return Mesh(std::move(vertices), std::move(triangles));
}

/// Random triangles in the unit cube, a third of them slivers (a vertex on the opposite edge), a
/// sixth with a repeated vertex, a sixth collinear.
Mesh degenerateSoup(std::size_t count, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  for (std::size_t t = 0; t < count; ++t) {
    const Vec3 a{unit(random), unit(random), unit(random)};
    const Vec3 b = a + Vec3{unit(random), unit(random), unit(random)} * 0.1;
    Vec3 c = a + Vec3{unit(random), unit(random), unit(random)} * 0.1;
    switch (t % 6) {
      case 0:
      case 1:
        c = a + (b - a) * unit(random) + Vec3{1e-9, -1e-9, 0};
        break;  // a sliver
      case 2:
        c = b;
        break;  // repeated
      case 3:
        c = a + (b - a) * 2.5;
        break;  // collinear
      default:
        break;
    }
    const auto first = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), {a, b, c});
    triangles.push_back({first, first + 1, first + 2});
  }
  return Mesh(std::move(vertices), std::move(triangles));
}

/// The exact kernel's least squared distance from `point` to the triangles of leaf `leaf`.
double leafDistanceSquared(const QueryMeshData& data, std::size_t leaf, const Vec3& point) {
  double nearest = kInfinity;
  for (std::size_t k = leaf * kFanout; k < std::min((leaf + 1) * kFanout, data.size()); ++k)
    nearest =
        std::min(nearest, kernels::closestPointOnTriangle(point, data.triangle(k)).distanceSquared);
  return nearest;
}

/// Probe points around leaf `leaf`: its vertices, points just off them and straight above its
/// triangles' interiors along their normals (where the cylinder is tightest), and points at
/// every scale from 10⁻⁹ to 10³ of the leaf's size.
std::vector<Vec3> probesOf(const QueryMeshData& data, std::size_t leaf, std::mt19937_64& random) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Vec3> points;
  const Aabb& box = data.levels[0][leaf];
  const double size = std::max(box.diagonal(), 1e-300);
  for (std::size_t k = leaf * kFanout; k < std::min((leaf + 1) * kFanout, data.size()); ++k) {
    const Triangle t = data.triangle(k);
    points.push_back(t.a);
    const Vec3 centroid = (t.a + t.b + t.c) * (1.0 / 3.0);
    const Vec3 area = t.areaVector();
    const double norm = length(area);
    for (double height : {0.0, 1e-12, 1e-6, 1e-2, 1.0, 30.0}) {
      const Vec3 up = norm > 0.0 ? area * (height * size / norm) : Vec3{0, 0, height * size};
      points.push_back(centroid + up);
      points.push_back(centroid - up);
    }
  }
  for (double scale : {1e-9, 1e-6, 1e-3, 0.1, 0.5, 1.0, 3.0, 100.0, 1e3})
    for (int i = 0; i < 4; ++i)
      points.push_back(box.center() +
                       Vec3{unit(random), unit(random), unit(random)} * (scale * size));
  return points;
}

/// Checks every leaf bound of up to `nodes` random level-1 nodes of `mesh` against the exact
/// kernel; `raised` counts the bounds the cylinders raised above the boxes'.
void expectBelowTheLeaves(const Mesh& mesh, const std::string& name, std::size_t nodes,
                          std::size_t& raised) {
  const QueryMesh query(mesh);
  const QueryMeshData& data = query.data();
  EXPECT_GE(data.levels.size(), 2u) << name;
  if (data.levels.size() < 2) return;
  const bool avx512 = kernels::isSupported(kernels::Isa::Avx512);
  const bool avx2 = kernels::isSupported(kernels::Isa::Avx2);
  const std::vector<kernels::Isa> isas = kernels::supportedIsas();
  std::mt19937_64 random(7);
  raised = 0;
  const std::size_t count = data.leafCylinders.size();
  for (std::size_t round = 0; round < std::min(nodes, count); ++round) {
    const std::size_t node = nodes >= count ? round : random() % count;
    const BoxOctet& boxes = data.childOctets[0][node];
    const CylinderOctet& cylinders = data.leafCylinders[node];
    for (std::size_t slot = 0; slot < kFanout; ++slot) {
      const std::size_t leaf = node * kFanout + slot;
      if (leaf >= data.levels[0].size()) break;
      for (const Vec3& p : probesOf(data, leaf, random)) {
        const double exact = leafDistanceSquared(data, leaf, p);
        const double shrink = cylinderShrink(data, p);
        const Vec3 local = p - data.lanes.origin;  // the octets' frame
        double boxOnly[kFanout], plain[kFanout];
        distancesSquared(boxes, local, boxOnly);
        PlainBounds::leaves(boxes, cylinders, local, shrink, kInfinity, plain);
        ASSERT_LE(plain[slot], exact) << name << ", leaf " << leaf << ", p = " << toString(p);
        if (plain[slot] > boxOnly[slot]) ++raised;
        // Every ISA's leaf bounds (its point table's) are bounds too.
        for (const kernels::Isa isa : isas) {
          double bounds[kFanout];
          pointKernels(isa).leaves(boxes, cylinders, local, shrink, kInfinity, bounds);
          ASSERT_LE(bounds[slot], exact) << name << " (" << kernels::name(isa) << "), leaf " << leaf
                                         << ", p = " << toString(p);
          // The same arithmetic but for contracted sums (AVX2, AVX-512): apart by a few
          // roundings of the coordinates, far within the shrink.
          const double reach = std::sqrt(std::max(plain[slot], exact));
          ASSERT_NEAR(bounds[slot], plain[slot], 1e-12 * (plain[slot] + exact) + shrink * reach)
              << name << " (" << kernels::name(isa) << "), leaf " << leaf;
          double boxes8[kFanout];  // and its boxes' distances, as the children's bounds
          pointKernels(isa).children(boxes, local, kInfinity, boxes8);
          ASSERT_LE(boxes8[slot], exact)
              << name << " (" << kernels::name(isa) << "), leaf " << leaf;
          ASSERT_NEAR(boxes8[slot], boxOnly[slot], 1e-12 * (boxOnly[slot] + exact))
              << name << " (" << kernels::name(isa) << "), leaf " << leaf;
        }
        if (avx2 && avx512) {  // AVX2's are AVX-512's operations in halves: the same bits
          double halves[kFanout], wide[kFanout];
          pointKernels(kernels::Isa::Avx2)
              .leaves(boxes, cylinders, local, shrink, kInfinity, halves);
          pointKernels(kernels::Isa::Avx512)
              .leaves(boxes, cylinders, local, shrink, kInfinity, wide);
          ASSERT_EQ(halves[slot], wide[slot]) << name << ", leaf " << leaf;
        }
      }
    }
  }
}

TEST(LeafCylinder, BoundNeverExceedsTheLeafsTriangles) {
  const std::filesystem::path meshes = std::filesystem::path(DELTA_DATA_DIR) / "meshes";
  const std::size_t nodes = test::kSlowBuild ? 40 : 200;
  std::size_t raised = 0;
  expectBelowTheLeaves(io::load(meshes / "fandisk.off"), "fandisk", nodes, raised);
  EXPECT_GT(raised, 100u);
  expectBelowTheLeaves(io::load(meshes / "armadillo.off"), "armadillo", nodes, raised);
  EXPECT_GT(raised, 100u);
  expectBelowTheLeaves(tiltedGrid(40, {1e6, -3e6, 2e5}), "tilted grid at 1e6", nodes, raised);
  EXPECT_GT(raised, 100u);
  expectBelowTheLeaves(tiltedGrid(24, {0, 0, 0}), "tilted grid", nodes, raised);
  EXPECT_GT(raised, 100u);
  expectBelowTheLeaves(primitives::icosphere(3, 1e-7, {3, 1, 2}), "tiny icosphere", nodes, raised);
  expectBelowTheLeaves(primitives::icosphere(3, 1.0, {1e9, -2e9, 3e8}), "icosphere at 1e9", nodes,
                       raised);
  EXPECT_GT(raised, 100u);  // the boxes as fine as at the origin: the cylinders still tighten
  expectBelowTheLeaves(primitives::box({1, 2, 3}), "box", nodes, raised);
  expectBelowTheLeaves(degenerateSoup(2000, 3), "slivers and zero-area triangles", nodes, raised);
  expectBelowTheLeaves(fan(4096, {0, 0, 0}), "fan of slivers", nodes, raised);
  EXPECT_GT(raised, 100u);
  expectBelowTheLeaves(fan(4096, {3e6, -1e6, 2e6}), "fan of slivers at 1e6", nodes, raised);
  EXPECT_GT(raised, 100u);
}

/// How many leaves of `query` the boxes admit, and how many the boxes and cylinders admit, for a
/// search from each of `points` whose pruning bound is its exact distance (summed over them).
struct Admitted {
  std::size_t byBoxes = 0, byCylinders = 0;
};

Admitted admittedLeaves(const QueryMesh& query, const std::vector<Vec3>& points) {
  const QueryMeshData& data = query.data();
  Admitted admitted;
  for (const Vec3& p : points) {
    const Vec3 local = p - data.lanes.origin;  // the octets' frame
    double nearest = kInfinity;
    for (std::size_t k = 0; k < data.size(); ++k)
      nearest =
          std::min(nearest, kernels::closestPointOnTriangle(p, data.triangle(k)).distanceSquared);
    for (std::size_t node = 0; node < data.leafCylinders.size(); ++node) {
      double boxes[kFanout], bounds[kFanout];
      admitted.byBoxes += static_cast<std::size_t>(
          std::popcount(PlainBounds::children(data.childOctets[0][node], local, nearest, boxes)));
      admitted.byCylinders += static_cast<std::size_t>(
          std::popcount(PlainBounds::leaves(data.childOctets[0][node], data.leafCylinders[node],
                                            local, cylinderShrink(data, p), nearest, bounds)));
    }
  }
  return admitted;
}

TEST(LeafCylinder, RejectsMostLeavesTheBoxesAdmitAboveATiltedPatch) {
  // Far above a flat tilted patch, the boxes of the leaves around the nearest point come closer
  // than the nearest triangle; the cylinders of a flat patch are flat.
  const QueryMesh query(tiltedGrid(64, {0, 0, 0}));
  const QueryMeshData& data = query.data();
  const Vec3 normal = normalized(data.triangle(0).areaVector());
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> unit(0.1, 0.9);
  std::vector<Vec3> points;
  for (int round = 0; round < 50; ++round) {
    const Triangle t = data.triangle(random() % data.size());
    points.push_back(t.a + normal * (unit(random) * 0.5));
  }
  const Admitted admitted = admittedLeaves(query, points);
  EXPECT_GE(admitted.byCylinders, 50u);  // at least the leaf of the nearest triangle
  EXPECT_LT(3 * admitted.byCylinders, admitted.byBoxes)
      << admitted.byCylinders << " of " << admitted.byBoxes;
}

TEST(LeafCylinder, RejectsMostLeavesTheBoxesAdmitAboveAFanOfSlivers) {
  // Above a fan, a leaf's box and a disc about its plane's normal come as close as the fan's
  // plane wherever the point's foot lies in the box (a fifth of the leaves); a rod along the
  // leaf's slivers does not.
  const QueryMesh query(fan(16384, {0, 0, 0}));
  std::mt19937_64 random(12);
  std::uniform_real_distribution<double> unit(-0.5, 0.5);
  std::vector<Vec3> points;
  for (int round = 0; round < 20; ++round)
    points.push_back({unit(random), unit(random), 0.3});
  const Admitted admitted = admittedLeaves(query, points);
  EXPECT_GE(admitted.byCylinders, 20u);  // at least the leaf of the nearest triangle
  EXPECT_LT(4 * admitted.byCylinders, admitted.byBoxes)
      << admitted.byCylinders << " of " << admitted.byBoxes;
}

TEST(LeafCylinder, NearAFansCentreTheConesAdmitFewLeaves) {
  // Near a fan's centre every wedge of slivers reaches within the point's distance of it along
  // its long direction, and a rod (a cylinder along the wedge, as wide as its rim) admitted a
  // sixth of the leaves; a cone, as thin as the wedge at every height, admits the few around the
  // point's foot.
  const QueryMesh query(fan(16384, {0, 0, 0}));
  std::mt19937_64 random(13);
  std::uniform_real_distribution<double> exponent(-4.0, -1.0), angle(0.0, 2 * std::numbers::pi);
  std::vector<Vec3> points;
  for (int round = 0; round < 20; ++round) {
    const double r = std::pow(10.0, exponent(random)), a = angle(random);
    points.push_back({r * std::cos(a), r * std::sin(a), 1e-9});
  }
  const Admitted admitted = admittedLeaves(query, points);
  EXPECT_GE(admitted.byCylinders, 20u);  // at least the leaf of the nearest triangle
  EXPECT_LE(admitted.byCylinders, 3u * 20u) << admitted.byCylinders << " of " << admitted.byBoxes;
  std::printf(
      "[ stats    ] 20 points 1e-4 to 1e-1 from a fan's centre: the boxes admit %zu leaves, "
      "the cones %zu\n",
      admitted.byBoxes, admitted.byCylinders);
}

}  // namespace
}  // namespace delta::detail
