#include "delta/query/sphere_contacts.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <span>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/kernels/point_triangle.h"
#include "delta/kernels/sphere.h"
#include "delta/mesh/primitives.h"
#include "delta/query/query_mesh.h"

namespace delta::contactdetection {
namespace {

constexpr double kUlp = std::numeric_limits<double>::epsilon();

/// Uniform doubles from std::mt19937_64's raw output (no standard-library distribution, whose
/// results differ between library implementations): the same spheres on every machine.
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double uniform(double low, double high) {
    return low + (high - low) * (static_cast<double>(engine_() >> 11) * 0x1p-53);
  }

 private:
  std::mt19937_64 engine_;
};

/// `count` spheres with centres uniform in the mesh's box grown by `margin` and radii uniform
/// in [smallest, largest].
std::vector<Sphere> randomSpheres(const Mesh& mesh, std::size_t count, double margin,
                                  double smallest, double largest, std::uint64_t seed) {
  Random random(seed);
  const Aabb box = mesh.bounds();
  std::vector<Sphere> spheres(count);
  for (Sphere& sphere : spheres) {
    for (std::size_t axis = 0; axis < 3; ++axis)
      sphere.center[axis] = random.uniform(box.lower[axis] - margin, box.upper[axis] + margin);
    sphere.radius = random.uniform(smallest, largest);
  }
  return spheres;
}

/// Every (sphere, triangle) pair by the scalar kernel, no pruning: the reference contact set.
std::vector<ContactPoint> byAllTriangles(std::span<const Sphere> spheres, const Mesh& mesh,
                                         double epsilon) {
  std::vector<ContactPoint> all;
  for (std::uint32_t i = 0; i < spheres.size(); ++i)
    for (std::uint32_t j = 0; j < mesh.triangleCount(); ++j) {
      const auto r = kernels::sphereTriangle(spheres[i], mesh.triangle(j));
      if (!(r.gap < 2 * epsilon)) continue;
      ContactPoint c;
      c.x = (r.p + r.q) * 0.5;
      c.normal = r.p - c.x;
      c.direction = r.normal;
      c.distance = std::fabs(r.gap);
      c.overlap = r.gap < 0;
      c.first = i;
      c.second = j;
      all.push_back(c);
    }
  return all;
}

std::vector<ContactPoint> byAllTriangles(const Sphere& sphere, const Mesh& mesh, double epsilon) {
  return byAllTriangles(std::span<const Sphere>(&sphere, 1), mesh, epsilon);
}

/// The same contacts, in the same order, bit for bit.
void expectSame(const std::vector<ContactPoint>& actual, const std::vector<ContactPoint>& expected,
                const std::string& label) {
  ASSERT_EQ(actual.size(), expected.size()) << label;
  for (std::size_t k = 0; k < actual.size(); ++k) {
    const ContactPoint& a = actual[k];
    const ContactPoint& e = expected[k];
    ASSERT_EQ(a.first, e.first) << label << " contact " << k;
    ASSERT_EQ(a.second, e.second) << label << " contact " << k;
    EXPECT_EQ(a.x, e.x) << label << " contact " << k;
    EXPECT_EQ(a.normal, e.normal) << label << " contact " << k;
    EXPECT_EQ(a.direction, e.direction) << label << " contact " << k;
    EXPECT_EQ(a.distance, e.distance) << label << " contact " << k;
    EXPECT_EQ(a.overlap, e.overlap) << label << " contact " << k;
  }
}

/// The documented meaning of a contact, checked against the independent point–triangle kernel:
/// P = x + normal on the sphere, Q = x − normal on the triangle, distance = |gap| = |P − Q|,
/// direction from Q toward the centre, normal = ±(distance / 2)·direction.
void expectContract(const ContactPoint& c, const Sphere& sphere, const Triangle& triangle,
                    double epsilon, double size, const std::string& label) {
  const double tolerance = 1e-12 * size + 8 * kUlp * maxAbs(sphere.center);
  const Vec3 p = c.x + c.normal;
  const Vec3 q = c.x - c.normal;
  const auto closest = kernels::closestPointOnTriangle(sphere.center, triangle);
  const double centreToTriangle = std::sqrt(closest.distanceSquared);
  const double gap = centreToTriangle - sphere.radius;
  EXPECT_NEAR(length(c.direction), 1.0, 1e-12) << label;
  EXPECT_NEAR(distance(p, sphere.center), sphere.radius, tolerance) << label;
  EXPECT_LE(std::sqrt(kernels::closestPointOnTriangle(q, triangle).distanceSquared), tolerance)
      << label;
  EXPECT_NEAR(c.distance, std::fabs(gap), tolerance) << label;
  EXPECT_NEAR(distance(p, q), c.distance, tolerance) << label;
  EXPECT_LT(gap, 2 * epsilon + tolerance) << label;
  if (std::fabs(gap) > tolerance) {
    EXPECT_EQ(c.overlap, gap < 0) << label;
  }
  const double sense = c.overlap ? -1.0 : 1.0;
  EXPECT_NEAR(dot(c.normal, c.direction), sense * c.distance / 2, tolerance) << label;
  EXPECT_NEAR(length(cross(c.normal, c.direction)), 0.0, tolerance) << label;
  if (centreToTriangle > 1e-6 * size) {
    const Vec3 toCentre = (sphere.center - closest.closest) / centreToTriangle;
    EXPECT_NEAR(distance(c.direction, toCentre), 0.0, tolerance / centreToTriangle) << label;
  }
}

struct Scene {
  std::string name;
  Mesh wall;
  std::vector<Sphere> spheres;
  double epsilon;
};

std::vector<Scene> scenes() {
  std::vector<Scene> all;
  const Mesh icosphere = primitives::icosphere(3);  // 1280 triangles: 20 blocks
  all.push_back({"icosphere", icosphere, randomSpheres(icosphere, 300, 0.4, 0.02, 0.3, 1), 0.01});
  const Mesh box = primitives::box({3, 2, 1});
  all.push_back({"box", box, randomSpheres(box, 300, 0.3, 0.01, 0.2, 2), 0.02});
  const Mesh cylinder = primitives::cylinder(1, 2, 40);
  all.push_back({"cylinder", cylinder, randomSpheres(cylinder, 300, 0.4, 0.02, 0.3, 3), 0.01});
  // Long slivers turned out of the axes (a CAD cylinder's caps and wall), whose boxes are as
  // wide as they are long: the tree's slabs keep them out.
  Mesh turned = primitives::cylinder(1, 2, 400);
  turned.rotate({1, 2, 3}, 0.7);
  all.push_back({"turned cylinder of 400 segments", turned,
                 randomSpheres(turned, 300, 0.3, 0.005, 0.2, 5), 0.01});
  // Spheres far larger than the mesh whose surfaces pass through it, many along its diagonals,
  // where their boxes meet every node's.
  Random random(6);
  std::vector<Sphere> large(300);
  for (Sphere& sphere : large) {
    const Vec3 along =
        normalized(Vec3{random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)} +
                   Vec3{1, 1, 1} * random.uniform(0, 2));
    sphere.radius = std::pow(10.0, random.uniform(1, 3));
    sphere.center = along * (sphere.radius + random.uniform(0.6, 1.3));
  }
  all.push_back({"spheres far larger than the mesh", icosphere, large, 0.01});
  Mesh granulate = primitives::granulate(11, {2, 1.5, 1}, 300);
  granulate.rotate({1, 2, 3}, 0.7).translate({1e6, -1e6, 5e5});
  all.push_back({"granulate far from the origin", granulate,
                 randomSpheres(granulate, 300, 0.3, 0.02, 0.25, 4), 0.005});
  return all;
}

