#include "delta/query/overlap.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "delta/core/error.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/primitives.h"

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
  // Its terms are then of the region's own size: two unit cubes overlapping by a slab 2⁻⁵⁰ deep
  // make a region (its fans from a far corner made its volume look like rounding: "touching").
  const QueryMesh unit(primitives::box({1, 1, 1}));
  const QueryMesh slab = placed(primitives::box({1, 1, 1}), {Quaternion{}, {1 - 0x1p-50, 0, 0}});
  const Overlap thin = overlap(unit, slab);
  ASSERT_EQ(thin.regions.size(), 1u);
  EXPECT_EQ(thin.touching, 0u);
  EXPECT_NEAR(thin.total.volume, 0x1p-50, 0x1p-50 * 1e-9);
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
