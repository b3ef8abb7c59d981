#include "delta/query/overlap.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/primitives.h"

#include "kernels/detail/exact_predicates.h"
#include "kernels/triangle_pairs.h"

namespace delta::contactdetection {
namespace {

QueryMesh placed(const Mesh& mesh, const RigidTransform& pose = {}) {
  QueryMesh prepared(mesh);
  prepared.setPose(pose);
  return prepared;
}

Vec3 randomAxis(std::mt19937_64& random) {
  std::normal_distribution<double> normal;
  return normalized(Vec3{normal(random), normal(random), normal(random)});
}

TEST(Overlap, OffsetCubesShareTheBoxOfTheirCommonPart) {
  const QueryMesh a(primitives::box({1, 1, 1}));
  const QueryMesh b(primitives::box({1, 1, 1}, {0.5, 0.25, 0.125}));
  const Overlap o = overlap(a, b);
  ASSERT_EQ(o.regions.size(), 1u);
  EXPECT_NEAR(o.total.volume, 0.5 * 0.75 * 0.875, 1e-15);
  EXPECT_NEAR(length(o.total.centroid - Vec3{0.25, 0.125, 0.0625}), 0.0, 1e-15);
  EXPECT_EQ(o.curves.size(), 1u);
  EXPECT_TRUE(o.curves[0].closed);
  // ∂A inside B pushes B along +x, +y, +z in proportion to the faces of A inside B.
  EXPECT_NEAR(o.total.areaVector.x, 0.75 * 0.875, 1e-14);
  EXPECT_NEAR(o.total.areaVector.y, 0.5 * 0.875, 1e-14);
  EXPECT_NEAR(o.total.areaVector.z, 0.5 * 0.75, 1e-14);
  EXPECT_NEAR(length(o.total.areaVector + o.total.areaVectorB), 0.0, 1e-14);
}

TEST(Overlap, ACubeTurnedByFortyFiveDegreesCutsAnOctagonalPrism) {
  // Coplanar top and bottom faces, edges crossing edges: the symbolic perturbation decides.
  const QueryMesh a(primitives::box({1, 1, 1}));
  const QueryMesh b = placed(primitives::box({1, 1, 1}),
                             {Quaternion::fromAxisAngle({0, 0, 1}, std::numbers::pi / 4), {}});
  const Overlap o = overlap(a, b);
  ASSERT_EQ(o.regions.size(), 1u);
  EXPECT_NEAR(o.total.volume, 2.0 * (std::numbers::sqrt2 - 1.0), 1e-14);
  EXPECT_NEAR(length(o.total.centroid), 0.0, 1e-14);
  for (const IntersectionCurve& curve : o.curves)
    EXPECT_TRUE(curve.closed);
}

TEST(Overlap, NestedMeshesShareTheSmallerOne) {
  const Mesh small = primitives::icosphere(2, 0.3, {0.1, 0.05, -0.02});
  const QueryMesh inner(small), outer(primitives::box({1, 1, 1}));
  const double expected = signedVolume(small);
  for (const bool innerFirst : {true, false}) {
    const Overlap o = innerFirst ? overlap(inner, outer) : overlap(outer, inner);
    ASSERT_EQ(o.regions.size(), 1u);
    EXPECT_NEAR(o.total.volume, expected, 1e-15);
    EXPECT_EQ(o.segments, 0u);
    EXPECT_TRUE(o.curves.empty());
    // Wholly inside: the inner surface is closed, its area vector zero.
    EXPECT_NEAR(length(o.total.areaVector), 0.0, 1e-15);
  }
}

TEST(Overlap, AMeshBeyondSinglePrecisionsRangeAroundAnother) {
  // Beyond 2¹⁰⁰ the leaves' single-precision boxes have no bounds (−∞, +∞), and the other
  // mesh's box none either beyond 3.4e38; the empty lanes past a leaf's last triangle (a box's
  // 12 triangles fill one and a half leaves) were taken to meet them, and triangles past the
  // mesh's end were read (found by fuzzing DEM checkpoints).
  for (const double size : {1e30, 1e39, 1e50, 1e59}) {
    const QueryMesh big(primitives::box({size, size, size}));
    const QueryMesh small = placed(primitives::box({1, 2, 3}),
                                   {Quaternion::fromAxisAngle({1, 1, 0}, 0.3), {0.5, 0, 0}});
    OverlapCache cache(0.1);
    for (const Overlap& o :
         {overlap(big, small), overlap(small, big), overlap(big, small, {}, cache)}) {
      ASSERT_EQ(o.regions.size(), 1u) << size;
      EXPECT_NEAR(o.total.volume, 6.0, 6.0 * 1e-15) << size;
      EXPECT_NEAR(length(o.total.centroid - Vec3{0.5, 0, 0}), 0.0, 1e-15) << size;
    }
  }
}

TEST(Overlap, ASmallBodyAgainstALargeOneKeepsItsAccuracy) {
  // A box of side 10⁻³ pressed 10⁻⁴ into a face of a box of side S. The large face's piece was
  // summed in fans from its triangle's corner, S/2 away: terms of S·10⁻³ into an area of 10⁻⁶.
  // At S = 10⁶ the area vector came out zero (no volume-law force), the centroid 10⁴ away and
  // the volume 12% off. What remains is the rounding of the small box's placed corners, an ulp
  // of S/2 against a depth of 10⁻⁴.
  for (const double size : {1e3, 1e5, 1e6, 1e7}) {
    const QueryMesh big(primitives::box({size, size, size}));
    const QueryMesh small =
        placed(primitives::box({1e-3, 1e-3, 1e-3}), {Quaternion{}, {size / 2 + 4e-4, 0, 0}});
    const double ulp = std::nextafter(size / 2, size) - size / 2;
    const double relative = 64.0 * ulp / 1e-4;
    for (const Overlap& o : {overlap(big, small), overlap(small, big)}) {
      ASSERT_EQ(o.regions.size(), 1u) << size;
      const OverlapRegion& region = o.regions[0];
      EXPECT_NEAR(region.volume, 1e-10, 1e-10 * relative) << size;
      EXPECT_NEAR(std::abs(region.areaVector.x), 1e-6, 1e-6 * relative) << size;
      EXPECT_NEAR(region.areaVector.y, 0.0, 1e-6 * relative) << size;
      EXPECT_NEAR(region.areaVector.z, 0.0, 1e-6 * relative) << size;
      EXPECT_NEAR(length(region.centroid - Vec3{size / 2 - 5e-5, 0, 0}), 0.0, 1e-4 * relative)
          << size;
    }
  }
  // Its terms are then of the region's own size: two unit cubes overlapping by a slab 10⁻¹¹
  // deep make a region (its fans from a far corner made its volume look like rounding:
  // "touching"). One 2⁻⁵⁰ deep (8.9e-16) is within the rounding the terms of the cubes' faces
  // may carry in general (a few ulps of a face's area times its distance from the reference
  // point): the cubes touch, as they do turned alike (below).
  const QueryMesh unit(primitives::box({1, 1, 1}));
  const QueryMesh slab = placed(primitives::box({1, 1, 1}), {Quaternion{}, {1 - 1e-11, 0, 0}});
  const Overlap thin = overlap(unit, slab);
  ASSERT_EQ(thin.regions.size(), 1u);
  EXPECT_EQ(thin.touching, 0u);
  EXPECT_NEAR(thin.total.volume, 1e-11, 1e-11 * 1e-4);
  const Overlap thinner =
      overlap(unit, placed(primitives::box({1, 1, 1}), {Quaternion{}, {1 - 0x1p-50, 0, 0}}));
  EXPECT_EQ(thinner.regions.size(), 0u);
  EXPECT_EQ(thinner.touching, 1u);
}

TEST(Overlap, CubesTurnedAlikeAndTouchingFaceToFaceShareNoVolume) {
  // The shared face's four corners are the same doubles in both and exactly coplanar; with B
  // displaced into A the faces' fans cancel but for their rounding, and a region of 9.5e-18
  // with the whole face's area vector came out where the reference point lay near the faces'
  // plane (its terms o·a were near 0, and their rounding scale with them). Sharing an edge
  // (offset (1, 1, 0)), a face's piece came out ulps wide on one mesh and of no area on the
  // other: regions of 1.7e-19 and 3.8e-19 under the two last turns. Both orders now agree with
  // the exact answer: nothing, or a touching piece.
  for (const Quaternion& turn :
       {Quaternion::fromComponents(0.26475914304120585, -0.52192719953169997, -0.56913681010804329,
                                   -0.57756201913311822),
        Quaternion::fromComponents(0.11769036405236692, -0.73562713584432693, -0.46045998585028697,
                                   0.48267825375652385),
        Quaternion::fromComponents(0.50595210297633386, 0.68503684263040965, -0.083722381338367777,
                                   -0.51742396213918962)})
    for (const Vec3& offset : {Vec3{1, 0, 0}, Vec3{0, 1, 0}, Vec3{1, 1, 0}, Vec3{0, 0, -1}})
      for (const double scale : {1e-6, 1.0, 1e3}) {
        Mesh first = primitives::box(Vec3{1, 1, 1} * scale, Vec3{0.5, 0.5, 0.5} * scale);
        Mesh second =
            primitives::box(Vec3{1, 1, 1} * scale, (Vec3{0.5, 0.5, 0.5} + offset) * scale);
        first.rotate(turn);
        second.rotate(turn);
        const QueryMesh a(first), b(second);
        for (const Overlap& o : {overlap(a, b), overlap(b, a)}) {
          EXPECT_EQ(o.regions.size(), 0u) << toString(offset) << " " << scale;
          EXPECT_EQ(o.total.volume, 0.0) << toString(offset) << " " << scale;
          EXPECT_LE(o.touching, 2u);
        }
      }
}

TEST(Overlap, DisjointAndTouchingMeshesShareNothing) {
  const QueryMesh a(primitives::box({1, 1, 1}));
  for (const Vec3& offset : {Vec3{3, 0, 0}, Vec3{1, 0, 0}, Vec3{-1, 0, 0}, Vec3{0, 1, 0},
                             Vec3{0, 0, -1}, Vec3{1, 1, 0}, Vec3{-1, -1, -1}}) {
    const QueryMesh b(primitives::box({1, 1, 1}, offset));
    for (const bool swap : {false, true}) {
      const Overlap o = swap ? overlap(b, a) : overlap(a, b);
      EXPECT_FALSE(o.any()) << offset.x << " " << offset.y << " " << offset.z;
      EXPECT_EQ(o.total.volume, 0.0);
    }
  }
}

TEST(Overlap, TouchingFacesAreCountedWhereTheDisplacementMovesBIntoA) {
  const QueryMesh a(primitives::box({1, 1, 1}));
  // B is displaced along +x first: from A's −x side into A (a piece of no volume), from its +x
  // side away (nothing).
  EXPECT_EQ(overlap(a, QueryMesh(primitives::box({1, 1, 1}, {-1, 0, 0}))).touching, 1u);
  EXPECT_EQ(overlap(a, QueryMesh(primitives::box({1, 1, 1}, {1, 0, 0}))).touching, 0u);
}

TEST(Overlap, CoplanarFacesAndTheSameMeshTwice) {
  const QueryMesh a(primitives::box({1, 1, 1}));
  const QueryMesh b(primitives::box({1, 1, 1}, {0.5, 0, 0}));
  EXPECT_NEAR(overlap(a, b).total.volume, 0.5, 1e-15);
  EXPECT_NEAR(overlap(b, a).total.volume, 0.5, 1e-15);
  const Overlap same = overlap(a, a);
  ASSERT_EQ(same.regions.size(), 1u);
  EXPECT_NEAR(same.total.volume, 1.0, 1e-15);
  const QueryMesh sphere(primitives::icosphere(3));
  EXPECT_NEAR(overlap(sphere, sphere).total.volume, signedVolume(sphere.mesh()), 1e-13);
}

/// Cells of the integer grid, each the unit cube from its corner.
using Cells = std::vector<std::array<int, 3>>;

/// A union of unit cubes: each face between a cell and an empty one is a unit square of two
/// triangles, its corners shared.
Mesh voxels(const Cells& cells) {
  const auto filled = [&](const std::array<int, 3>& cell) {
    return std::find(cells.begin(), cells.end(), cell) != cells.end();
  };
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  const auto vertex = [&](const std::array<int, 3>& corner) {
    const Vec3 point{static_cast<double>(corner[0]), static_cast<double>(corner[1]),
                     static_cast<double>(corner[2])};
    const auto found = std::find(vertices.begin(), vertices.end(), point);
    if (found != vertices.end()) return static_cast<std::uint32_t>(found - vertices.begin());
    vertices.push_back(point);
    return static_cast<std::uint32_t>(vertices.size() - 1);
  };
  for (const std::array<int, 3>& cell : cells)
    for (std::size_t axis = 0; axis < 3; ++axis)
      for (const int side : {-1, 1}) {
        std::array<int, 3> neighbour = cell;
        neighbour[axis] += side;
        if (filled(neighbour)) continue;
        const std::size_t u = (axis + 1) % 3, v = (axis + 2) % 3;
        std::array<std::array<int, 3>, 4> corners;
        corners.fill(cell);
        for (std::array<int, 3>& corner : corners)
          corner[axis] += side > 0 ? 1 : 0;
        ++corners[1][u], ++corners[2][u], ++corners[2][v], ++corners[3][v];
        if (side < 0) std::swap(corners[1], corners[3]);  // outward: along −axis
        const std::uint32_t q[4] = {vertex(corners[0]), vertex(corners[1]), vertex(corners[2]),
                                    vertex(corners[3])};
        triangles.push_back({q[0], q[1], q[2]});
        triangles.push_back({q[0], q[2], q[3]});
      }
  return Mesh(vertices, triangles);
}

/// The volume the cells of `a` share with those of `b` moved by `shift`: per pair of cells, the
/// product of their overlaps along the axes (exact for the shifts below, multiples of 1/4).
double sharedVolume(const Cells& a, const Cells& b, const Vec3& shift) {
  double volume = 0.0;
  for (const std::array<int, 3>& p : a)
    for (const std::array<int, 3>& q : b) {
      double product = 1.0;
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const double low = q[axis] + shift[axis];
        product *= std::max(0.0, std::min(p[axis] + 1.0, low + 1.0) - std::max(p[axis] + 0.0, low));
      }
      volume += product;
    }
  return volume;
}

TEST(Overlap, CongruentMeshesTurnedAlikeShareTheirCoplanarFacesExactly) {
  // Two unit cubes, the second moved by 1/2 along the first's x axis, both turned by the same
  // small or moderate rotation (found by a differential fuzzer, 17 of 818 pairs of voxel
  // unions): the faces that were coplanar are so only to the rounding of the turned corners, an
  // edge of one lies in a face of the other to an ulp, and the points where it crosses that
  // face's two triangles are anywhere along it. Ordered by those rounded points, an edge's
  // crossings did not alternate, and the query threw "a triangle's crossings along an edge do
  // not alternate (internal error)": in a DEM step with the volume law, particles alike in
  // orientation. The order is now the exact one, under the symbolic displacement.
  const Cells cube{{0, 0, 0}}, bar{{0, 0, 0}, {1, 0, 0}}, ell{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const Cells notched{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  // Each pair both ways; a throw or a volume off counts, the first few are shown.
  int failures = 0;
  const auto check = [&](const QueryMesh& a, const QueryMesh& b, double expected,
                         const std::string& what) {
    for (const bool swap : {false, true}) {
      std::string wrong;
      try {
        const double volume = (swap ? overlap(b, a) : overlap(a, b)).total.volume;
        if (!(std::abs(volume - expected) <= 1e-13))
          wrong = "volume " + toString(volume) + ", not " + toString(expected);
      } catch (const Error& e) {
        wrong = e.what();
      }
      if (!wrong.empty() && ++failures <= 5)
        ADD_FAILURE() << what << (swap ? " (swapped): " : ": ") << wrong;
    }
  };
  const Vec3 axis = normalized(Vec3{1, 2, 3});
  for (const double angle : {1e-9, 0.3}) {
    const Quaternion turn = Quaternion::fromAxisAngle(axis, angle);
    check(placed(primitives::box(), {turn, {}}),
          placed(primitives::box(), {turn, turn.rotate(Vec3{0.5, 0, 0})}), 0.5,
          "boxes turned by " + toString(angle));
  }
  // A cube under a bar of two, half over it: touching, no volume.
  const Quaternion tiny = Quaternion::fromAxisAngle(axis, 1e-12);
  check(placed(voxels(cube), {tiny, {}}),
        placed(voxels(bar), {tiny, tiny.rotate(Vec3{-0.5, 0, 1})}), 0.0, "a cube under a bar");
  // The sweep: pairs of unions of cubes, one moved against the other along its own axes and
  // diagonals by halves and quarters, both turned alike (small turns among them); two cubes
  // every turn, the larger unions (slower: their coplanar faces take the exact predicates) every
  // tenth.
  const std::vector<std::pair<const Cells*, const Cells*>> pairs{
      {&cube, &cube}, {&bar, &ell}, {&notched, &bar}, {&ell, &notched}};
  const std::vector<Vec3> shifts{{0.5, 0, 0},     {0, 0.5, 0},        {0, 0, -0.5},
                                 {0.25, 0, 0},    {0.5, 0.5, 0},      {0.25, -0.5, 0},
                                 {0.5, 0.5, 0.5}, {0.25, 0.25, 0.25}, {-0.5, 0, 1}};
  std::mt19937_64 random(34);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int trial = 0; trial < static_cast<int>(test::scaledCount(200)); ++trial) {
    const double angle = trial % 4 == 0 ? std::pow(10.0, -12.0 * uniform(random))
                                        : 2.0 * std::numbers::pi * uniform(random);
    const Quaternion turn = Quaternion::fromAxisAngle(randomAxis(random), angle);
    for (const auto& [first, second] : pairs) {
      if (first != &cube && trial % 10 != 0) continue;
      const QueryMesh a = placed(voxels(*first), {turn, {}});
      for (const Vec3& shift : shifts)
        check(a, placed(voxels(*second), {turn, turn.rotate(shift)}),
              sharedVolume(*first, *second, shift),
              "trial " + std::to_string(trial) + ", shift " + toString(shift));
    }
  }
  EXPECT_EQ(failures, 0);
}

TEST(Overlap, CoplanarFacesGetTheMeanOfBothDisplacements) {
  // Aligned cubes 2·10⁻² across, face to face 10⁻³ deep: their side faces lie in one plane,
  // facing the same way. B displaced along +x then +y alone counts A's +x and +y sides as inside
  // B, and pushed them apart sideways (a volume-law audit: a 9% sideways kick, 1.9% of the
  // energy into spin).
  const QueryMesh a(primitives::box({0.02, 0.02, 0.02}));
  const QueryMesh b(primitives::box({0.02, 0.02, 0.02}, {0, 0, 0.019}));
  OverlapOptions oneWay;
  oneWay.symmetric = false;
  const Overlap plus = overlap(a, b, oneWay);
  ASSERT_EQ(plus.regions.size(), 1u);
  EXPECT_GT(plus.coplanar, 0u);
  EXPECT_TRUE(plus.oneSided);
  EXPECT_NEAR(plus.total.areaVector.x, 2e-5, 1e-18);
  const Overlap ab = overlap(a, b), ba = overlap(b, a);
  for (const Overlap* o : {&ab, &ba}) {
    ASSERT_EQ(o->regions.size(), 1u);
    EXPECT_FALSE(o->oneSided);
    EXPECT_EQ(o->coplanar, plus.coplanar);
    EXPECT_NEAR(o->total.volume, 4e-7, 1e-20);
  }
  EXPECT_NEAR(length(ab.total.areaVector - Vec3{0, 0, 4e-4}), 0.0, 1e-19);
  EXPECT_NEAR(length(ab.regions[0].areaVector - Vec3{0, 0, 4e-4}), 0.0, 1e-19);
  EXPECT_NEAR(length(ab.total.areaVectorB + ab.total.areaVector), 0.0, 1e-19);
  // The moment about the centroid, to rounding (ε·|S|·size ≈ 2e-21); the spin came from the
  // sideways S, off the particles' centres.
  EXPECT_NEAR(length(ab.total.moment), 0.0, 1e-20);
  // Either order, the same mean (the sums are the same two terms).
  EXPECT_EQ(ab.total.areaVector, ba.total.areaVectorB);
  EXPECT_NEAR(length(ab.total.moment + ba.total.moment), 0.0, 1e-20);
  // Through a cache, bit for bit.
  OverlapCache cache(1e-3);
  for (int call = 0; call < 2; ++call) {
    const Overlap cached = overlap(a, b, {}, cache);
    EXPECT_EQ(cached.total.areaVector, ab.total.areaVector);
    EXPECT_EQ(cached.total.moment, ab.total.moment);
  }

  // Unions of unit cubes moved by halves and quarters: their answers mirrored in x and turned by
  // a quarter about z are those of the mirrored or turned scene (exactly so: every coordinate is
  // a multiple of 1/4). +t alone fails this, on most of them.
  const Cells cube{{0, 0, 0}}, bar{{0, 0, 0}, {1, 0, 0}}, ell{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const Cells notched{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
  using Map = std::array<int, 3> (*)(const std::array<int, 3>&);
  const Map mirror = [](const std::array<int, 3>& c) {
    return std::array<int, 3>{-c[0] - 1, c[1], c[2]};
  };
  const Map turn = [](const std::array<int, 3>& c) {
    return std::array<int, 3>{-c[1] - 1, c[0], c[2]};
  };
  const auto mapped = [](const Cells& cells, Map map) {
    Cells out;
    for (const std::array<int, 3>& cell : cells)
      out.push_back(map(cell));
    return out;
  };
  const std::vector<std::pair<const Cells*, const Cells*>> pairs{
      {&cube, &cube}, {&bar, &ell}, {&notched, &bar}, {&ell, &notched}, {&notched, &ell}};
  const std::vector<Vec3> shifts{{0.5, 0, 0},     {0, 0.5, 0},        {0, 0, -0.5},
                                 {0.25, 0, 0},    {0.5, 0.5, 0},      {0.25, -0.5, 0},
                                 {0.5, 0.5, 0.5}, {0.25, 0.25, 0.25}, {-0.5, 0, 1},
                                 {1, 0, 0},       {0, 1, 0.5},        {0, 0, 0}};
  std::size_t compared = 0, differed = 0;
  for (const auto& [first, second] : pairs)
    for (const Vec3& shift : shifts) {
      const std::string what = std::to_string(first->size()) + " and " +
                               std::to_string(second->size()) + " cubes, shift " + toString(shift);
      const auto answer = [&](const Cells& p, const Cells& q, const Vec3& by, bool symmetric) {
        OverlapOptions options;
        options.symmetric = symmetric;
        const Overlap o =
            overlap(QueryMesh(voxels(p)), placed(voxels(q), {Quaternion{}, by}), options);
        EXPECT_EQ(o.oneSided, !symmetric && o.coplanar > 0 && o.any()) << what;
        // The torque about the origin: moment + centroid × S.
        return std::pair{o.total.areaVector,
                         o.total.moment + cross(o.total.centroid, o.total.areaVector)};
      };
      for (const bool symmetric : {true, false}) {
        const auto [area, torque] = answer(*first, *second, shift, symmetric);
        const auto [areaM, torqueM] = answer(mapped(*first, mirror), mapped(*second, mirror),
                                             {-shift.x, shift.y, shift.z}, symmetric);
        const auto [areaT, torqueT] = answer(mapped(*first, turn), mapped(*second, turn),
                                             {-shift.y, shift.x, shift.z}, symmetric);
        // Mirrored: S a vector, the torque a pseudovector.
        const double error = std::max({length(areaM - Vec3{-area.x, area.y, area.z}),
                                       length(torqueM - Vec3{torque.x, -torque.y, -torque.z}),
                                       length(areaT - Vec3{-area.y, area.x, area.z}),
                                       length(torqueT - Vec3{-torque.y, torque.x, torque.z})});
        if (symmetric) {
          ++compared;
          EXPECT_LT(error, 1e-13) << what;
        } else {
          differed += error > 1e-6 ? 1 : 0;
        }
      }
    }
  std::printf("%zu scenes: the mean is mirrored and turned with them; +t alone is not in %zu\n",
              compared, differed);
  EXPECT_GT(differed, compared / 4);

  // Pieces meeting only at an edge, joined under one displacement and split under the other.
  // Two L-shapes sharing two cubes along an edge: one region under +t, two under −t; +t's
  // answer stood, (2, 2, 2) one way round and (0, 0, −2) the other. And an audit's P1 (1) – P2
  // (6) – P3 (1): P1 + P2 and P3 under +t, P1 and P2 + P3 under −t, the same counts and volumes
  // but other solids, were matched across (P3 with P1, 4.5 apart) and their integrals mixed.
  // Regions that do not match are now joined on each side into one, and that is averaged.
  Cells ell1{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, ell2{{1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  Cells p{{1, 2, 0}, {5, -1, 0}, {2, 2, 0}, {4, -1, 0}},
      q{{1, 2, 0}, {5, -1, 0}, {1, 1, 0}, {5, 0, 0}};
  for (const std::array<int, 3>& cell :
       Cells{{2, 0, 0}, {3, 0, 0}, {4, 0, 0}, {2, 1, 0}, {3, 1, 0}, {4, 1, 0}}) {
    p.push_back(cell);
    q.push_back(cell);
  }
  for (const auto& [x, y, volume] : {std::tuple{&ell1, &ell2, 2.0}, std::tuple{&p, &q, 8.0}}) {
    const QueryMesh first(voxels(*x)), second(voxels(*y));
    const Overlap plusOnly = overlap(first, second, oneWay),
                  minusOnly = overlap(second, first, oneWay);
    EXPECT_NE(plusOnly.total.areaVector, minusOnly.total.areaVectorB) << volume;
    const Overlap xy = overlap(first, second), yx = overlap(second, first);
    for (const Overlap* o : {&xy, &yx}) {
      EXPECT_FALSE(o->oneSided) << volume;
      ASSERT_EQ(o->regions.size(), 1u) << volume;
      EXPECT_NEAR(o->regions[0].volume, volume, 1e-14);
      for (const IntersectionCurve& curve : o->curves)
        EXPECT_EQ(curve.region, 0u);
    }
    EXPECT_EQ(xy.regions[0].areaVector, yx.regions[0].areaVectorB) << volume;
    EXPECT_EQ(xy.total.areaVector, yx.total.areaVectorB) << volume;
    EXPECT_NEAR(length(xy.regions[0].areaVector -
                       (plusOnly.total.areaVector + minusOnly.total.areaVectorB) * 0.5),
                0.0, 1e-14)
        << volume;
    EXPECT_NEAR(length(xy.regions[0].moment + yx.regions[0].moment), 0.0, 1e-13) << volume;
  }
}

TEST(OverlapCrossingOrder, FollowsTheRoundedPointsWhereTheyAreApart) {
  std::mt19937_64 random(35);
  std::uniform_real_distribution<double> coordinate(-1.0, 1.0);
  const auto point = [&] {
    return Vec3{coordinate(random), coordinate(random), coordinate(random)};
  };
  int compared = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 e0 = point(), e1 = point();
    const std::array<Vec3, 3> s{point(), point(), point()}, t{point(), point(), point()};
    const auto at = [&](const std::array<Vec3, 3>& triangle) {
      const Vec3 normal = cross(triangle[1] - triangle[0], triangle[2] - triangle[0]);
      return dot(e0 - triangle[0], normal) / dot(e0 - e1, normal);
    };
    const double lambdaS = at(s), lambdaT = at(t);
    if (!(std::abs(lambdaS - lambdaT) > 1e-6)) continue;
    ++compared;
    const int expected = lambdaS < lambdaT ? -1 : 1;
    for (const bool edgeOfA : {true, false}) {
      EXPECT_EQ(detail::crossingOrder(e0, e1, s, t, edgeOfA), expected) << trial;
      EXPECT_EQ(detail::crossingOrder(e0, e1, t, s, edgeOfA), -expected) << trial;
      EXPECT_EQ(detail::crossingOrder(e1, e0, s, t, edgeOfA), -expected) << trial;
    }
  }
  EXPECT_GT(compared, 1900);
}

TEST(OverlapCrossingOrder, CrossingsAtOnePointAreOrderedByTheDisplacement) {
  // The z axis through two planes that hold the x axis, z = y and z = −y: both at the origin.
  // Moved by t = (δ, δ², δ³), they cross it at z = δ³ − δ² and δ³ + δ²: first z = y, where the
  // triangles are B's (the edge A's), and last where the edge is B's (moved by t against them).
  // At any scale, and moved along the x axis (whose rounding keeps every point in its plane):
  // by 2⁻²⁵⁰ against coordinates of 1, the products of six differences span more than a
  // double's exponents, and the order is found in integers.
  for (const double scale : {1.0, 0x1p-200, 0x1p150})
    for (const double offset : {0.0, 0x1p-250, 0.75 * scale}) {
      const Vec3 shift{offset, 0, 0};
      const Vec3 e0 = Vec3{0, 0, -1} * scale + shift, e1 = Vec3{0, 0, 1} * scale + shift;
      const std::array<Vec3, 3> rising{Vec3{-1, 0, 0} * scale + shift,
                                       Vec3{1, 0, 0} * scale + shift,
                                       Vec3{0, 1, 1} * scale + shift};
      const std::array<Vec3, 3> falling{Vec3{1, 0, 0} * scale + shift,
                                        Vec3{-1, 0, 0} * scale + shift,
                                        Vec3{0, -1, 1} * scale + shift};
      EXPECT_EQ(detail::crossingOrder(e0, e1, rising, falling, true), -1) << scale << " " << offset;
      EXPECT_EQ(detail::crossingOrder(e0, e1, rising, falling, false), 1) << scale << " " << offset;
      EXPECT_EQ(detail::crossingOrder(e1, e0, rising, falling, true), 1) << scale << " " << offset;
      // Triangles of one plane: at one point whatever the displacement.
      const std::array<Vec3, 3> beside{Vec3{1, 0, 0} * scale + shift,
                                       Vec3{-1, 0, 0} * scale + shift,
                                       Vec3{0, -1, -1} * scale + shift};
      EXPECT_EQ(detail::crossingOrder(e0, e1, rising, beside, true), 0) << scale << " " << offset;
    }
}

TEST(Overlap, CoordinatesWhereThePredicatesUnderflowAreRefusedWithTheReason) {
  // A mesh moved by 1e-300 against its copy: the predicates' products of differences underflowed,
  // and the query said "inconsistent crossing (internal error)" or called a closed mesh open (and
  // a sign could have been wrong without a word). Such a vertex is now refused by name.
  const QueryMesh a(primitives::icosphere(1));
  for (const Vec3& shift : {Vec3{0, 0, 1e-300}, Vec3{1e-300, 0, 0}, Vec3{0, 0, 1e-200}}) {
    const QueryMesh b = placed(primitives::icosphere(1), RigidTransform::translationBy(shift));
    try {
      (void)overlap(a, b);
      ADD_FAILURE() << "answered";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("second mesh"), std::string::npos) << message;
      EXPECT_NE(message.find("below 2^-250"), std::string::npos) << message;
      EXPECT_EQ(message.find("internal"), std::string::npos) << message;
    }
  }
  // At 2^-250 and above, the copy shifted along z shares all but a sliver.
  const QueryMesh b =
      placed(primitives::icosphere(1), RigidTransform::translationBy({0, 0, 0x1p-250}));
  EXPECT_NEAR(overlap(a, b).total.volume, signedVolume(a.mesh()), 1e-14);
}

TEST(Overlap, SpheresShareTheirLens) {
  const double radius = 1.0, distance = 1.2;
  const Mesh sphere = primitives::icosphere(5, radius);
  const QueryMesh a(sphere), b = placed(sphere, {Quaternion{}, {distance, 0, 0}});
  const Overlap o = overlap(a, b);
  ASSERT_EQ(o.regions.size(), 1u);
  const double lens = std::numbers::pi * (4 * radius + distance) * (2 * radius - distance) *
                      (2 * radius - distance) / 12.0;
  // The inscribed polyhedra lose about as much of the lens as of the sphere.
  const double shortfall = 1.0 - signedVolume(sphere) / (4.0 / 3.0 * std::numbers::pi);
  EXPECT_NEAR(o.total.volume / lens, 1.0, 3.0 * shortfall);
  EXPECT_NEAR(o.total.centroid.x, distance / 2, 1e-12);
  const double disc = std::numbers::pi * (radius * radius - distance * distance / 4);
  EXPECT_NEAR(o.total.areaVector.x / disc, 1.0, 3.0 * shortfall);
  EXPECT_NEAR(std::abs(o.total.areaVector.y) + std::abs(o.total.areaVector.z), 0.0, 1e-12);
  ASSERT_EQ(o.curves.size(), 1u);
  EXPECT_NEAR(o.curves[0].length / (2 * std::numbers::pi * std::sqrt(1 - 0.36)), 1.0,
              3.0 * shortfall);
}

TEST(Overlap, AnswersDoNotDependOnTheOrderOrTheOffset) {
  std::mt19937_64 random(7);
  const Mesh granulate = primitives::granulate(3);
  const Mesh other = primitives::granulate(11, {1.0, 0.7, 0.5});
  std::uniform_real_distribution<double> angle(0.0, 6.0), shift(-0.8, 0.8);
  for (int trial = 0; trial < 40; ++trial) {
    const RigidTransform poseA{Quaternion::fromAxisAngle(randomAxis(random), angle(random)), {}};
    const RigidTransform poseB{Quaternion::fromAxisAngle(randomAxis(random), angle(random)),
                               {shift(random), shift(random), shift(random)}};
    const Overlap ab = overlap(placed(granulate, poseA), placed(other, poseB));
    const Overlap ba = overlap(placed(other, poseB), placed(granulate, poseA));
    EXPECT_NEAR(ab.total.volume, ba.total.volume, 1e-14);
    EXPECT_EQ(ab.regions.size(), ba.regions.size());
    EXPECT_NEAR(length(ab.total.areaVector + ab.total.areaVectorB), 0.0, 1e-13);
    EXPECT_NEAR(length(ab.total.areaVector - ba.total.areaVectorB), 0.0, 1e-13);
    for (const IntersectionCurve& curve : ab.curves)
      EXPECT_TRUE(curve.closed);
    // A million away, the same numbers to the rounding of the far coordinates.
    const Vec3 far{1e6, -2e6, 3e6};
    const Overlap moved = overlap(placed(granulate, {poseA.rotation, poseA.translation + far}),
                                  placed(other, {poseB.rotation, poseB.translation + far}));
    EXPECT_NEAR(moved.total.volume, ab.total.volume, 1e-9);
    EXPECT_EQ(moved.regions.size(), ab.regions.size());
  }
}

TEST(Overlap, AnInsideOutMeshBoundsTheSameSolid) {
  Mesh reversed = primitives::icosphere(2);
  std::vector<TriangleIndices> flipped(reversed.triangles().begin(), reversed.triangles().end());
  for (TriangleIndices& t : flipped)
    std::swap(t[1], t[2]);
  const Mesh inverted(std::vector<Vec3>(reversed.vertices().begin(), reversed.vertices().end()),
                      flipped);
  const QueryMesh normal(reversed), insideOut(inverted);
  const QueryMesh box = placed(primitives::box({1, 1, 1}), {Quaternion{}, {0.6, 0.2, 0.1}});
  const Overlap expected = overlap(normal, box);
  for (const bool first : {true, false}) {
    const Overlap o = first ? overlap(insideOut, box) : overlap(box, insideOut);
    EXPECT_NEAR(o.total.volume, expected.total.volume, 1e-14);
    EXPECT_EQ(o.regions.size(), expected.regions.size());
  }
  EXPECT_NEAR(length(overlap(insideOut, box).total.areaVector - expected.total.areaVector), 0.0,
              1e-14);
}

TEST(Overlap, ManyThreadsOnFreshMeshesGetTheSameAnswers) {
  // Fresh meshes: the threads race to make the lazily built parts (the edges' neighbours, the
  // connected pieces, the self-intersection check), and each keeps its own buffers.
  const Mesh granulate = primitives::granulate(5), sphere = primitives::icosphere(3, 0.8);
  const QueryMesh a(granulate);
  const QueryMesh b = placed(sphere, {Quaternion::fromAxisAngle({1, 2, 3}, 0.7), {0.9, 0.2, 0}});
  std::vector<double> volumes(8, 0.0);
  std::vector<std::size_t> segments(8, 0);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < volumes.size(); ++t)
    threads.emplace_back([&, t] {
      for (int repeat = 0; repeat < 20; ++repeat) {
        const Overlap o = t % 2 == 0 ? overlap(a, b) : overlap(b, a);
        volumes[t] = o.total.volume;
        segments[t] = o.segments;
      }
    });
  for (std::thread& thread : threads)
    thread.join();
  const Overlap serial[2] = {overlap(a, b), overlap(b, a)};
  ASSERT_GT(serial[0].total.volume, 0.0);
  for (std::size_t t = 0; t < volumes.size(); ++t) {  // the same bits as one thread alone
    EXPECT_EQ(volumes[t], serial[t % 2].total.volume) << t;
    EXPECT_EQ(segments[t], serial[t % 2].segments) << t;
  }
}

TEST(Overlap, RefusesMeshesThatBoundNoVolume) {
  const QueryMesh open(primitives::quad());
  const QueryMesh box(primitives::box());
  EXPECT_THROW(overlap(open, box), Error);
  EXPECT_THROW(overlap(box, open), Error);
}

}  // namespace
}  // namespace delta::contactdetection