TEST(SphereContacts, SameSetAsEveryTriangleByTheKernel) {
  for (const Scene& scene : scenes()) {
    const std::vector<ContactPoint> expected =
        byAllTriangles(scene.spheres, scene.wall, scene.epsilon);
    // The scene exercises every path: pruned spheres, contacts apart and overlapping.
    std::vector<bool> touched(scene.spheres.size(), false);
    bool sawOverlap = false, sawApart = false;
    for (const ContactPoint& c : expected) {
      touched[c.first] = true;
      (c.overlap ? sawOverlap : sawApart) = true;
    }
    ASSERT_TRUE(sawOverlap && sawApart) << scene.name;
    ASSERT_NE(std::count(touched.begin(), touched.end(), false), 0) << scene.name;

    const TriangleSoA mesh = flatten(scene.wall);
    const std::vector<ContactPoint> actual = sphereContacts(scene.spheres, mesh, scene.epsilon);
    expectSame(actual, expected, scene.name);
    // Through a prepared mesh's tree: the very same contacts (the DEM's path).
    expectSame(sphereContacts(scene.spheres, QueryMesh(scene.wall), scene.epsilon), expected,
               scene.name + " through the tree");
    const double size = scene.wall.bounds().diagonal();
    for (const ContactPoint& c : actual)
      expectContract(c, scene.spheres[c.first], scene.wall.triangle(c.second), scene.epsilon, size,
                     scene.name + " sphere " + std::to_string(c.first) + " triangle " +
                         std::to_string(c.second));

    // One sphere at a time: the same contacts, with sphere index 0.
    std::size_t next = 0;
    for (std::uint32_t i = 0; i < scene.spheres.size(); ++i) {
      std::vector<ContactPoint> mine;
      for (; next < expected.size() && expected[next].first == i; ++next) {
        mine.push_back(expected[next]);
        mine.back().first = 0;
      }
      expectSame(sphereContacts(scene.spheres[i], mesh, scene.epsilon), mine,
                 scene.name + " alone, sphere " + std::to_string(i));
    }
  }
}

