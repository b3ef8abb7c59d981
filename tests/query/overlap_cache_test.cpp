// overlap(a, b, options, cache) against overlap(a, b, options): the same overlap, bit for bit
// (volumes, centroids, area vectors, moments, curves, counts), at every pose of a pair moved
// along a path, whether the cache answered or was made anew. The paths move the second mesh
// against the first by small steps (the cache answers most calls) and by jumps (it must be made
// anew), both meshes moved or only one, on interpenetrating pairs: granulates, icospheres, a box
// face on a box face (coplanar faces, touching), a cylinder sunk into a box a million units from
// the origin, a tiny pair.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/rotation.h"
#include "delta/mesh/primitives.h"
#include "delta/query/overlap.h"
#include "delta/query/query_mesh.h"

#include "pair_paths.h"

namespace delta::contactdetection {
namespace {

template <class T>
bool sameBits(const T& x, const T& y) {
  return std::memcmp(&x, &y, sizeof(T)) == 0;
}

bool sameRegion(const OverlapRegion& x, const OverlapRegion& y) {
  return sameBits(x.volume, y.volume) && sameBits(x.centroid, y.centroid) &&
         sameBits(x.areaVector, y.areaVector) && sameBits(x.areaVectorB, y.areaVectorB) &&
         sameBits(x.moment, y.moment) && sameBits(x.curveLength, y.curveLength) &&
         x.triangles == y.triangles;
}

bool sameOverlap(const Overlap& x, const Overlap& y) {
  if (!sameRegion(x.total, y.total) || x.regions.size() != y.regions.size() ||
      x.curves.size() != y.curves.size() || x.segments != y.segments || x.touching != y.touching)
    return false;
  for (std::size_t r = 0; r < x.regions.size(); ++r)
    if (!sameRegion(x.regions[r], y.regions[r])) return false;
  for (std::size_t c = 0; c < x.curves.size(); ++c) {
    const IntersectionCurve &p = x.curves[c], &q = y.curves[c];
    if (p.points.size() != q.points.size() ||
        std::memcmp(p.points.data(), q.points.data(), p.points.size() * sizeof(Vec3)) != 0 ||
        p.trianglesA != q.trianglesA || p.trianglesB != q.trianglesB || p.region != q.region ||
        p.closed != q.closed || !sameBits(p.length, q.length))
      return false;
  }
  return true;
}

/// `scene`'s path of 150 steps, each pose's overlap through `cache` against a fresh one.
void walk(const test::PairScene& scene, bool moveFirst, OverlapCache& cache,
          std::size_t& overlapping) {
  test::walkPath(scene, moveFirst, 150, [&](int s, const QueryMesh& a, const QueryMesh& b) {
    const OverlapOptions options{s % 2 == 0};  // curves on every other step
    const Overlap fresh = overlap(a, b, options);
    const Overlap cached = overlap(a, b, options, cache);
    ASSERT_TRUE(sameOverlap(cached, fresh))
        << "step " << s << ": volume " << cached.total.volume << " against " << fresh.total.volume
        << ", " << cached.segments << " segments against " << fresh.segments;
    overlapping += fresh.any() ? 1 : 0;
  });
}

TEST(OverlapCache, SameOverlapAsAFreshQueryAlongAPath) {
  for (const test::PairScene& scene : test::pairScenes(true)) {
    SCOPED_TRACE(scene.name);
    for (const bool moveFirst : {false, true}) {
      OverlapCache cache(0.5 * scene.epsilon);
      std::size_t overlapping = 0;
      walk(scene, moveFirst, cache, overlapping);
      // Both ways of answering were taken, on a path that overlapped most of the time.
      EXPECT_GT(cache.reused(), 75u);
      EXPECT_GT(cache.made(), 4u);
      EXPECT_GT(overlapping, 75u);
    }
  }
}

// A move beyond the skin makes it anew: made with a tenth of the skin, the pair moved by half of
// it, by a random shift each trial; the moves change the overlap, and the cache's answer is a
// fresh query's.
TEST(OverlapCache, AMoveBeyondItsSkinMakesItAnew) {
  const test::PairScene scene = test::pairScenes(true).front();
  const QueryMesh first(scene.first), second(scene.second);
  std::size_t differing = 0;
  std::mt19937_64 random(11);
  for (int trial = 0; trial < 40; ++trial) {
    OverlapCache cache(0.05 * scene.epsilon);
    QueryMesh b = second;
    const Overlap made = overlap(first, b, {}, cache);
    ASSERT_EQ(cache.made(), 1u);
    const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53 - 0.5; };
    const Vec3 shift = normalized(Vec3{uniform(), uniform(), uniform()}) * (0.25 * scene.epsilon);
    b.setPose(RigidTransform::translationBy(shift));
    const Overlap moved = overlap(first, b, {}, cache);
    EXPECT_EQ(cache.made(), 2u);
    EXPECT_TRUE(sameOverlap(moved, overlap(first, b, {})));
    differing += sameBits(made.total.volume, moved.total.volume) ? 0 : 1;
  }
  EXPECT_EQ(differing, 40u);  // every move changed the overlap
}

// Pairs that share nothing for a while: two granulates near but apart (their boxes meet), which
// the cache answers alone while they drift, and a small mesh wholly inside a large one (no
// triangles cross, yet they share the small one's volume), which it must not: the same overlap as
// a fresh query at every step, from both.
TEST(OverlapCache, PairsApartOrWhollyInsideAlongAPath) {
  Mesh near = primitives::granulate(4);
  near.translate({1.5, 1.5, 0.1});
  Mesh inner = primitives::icosphere(2, 0.2);
  inner.translate({0.1, -0.05, 0.0});
  const test::PairScene scenes[] = {
      {"apart", primitives::granulate(3), near, 0.04, 0.002},
      {"wholly inside", primitives::icosphere(3), inner, 0.04, 0.002}};
  for (const test::PairScene& scene : scenes) {
    SCOPED_TRACE(scene.name);
    OverlapCache cache(0.5 * scene.epsilon);
    std::size_t overlapping = 0;
    walk(scene, false, cache, overlapping);
    EXPECT_GT(cache.reused(), 75u);
    if (std::string(scene.name) == "apart")
      EXPECT_EQ(overlapping, 0u);
    else
      EXPECT_EQ(overlapping, 150u);
  }
}

TEST(OverlapCache, OtherMeshesMakeItAnew) {
  const QueryMesh a(primitives::granulate(3));
  QueryMesh b(primitives::granulate(4));
  b.setPose(RigidTransform::translationBy({1.6, 0.1, 0.0}));
  QueryMesh c(primitives::icosphere(2));
  c.setPose(RigidTransform::translationBy({1.7, 0.0, 0.0}));
  OverlapCache cache(0.02);
  EXPECT_TRUE(sameOverlap(overlap(a, b, {}, cache), overlap(a, b)));
  EXPECT_TRUE(sameOverlap(overlap(a, b, {}, cache), overlap(a, b)));
  EXPECT_EQ(cache.made(), 1u);
  EXPECT_EQ(cache.reused(), 1u);
  EXPECT_GT(cache.size(), 0u);
  EXPECT_TRUE(sameOverlap(overlap(a, c, {}, cache), overlap(a, c)));  // another mesh
  EXPECT_TRUE(sameOverlap(overlap(c, b, {}, cache), overlap(c, b)));  // swapped roles
  EXPECT_TRUE(sameOverlap(overlap(b, c, {}, cache), overlap(b, c)));
  EXPECT_EQ(cache.made(), 4u);
  cache.clear();
  EXPECT_TRUE(sameOverlap(overlap(b, c, {}, cache), overlap(b, c)));
  EXPECT_EQ(cache.made(), 5u);
  // Apart: answered without the cache, which is left as it was.
  QueryMesh far = c;
  far.setPose(RigidTransform::translationBy({100.0, 0.0, 0.0}));
  EXPECT_FALSE(overlap(b, far, {}, cache).any());
  EXPECT_EQ(cache.made() + cache.reused(), 6u);
}

TEST(OverlapCache, NoSkinAskedIsAFreshQueryEachCall) {
  const QueryMesh a(primitives::granulate(3));
  QueryMesh b(primitives::granulate(4));
  b.setPose(RigidTransform::translationBy({1.6, 0.1, 0.0}));
  for (const double skin : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    OverlapCache cache(skin);
    for (int call = 0; call < 3; ++call)
      EXPECT_TRUE(sameOverlap(overlap(a, b, {}, cache), overlap(a, b)));
    EXPECT_EQ(cache.reused(), 0u) << skin;
    EXPECT_EQ(cache.size(), 0u) << skin;
  }
}

TEST(OverlapCache, BadInputThrowsAsTheQueryDoes) {
  const QueryMesh a(primitives::quad()), b(primitives::granulate(4));
  OverlapCache cache(0.01);
  EXPECT_THROW(overlap(a, b, {}, cache), Error);
  EXPECT_THROW(overlap(b, a, {}, cache), Error);
  EXPECT_EQ(cache.made(), 0u);
}

}  // namespace
}  // namespace delta::contactdetection
