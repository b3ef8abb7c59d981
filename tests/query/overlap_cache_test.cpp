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

struct Scene {
  const char* name;
  Mesh first, second;
  double skin;
  double step;  ///< the path's step
};

std::vector<Scene> scenes() {
  std::vector<Scene> all;
  Mesh a = primitives::granulate(3);
  Mesh b = primitives::granulate(4);
  b.translate({1.6, 0.1, 0.0});
  all.push_back({"granulates", a, b, 0.025, 0.004});
  Mesh c = primitives::icosphere(3);
  Mesh d = primitives::icosphere(3);
  d.rotate({1, 0, 0}, 0.3).translate({1.8, 0.3, 0});
  all.push_back({"icospheres", c, d, 0.005, 0.002});
  all.push_back({"box face on box face", primitives::box({1, 1, 1}),
                 primitives::box({1, 1, 1}, {0.2, 0.1, 1.0}), 0.005, 0.001});
  all.push_back({"cylinder in a box far from the origin", primitives::box({2, 2, 0.5}, {1e6, 0, 0}),
                 primitives::cylinder(0.5, 1, 24, {1e6 + 0.3, 0.2, 0.74}), 0.001, 2e-4});
  Mesh e = primitives::granulate(5, {1e-6, 1e-6, 1e-6});
  Mesh f = primitives::granulate(6, {1e-6, 1e-6, 1e-6});
  f.translate({1.6e-6, 0.0, 0.0});
  all.push_back({"tiny granulates", e, f, 2.5e-8, 4e-9});
  return all;
}

/// The move at step `s` of a path: a drift and a turn of about the scene's step, with a jump
/// every 37 steps (40 steps at once) that no skin covers.
RigidTransform poseAt(int s, double step, std::mt19937_64& random) {
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53 - 0.5; };
  const double jump = s % 37 == 36 ? 40.0 : 1.0;
  const Vec3 axis{0.3 + uniform(), 0.5, 1.0};
  return RigidTransform{Quaternion::fromAxisAngle(axis, 0.5 * step),
                        Vec3{uniform(), uniform(), uniform()} * (jump * step)};
}

/// `scene`'s path of 150 steps, each pose's overlap through `cache` against a fresh one.
void walk(const Scene& scene, bool moveFirst, OverlapCache& cache, std::size_t& overlapping) {
  const QueryMesh first(scene.first), second(scene.second);
  std::mt19937_64 random(7);
  RigidTransform secondPose, firstPose;
  for (int s = 0; s < 150; ++s) {
    const RigidTransform step = poseAt(s, scene.step, random);
    // Turned about the second mesh's centre, so that it rolls in the first.
    const Vec3 centre = secondPose.apply(scene.second.bounds().center());
    secondPose = RigidTransform::translationBy(step.translation) *
                 RigidTransform::rotationAbout(step.rotation, centre) * secondPose;
    if (moveFirst) firstPose = RigidTransform::translationBy(step.translation * 0.5) * firstPose;
    QueryMesh a = first, b = second;
    a.setPose(firstPose);
    b.setPose(secondPose);
    const OverlapOptions options{s % 2 == 0};  // curves on every other step
    const Overlap fresh = overlap(a, b, options);
    const Overlap cached = overlap(a, b, options, cache);
    ASSERT_TRUE(sameOverlap(cached, fresh))
        << "step " << s << ": volume " << cached.total.volume << " against " << fresh.total.volume
        << ", " << cached.segments << " segments against " << fresh.segments;
    overlapping += fresh.any() ? 1 : 0;
  }
}

TEST(OverlapCache, SameOverlapAsAFreshQueryAlongAPath) {
  for (const Scene& scene : scenes()) {
    SCOPED_TRACE(scene.name);
    for (const bool moveFirst : {false, true}) {
      OverlapCache cache(scene.skin);
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
  const Scene scene = scenes().front();
  const QueryMesh first(scene.first), second(scene.second);
  std::size_t differing = 0;
  std::mt19937_64 random(11);
  for (int trial = 0; trial < 40; ++trial) {
    OverlapCache cache(0.1 * scene.skin);
    QueryMesh b = second;
    const Overlap made = overlap(first, b, {}, cache);
    ASSERT_EQ(cache.made(), 1u);
    const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53 - 0.5; };
    const Vec3 shift = normalized(Vec3{uniform(), uniform(), uniform()}) * (0.5 * scene.skin);
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
  const Scene scenes[] = {{"apart", primitives::granulate(3), near, 0.02, 0.002},
                          {"wholly inside", primitives::icosphere(3), inner, 0.02, 0.002}};
  for (const Scene& scene : scenes) {
    SCOPED_TRACE(scene.name);
    OverlapCache cache(scene.skin);
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