TEST(SphereContacts, SphereAboveAFloorHasTheAnalyticGap) {
  const Mesh floor = primitives::quad(2, 2);
  const TriangleSoA mesh = flatten(floor);
  // Centre above (0, 0), on the quad's diagonal: both triangles share the closest point.
  for (const auto& [height, radius] : {std::pair{1.0, 0.75}, std::pair{0.5, 0.5 - 0x1p-10},
                                       std::pair{0.25, 0.5}, std::pair{0.5, 0.3}}) {
    const Sphere sphere{{0, 0, height}, radius};
    const std::vector<ContactPoint> found = sphereContacts(sphere, mesh, 0.125);
    const std::string label = "h = " + std::to_string(height) + ", r = " + std::to_string(radius);
    const double gap = height - radius;
    if (gap >= 0.25) {
      EXPECT_TRUE(found.empty()) << label;
      continue;
    }
    ASSERT_EQ(found.size(), 2u) << label;
    for (const ContactPoint& c : found) {
      EXPECT_NEAR(c.distance, std::fabs(gap), 1e-15) << label;
      EXPECT_EQ(c.overlap, gap < 0) << label;
      EXPECT_NEAR(distance(c.direction, {0, 0, 1}), 0.0, 1e-15) << label;
      EXPECT_NEAR(distance(c.x, {0, 0, gap / 2}), 0.0, 1e-15) << label;
      EXPECT_NEAR(distance(c.normal, {0, 0, gap / 2}), 0.0, 1e-15) << label;
    }
    expectSame(found, byAllTriangles(sphere, floor, 0.125), label);
  }
  // Off the diagonal: the nearer triangle has the gap h − r along +z; the other one, if any,
  // is further and its direction still leans up.
  const Sphere sphere{{0.5, -0.3, 0.4}, 0.35};
  const std::vector<ContactPoint> found = sphereContacts(sphere, mesh, 0.25);
  ASSERT_FALSE(found.empty());
  double nearest = std::numeric_limits<double>::infinity();
  for (const ContactPoint& c : found) {
    EXPECT_GT(c.direction.z, 0.0);
    if (c.distance < nearest) {
      nearest = c.distance;
      EXPECT_NEAR(distance(c.direction, {0, 0, 1}), 0.0, 1e-15);
    }
  }
  EXPECT_NEAR(nearest, 0.05, 1e-15);
  expectSame(found, byAllTriangles(sphere, floor, 0.25), "off the diagonal");
}

TEST(SphereContacts, TouchingAFaceExactlyIsAContactWithoutOverlap) {
  const Mesh floor = primitives::quad(2, 2);
  const Sphere sphere{{0.5, -0.25, 0.5}, 0.5};  // gap exactly 0, far from the diagonal
  const std::vector<ContactPoint> found = sphereContacts(sphere, flatten(floor), 1e-9);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].distance, 0.0);
  EXPECT_FALSE(found[0].overlap);
  EXPECT_EQ(found[0].direction, (Vec3{0, 0, 1}));
  EXPECT_EQ(found[0].x, (Vec3{0.5, -0.25, 0}));
  EXPECT_EQ(found[0].normal, (Vec3{}));
  expectSame(found, byAllTriangles(sphere, floor, 1e-9), "touching");
}

TEST(SphereContacts, OnlyGapsStrictlyBelowTwoEpsilon) {
  const Mesh floor = primitives::quad(2, 2);
  const TriangleSoA mesh = flatten(floor);
  // ε = 0.25: a gap of exactly 0.5 = 2ε is no contact, one ulp less is.
  EXPECT_TRUE(sphereContacts(Sphere{{0.5, -0.25, 1.0}, 0.5}, mesh, 0.25).empty());
  const Sphere closer{{0.5, -0.25, std::nextafter(1.0, 0.0)}, 0.5};
  const std::vector<ContactPoint> found = sphereContacts(closer, mesh, 0.25);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_LT(found[0].distance, 0.5);
  expectSame(found, byAllTriangles(closer, floor, 0.25), "one ulp closer");
}

TEST(SphereContacts, RoundingInThePruneNeverDropsAContact) {
  // A floor at z = 1e6 (ulp u = 2⁻³³ there) and r = 0.25 + u/4: the kernel's gap, computed from
  // the triangle, is (c.z − 1e6) − r = 0.25 − u/4 exactly, below 2ε = 0.25; the sphere box's
  // lower corner c.z − r rounds up to 1e6 + 0.25, a box gap of exactly 2ε. An exact-looking box
  // test would skip the floor; the prune must not.
  const double ulp = 0x1p-33;
  const Mesh floor = primitives::quad(2, 2, {0, 0, 1e6});
  const Sphere sphere{{0.5, -0.25, 1e6 + 0.5}, 0.25 + ulp / 4};
  ASSERT_EQ(sphere.center.z - sphere.radius, 1e6 + 0.25);  // the premise: it rounds up
  const std::vector<ContactPoint> expected = byAllTriangles(sphere, floor, 0.125);
  ASSERT_EQ(expected.size(), 1u);
  ASSERT_EQ(expected[0].distance, 0.25 - ulp / 4);
  expectSame(sphereContacts(sphere, flatten(floor), 0.125), expected, "rounded box");
  expectSame(sphereContacts(std::span<const Sphere>(&sphere, 1), QueryMesh(floor), 0.125), expected,
             "rounded box, through the tree");
}

TEST(SphereContacts, CentreOnTheWallSurfaceGetsTheFaceNormal) {
  // A centre in the plane of a floor triangle: the sphere is half in the wall; direction is the
  // face normal +z, the depth is the radius and P the sphere's lowest point.
  const Mesh floor = primitives::quad(2, 2);
  const Sphere inPlane{{0.3, -0.2, 0}, 0.25};
  const std::vector<ContactPoint> found = sphereContacts(inPlane, flatten(floor), 0.01);
  expectSame(found, byAllTriangles(inPlane, floor, 0.01), "in the plane");
  int faceContacts = 0;
  for (const ContactPoint& c : found) {
    EXPECT_TRUE(c.overlap);
    if (c.direction.z > 0.5) {
      ++faceContacts;
      EXPECT_EQ(c.direction, (Vec3{0, 0, 1}));
      EXPECT_EQ(c.distance, 0.25);
      EXPECT_NEAR(distance(c.x + c.normal, {0.3, -0.2, -0.25}), 0.0, 1e-16);  // P
      EXPECT_NEAR(distance(c.normal, {0, 0, -0.125}), 0.0, 1e-16);
    } else {
      EXPECT_NEAR(c.direction.z, 0.0, 1e-15) << "the other triangle is beside the centre";
    }
  }
  EXPECT_EQ(faceContacts, 1);

  // A centre on an edge, then on a vertex, of a box: every triangle through the centre
  // reports the radius as depth along its outward face normal (so P is inside the box).
  const Mesh box = primitives::box({2, 2, 2});
  const TriangleSoA mesh = flatten(box);
  for (const Vec3& centre : {Vec3{1, 1, 0.25}, Vec3{1, 1, 1}}) {
    const Sphere sphere{centre, 0.3};
    const std::vector<ContactPoint> atCentre = sphereContacts(sphere, mesh, 0.01);
    const std::string label = "centre " + std::to_string(centre.z);
    expectSame(atCentre, byAllTriangles(sphere, box, 0.01), label);
    Vec3 seen;  // which outward axes appeared
    for (const ContactPoint& c : atCentre) {
      const Triangle triangle = box.triangle(c.second);
      if (kernels::closestPointOnTriangle(centre, triangle).distanceSquared > 1e-24) continue;
      EXPECT_TRUE(c.overlap) << label;
      EXPECT_NEAR(c.distance, 0.3, 1e-15) << label;
      EXPECT_NEAR(distance(c.direction, normalized(triangle.areaVector())), 0.0, 1e-15) << label;
      const Vec3 p = c.x + c.normal;
      EXPECT_LE(maxAbs(p), 1.0 + 1e-15) << label << ": P inside the box";
      seen += max(c.direction, Vec3{});
    }
    EXPECT_EQ(seen.x > 0, true) << label;
    EXPECT_EQ(seen.y > 0, true) << label;
    EXPECT_EQ(seen.z > 0, centre.z == 1.0) << label;
  }
}

TEST(SphereContacts, RestingOnAFloorFarFromTheOrigin) {
  const Vec3 offset{1e6, -1e6, 1e6};
  const Mesh floor = primitives::quad(2, 2, offset);
  const TriangleSoA mesh = flatten(floor);
  for (const double lift : {0.5 + 1e-3, 0.5 - 1e-4}) {
    const Sphere sphere{offset + Vec3{0.1, 0.3, lift}, 0.5};
    const double gap = (sphere.center.z - offset.z) - 0.5;  // the subtraction is exact
    const std::vector<ContactPoint> found = sphereContacts(sphere, mesh, 1e-3);
    const std::string label = "lift " + std::to_string(lift);
    ASSERT_EQ(found.size(), 1u) << label;
    const ContactPoint& c = found[0];
    EXPECT_NEAR(c.distance, std::fabs(gap), 1e-12) << label;
    EXPECT_EQ(c.overlap, gap < 0) << label;
    EXPECT_NEAR(distance(c.direction, {0, 0, 1}), 0.0, 1e-12) << label;
    EXPECT_NEAR(distance(c.x, offset + Vec3{0.1, 0.3, gap / 2}), 0.0, 4 * kUlp * 1e6) << label;
    expectSame(found, byAllTriangles(sphere, floor, 1e-3), label);
  }
}

TEST(SphereContacts, TinySpheres) {
  const Mesh box = primitives::box({1, 1, 1});
  const TriangleSoA mesh = flatten(box);
  const double radius = 1e-9;
  const Sphere above{{0.1, 0.2, 0.5 + 1.5e-9}, radius};  // gap 5e-10 above the top face
  const std::vector<ContactPoint> found = sphereContacts(above, mesh, 1e-9);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].distance, 5e-10, 1e-16);
  EXPECT_FALSE(found[0].overlap);
  EXPECT_NEAR(distance(found[0].direction, {0, 0, 1}), 0.0, 1e-12);
  const Sphere straddling{{0.1, 0.2, 0.5}, radius};
  const std::vector<ContactPoint> half = sphereContacts(straddling, mesh, 1e-9);
  ASSERT_EQ(half.size(), 1u);
  EXPECT_TRUE(half[0].overlap);
  EXPECT_NEAR(half[0].distance, radius, 1e-16);
  EXPECT_TRUE(sphereContacts(Sphere{{0.1, 0.2, 0.3}, radius}, mesh, 1e-9).empty());
  const std::vector<Sphere> all{above, straddling, {{0.1, 0.2, 0.3}, radius}};
  expectSame(sphereContacts(all, mesh, 1e-9), byAllTriangles(all, box, 1e-9), "tiny");
}

TEST(SphereContacts, ZeroAreaTriangles) {
  const Mesh wall({{0, 0, 0}, {2, 0, 0}, {1, 0, 0}, {5, 5, 5}, {0, 0, 3}, {1, 0, 3}, {0, 1, 3}},
                  {{0, 1, 2}, {3, 3, 3}, {4, 5, 6}});  // a segment, a point, a proper triangle
  const TriangleSoA mesh = flatten(wall);
  const double epsilon = 0.2;
  const std::vector<Sphere> spheres{
      {{1, 0.75, 0}, 0.5},    // beside the segment: gap 0.25 along +y
      {{1, 0, 0}, 0.5},       // centre on the segment: depth 0.5, direction ⟂ the segment
      {{5, 5, 5}, 0.5},       // centre on the point: +x
      {{5, 5, 5.5}, 0.25},    // above the point: gap 0.25 along +z
      {{0.2, 0.2, 2.0}, 0.7}  // under the proper triangle only: gap 0.3 along −z
  };
  const std::vector<ContactPoint> found = sphereContacts(spheres, mesh, epsilon);
  expectSame(found, byAllTriangles(spheres, wall, epsilon), "zero-area");
  ASSERT_EQ(found.size(), 5u);
  const std::uint32_t triangleOf[] = {0, 0, 1, 1, 2};
  const double distances[] = {0.25, 0.5, 0.5, 0.25, 0.3};
  for (std::uint32_t i = 0; i < 5; ++i) {
    EXPECT_EQ(found[i].first, i);
    EXPECT_EQ(found[i].second, triangleOf[i]);
    EXPECT_NEAR(found[i].distance, distances[i], 1e-15) << "sphere " << i;
    EXPECT_NEAR(length(found[i].direction), 1.0, 1e-15) << "sphere " << i;
  }
  EXPECT_NEAR(distance(found[0].direction, {0, 1, 0}), 0.0, 1e-15);
  EXPECT_TRUE(found[1].overlap);
  EXPECT_NEAR(found[1].direction.x, 0.0, 1e-15);
  EXPECT_EQ(found[2].direction, (Vec3{1, 0, 0}));
  EXPECT_NEAR(distance(found[3].direction, {0, 0, 1}), 0.0, 1e-15);
  EXPECT_NEAR(distance(found[4].direction, {0, 0, -1}), 0.0, 1e-15);
}

TEST(SphereContacts, SphereStraddlingManyTriangles) {
  const Mesh shell = primitives::icosphere(4);  // 5120 triangles
  const TriangleSoA mesh = flatten(shell);
  // A ball centred on the surface cuts through a cap of many triangles.
  const Sphere onSurface{normalized({1, 2, 3}), 0.25};
  const std::vector<ContactPoint> cap = sphereContacts(onSurface, mesh, 0.005);
  EXPECT_GT(cap.size(), 40u);
  expectSame(cap, byAllTriangles(onSurface, shell, 0.005), "cap");
  // A ball just inside the shell touches every triangle, each pushing it inward.
  const Mesh coarse = primitives::icosphere(2);
  const Sphere inside{{}, 0.99};
  const std::vector<ContactPoint> every = sphereContacts(inside, flatten(coarse), 0.02);
  ASSERT_EQ(every.size(), coarse.triangleCount());
  for (std::uint32_t j = 0; j < every.size(); ++j) {
    EXPECT_EQ(every[j].second, j);
    EXPECT_LT(dot(every[j].direction, coarse.triangle(j).centroid()), 0.0);
  }
  expectSame(every, byAllTriangles(inside, coarse, 0.02), "inside");
}

TEST(SphereContacts, FarSpheresAndNoSpheresHaveNone) {
  const TriangleSoA mesh = flatten(primitives::icosphere(1));
  EXPECT_TRUE(sphereContacts(Sphere{{10, 0, 0}, 1}, mesh, 0.1).empty());
  EXPECT_TRUE(sphereContacts(std::span<const Sphere>(), mesh, 0.1).empty());
}

TEST(SphereContacts, BadInputThrows) {
  const TriangleSoA mesh = flatten(primitives::icosphere(1));
  const Sphere good{{0, 0, 0.9}, 0.2};
  const std::vector<Sphere> goods{good, good};
  for (double epsilon : {0.0, -1.0, double(NAN), double(INFINITY)}) {
    EXPECT_THROW(sphereContacts(good, mesh, epsilon), Error);
    EXPECT_THROW(sphereContacts(goods, mesh, epsilon), Error);
    EXPECT_THROW(sphereContacts(std::span<const Sphere>(), mesh, epsilon), Error);
  }
  EXPECT_THROW(sphereContacts(good, TriangleSoA(), 0.1), Error);
  EXPECT_THROW(sphereContacts(goods, TriangleSoA(), 0.1), Error);

  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<Sphere> bad{{{0, 0, 0}, 0.0},   {{0, 0, 0}, -1.0},  {{0, 0, 0}, nan},
                                {{0, 0, 0}, inf},   {{nan, 0, 0}, 1.0}, {{0, inf, 0}, 1.0},
                                {{0, 0, -inf}, 1.0}};
  for (const Sphere& sphere : bad) {
    EXPECT_THROW(sphereContacts(sphere, mesh, 0.1), Error);
    const std::vector<Sphere> spheres{good, good, sphere, good};
    try {
      sphereContacts(spheres, mesh, 0.1);
      ADD_FAILURE() << "no error for radius " << sphere.radius;
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find("sphere 2 "), std::string::npos) << error.what();
    }
  }
}

TEST(SphereContacts, TrianglesTooSmallForTheKernelAreRefusedInEveryForm) {
  // An audit's case: a triangle 1e-100 across (below 2⁻²⁰⁰, where the kernel's products
  // underflow) and a sphere overlapping it. The flattened form refused it; the prepared form
  // answered no contact (the kernel's gap +6.9e-102, exactly −1e-101).
  const double side = 0x1.bff2ee48e053p-333;
  const Mesh mesh({{0, 0, 0}, {side, 0, 0}, {0, side, 0}, {1, 1, 1}, {2, 1, 1}, {1, 2, 1}},
                  {{0, 1, 2}, {3, 4, 5}});
  const Sphere sphere{{0x1.bff2ee48e053p-335, 0x1.bff2ee48e053p-335, 0x1.665bf1d3e6a8dp-336},
                      0x1.665bf1d3e6a8dp-335};
  const double epsilon = 1e-300;
  EXPECT_THROW(sphereContacts(sphere, flatten(mesh), epsilon), Error);
  const QueryMesh query(mesh);  // the point queries take it (they scale such triangles up)
  EXPECT_THROW(sphereContacts(std::span<const Sphere>(&sphere, 1), query, epsilon), Error);
  SphereContactCache cache(0.1);
  std::vector<ContactPoint> out;
  EXPECT_THROW(sphereContacts(sphere, query, epsilon, cache, out), Error);
}

TEST(SphereContacts, SameResultForOneAndTwoOmpThreads) {
  const Mesh wall = primitives::icosphere(3);
  const std::vector<Sphere> spheres = randomSpheres(wall, 1000, 0.3, 0.02, 0.2, 5);
  const TriangleSoA mesh = flatten(wall);
  const int previous = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<ContactPoint> serial = sphereContacts(spheres, mesh, 0.01);
  omp_set_num_threads(2);
  const std::vector<ContactPoint> parallel = sphereContacts(spheres, mesh, 0.01);
  omp_set_num_threads(previous);
  ASSERT_GT(serial.size(), 100u);
  expectSame(parallel, serial, "two threads");
  expectSame(serial, byAllTriangles(spheres, wall, 0.01), "reference");
}

TEST(SphereContacts, OneSphereAtATimeInsideAnOuterOmpLoopMatchesTheBatch) {
  // The DEM case: the caller's own parallel loop over particles, one library call each.
  const Mesh wall = primitives::cylinder(1, 2, 32);
  const std::vector<Sphere> spheres = randomSpheres(wall, 200, 0.3, 0.02, 0.3, 6);
  const TriangleSoA mesh = flatten(wall);
  std::vector<std::vector<ContactPoint>> perSphere(spheres.size());
  const int count = static_cast<int>(spheres.size());
#pragma omp parallel for num_threads(2)
  for (int i = 0; i < count; ++i)
    perSphere[i] = sphereContacts(spheres[i], mesh, 0.01);
  const std::vector<ContactPoint> batch = sphereContacts(spheres, mesh, 0.01);
  std::vector<ContactPoint> joined;
  for (std::uint32_t i = 0; i < perSphere.size(); ++i)
    for (ContactPoint c : perSphere[i]) {
      c.first = i;
      joined.push_back(c);
    }
  ASSERT_FALSE(batch.empty());
  expectSame(joined, batch, "outer loop");
}

TEST(SphereContacts, ManyUserThreadsGetTheReferenceResult) {
  const Mesh wall = primitives::granulate(8, {1.5, 1, 1}, 100);
  const std::vector<Sphere> spheres = randomSpheres(wall, 400, 0.3, 0.02, 0.3, 7);
  const TriangleSoA mesh = flatten(wall);
  const std::vector<ContactPoint> expected = byAllTriangles(spheres, wall, 0.01);
  ASSERT_FALSE(expected.empty());
  std::vector<std::vector<ContactPoint>> answers(4);
  std::vector<std::thread> callers;
  for (auto& answer : answers)
    callers.emplace_back([&] { answer = sphereContacts(spheres, mesh, 0.01); });
  for (std::thread& caller : callers)
    caller.join();
  for (std::size_t t = 0; t < answers.size(); ++t)
    expectSame(answers[t], expected, "thread " + std::to_string(t));
}

/// A sphere walking about a point by a prepared mesh in steps of `stride` (some steps a skin
/// long or more, most shorter), in the mesh's prepared frame: through `cache`, each call gives the
/// fresh query's contacts, bit for bit.
void expectCachedWalkMatchesFresh(const QueryMesh& mesh, const Sphere& start, double epsilon,
                                  SphereContactCache& cache, double stride, int steps,
                                  std::uint64_t seed, const std::string& label) {
  Random random(seed);
  Sphere sphere = start;
  std::vector<ContactPoint> cached;
  std::size_t found = 0;
  for (int step = 0; step < steps; ++step) {
    const double length = random.uniform(0.0, 1.0) < 0.9 ? stride : 20.0 * stride;
    sphere.center +=
        Vec3{random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)} * length;
    // On a leash about where it started, so that it stays by the wall.
    if (distance(sphere.center, start.center) > 50.0 * stride)
      sphere.center = start.center + (sphere.center - start.center) * 0.5;
    sphereContacts(sphere, mesh, epsilon, cache, cached);
    const std::vector<ContactPoint> fresh =
        sphereContacts(std::span<const Sphere>(&sphere, 1), mesh, epsilon);
    expectSame(cached, fresh, label + " step " + std::to_string(step));
    found += fresh.size();
  }
  EXPECT_GT(found, static_cast<std::size_t>(steps) / 4) << label << ": the walk met the wall";
}

TEST(SphereContactCache, AWalkGivesTheFreshContactsBitForBit) {
  const double epsilon = 0.01;
  // A box (a floor of two triangles), a fine icosphere, and a granulate far from the origin.
  const QueryMesh box(primitives::box({3, 2, 1}));
  SphereContactCache boxCache(0.5 * epsilon);
  expectCachedWalkMatchesFresh(box, {{0.3, 0.2, -0.5 - 0.1 - epsilon}, 0.1}, epsilon, boxCache,
                               0.002, 2000, 1, "box");
  EXPECT_GT(boxCache.reused(), boxCache.made()) << "the cache answered most calls";
  EXPECT_GT(boxCache.made(), 10u) << "and was made again as the sphere moved";

  const QueryMesh icosphere(primitives::icosphere(4));
  SphereContactCache icosphereCache(0.5 * epsilon);
  expectCachedWalkMatchesFresh(icosphere, {{0, 0, 1.05}, 0.06}, epsilon, icosphereCache, 0.001,
                               2000, 2, "icosphere");
  EXPECT_GT(icosphereCache.reused(), icosphereCache.made());

  Mesh granulate = primitives::granulate(11, {2, 1.5, 1}, 300);
  granulate.translate({1e6, -1e6, 5e5});
  const QueryMesh far(granulate);
  SphereContactCache farCache(0.5 * epsilon);
  const Aabb bounds = granulate.bounds();
  expectCachedWalkMatchesFresh(far, {{bounds.upper.x, 1e6 * -1.0, 5e5}, 0.2}, epsilon, farCache,
                               0.002, 1000, 3, "granulate far from the origin");
}

TEST(SphereContactCache, RemadeForAnotherMeshRadiusOrEpsilon) {
  const double epsilon = 0.01;
  const QueryMesh box(primitives::box({2, 2, 2}));
  const QueryMesh bigger(primitives::box({2.02, 2.02, 2.02}));
  SphereContactCache cache(0.5 * epsilon);
  std::vector<ContactPoint> out;
  const Sphere sphere{{0, 0, 1.105}, 0.1};
  const auto expectFresh = [&](const QueryMesh& mesh, const Sphere& s, double eps,
                               const std::string& label) {
    sphereContacts(s, mesh, eps, cache, out);
    expectSame(out, sphereContacts(std::span<const Sphere>(&s, 1), mesh, eps), label);
  };
  expectFresh(box, sphere, epsilon, "first");
  EXPECT_EQ(cache.made(), 1u);
  expectFresh(box, sphere, epsilon, "again");
  EXPECT_EQ(cache.reused(), 1u);
  expectFresh(bigger, sphere, epsilon, "another mesh");  // overlaps it: kept gaps would not say
  expectFresh(box, {sphere.center, 0.11}, epsilon, "another radius");
  expectFresh(box, sphere, 0.001, "another epsilon");
  EXPECT_EQ(cache.made(), 4u);
  // No skin: every call a fresh query.
  SphereContactCache none(0.0);
  for (int i = 0; i < 3; ++i) {
    sphereContacts(sphere, box, epsilon, none, out);
    expectSame(out, sphereContacts(std::span<const Sphere>(&sphere, 1), box, epsilon), "no skin");
  }
  EXPECT_EQ(none.made(), 3u);
  EXPECT_EQ(none.reused(), 0u);
  // Bad input throws as the fresh query does.
  EXPECT_THROW(sphereContacts(sphere, box, -1.0, cache, out), Error);
  EXPECT_THROW(sphereContacts({{0, 0, NAN}, 0.1}, box, epsilon, cache, out), Error);
  EXPECT_THROW(sphereContacts({{0, 0, 0}, 0.0}, box, epsilon, cache, out), Error);
}

}  // namespace
}  // namespace delta::contactdetection
