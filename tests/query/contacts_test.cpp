#include "delta/query/contacts.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <thread>
#include <vector>

#include "delta/core/error.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/point_triangle.h"
#include "delta/kernels/triangle_triangle.h"
#include "delta/mesh/primitives.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"

#include "kernels/triangle_pairs.h"

namespace delta::contactdetection {
namespace {

/// Every pair by the scalar brute force: the reference contact set (pairs closer than 2ε).
std::vector<ContactPoint> byAllPairs(const Mesh& first, const Mesh& second, double epsilon) {
  std::vector<ContactPoint> all;
  for (std::uint32_t i = 0; i < first.triangleCount(); ++i)
    for (std::uint32_t j = 0; j < second.triangleCount(); ++j) {
      const auto r = kernels::triangleDistanceBruteForce(first.triangle(i), second.triangle(j));
      if (r.distanceSquared >= 4 * epsilon * epsilon) continue;
      ContactPoint c;
      c.x = (r.p + r.q) * 0.5;
      c.distance = std::sqrt(r.distanceSquared);
      c.overlap = r.intersect;
      c.first = i;
      c.second = j;
      all.push_back(c);
    }
  return all;
}

struct Scene {
  const char* name;
  Mesh first, second;
  double epsilon;
};

std::vector<Scene> scenes() {
  std::vector<Scene> all;
  Mesh a = primitives::granulate(3);
  Mesh b = primitives::granulate(4);
  b.rotate({0, 1, 1}, 1.1).translate({1.5, 0.2, 0.1});
  all.push_back({"granulates near each other", a, b, 0.05});
  Mesh c = primitives::icosphere(3);
  Mesh d = primitives::icosphere(3);
  d.rotate({1, 0, 0}, 0.3).translate({1.5, 0.5, 0});  // interpenetrating copies
  all.push_back({"overlapping rotated icospheres", c, d, 0.01});
  Mesh e = primitives::box({2, 2, 0.5}, {1e6, 0, 0});
  Mesh f = primitives::cylinder(0.5, 1, 24, {1e6 + 0.3, 0.2, 0.75 + 1e-3});  // resting on it
  all.push_back({"cylinder on a box far from the origin", e, f, 0.002});
  return all;
}

TEST(Contacts, SameSetAsAllPairsByBruteForce) {
  for (const Scene& scene : scenes()) {
    const std::vector<ContactPoint> expected = byAllPairs(scene.first, scene.second, scene.epsilon);
    ASSERT_FALSE(expected.empty()) << scene.name << ": a scene without contacts tests nothing";
    const double size = scene.first.bounds().diagonal();
    for (kernels::Solver solver : {kernels::Solver::Hybrid, kernels::Solver::BruteForce}) {
      const std::vector<ContactPoint> actual =
          contacts(flatten(scene.first), flatten(scene.second), scene.epsilon, solver);
      ASSERT_EQ(actual.size(), expected.size()) << scene.name << " " << kernels::name(solver);
      for (std::size_t k = 0; k < actual.size(); ++k) {
        const ContactPoint& a = actual[k];
        const ContactPoint& e = expected[k];
        ASSERT_EQ(a.first, e.first) << scene.name << " contact " << k;
        ASSERT_EQ(a.second, e.second) << scene.name << " contact " << k;
        EXPECT_NEAR(a.distance, e.distance, 1e-12 * size);
        EXPECT_EQ(a.overlap, e.overlap);
        // P = x + normal and Q = x − normal are a closest pair: on their triangles (where the
        // closest points are not unique, e.g. parallel faces, any such pair is right), to the
        // rounding of coordinates far from the origin (4 ulps of |x|)
        const double onTriangle = 1e-12 * size + 4 * 0x1p-52 * maxAbs(a.x);
        const Triangle firstTriangle = scene.first.triangle(a.first);
        const Triangle secondTriangle = scene.second.triangle(a.second);
        const auto p = kernels::closestPointOnTriangle(a.x + a.normal, firstTriangle);
        const auto q = kernels::closestPointOnTriangle(a.x - a.normal, secondTriangle);
        EXPECT_LE(std::sqrt(p.distanceSquared), onTriangle);
        EXPECT_LE(std::sqrt(q.distanceSquared), onTriangle);
        // the contract of ContactPoint
        EXPECT_NEAR(length(a.normal), a.distance / 2, 1e-12 * size);
        EXPECT_LT(length(a.normal), scene.epsilon);
        EXPECT_NEAR(length(a.direction), 1.0, 1e-12);
        if (a.distance > 1e-9 * size) {
          EXPECT_NEAR(dot(a.direction, a.normal), a.distance / 2, 1e-12 * size);
        }
      }
    }
  }
}

TEST(Contacts, IntersectingTrianglesGetADirectionFromTheirFaces) {
  // A floor (normal +z) and a box sunk into it: the overlap contacts of the box's bottom face
  // point from the floor into the box (+z); every direction is a unit vector.
  const Mesh box = primitives::box({1, 1, 1}, {0, 0, 0.4});
  const Mesh floor = primitives::quad(4, 4);
  const std::vector<ContactPoint> found = contacts(flatten(box), flatten(floor), 0.05);
  ASSERT_FALSE(found.empty());
  bool sawOverlap = false;
  for (const ContactPoint& c : found) {
    EXPECT_NEAR(length(c.direction), 1.0, 1e-12);
    if (!c.overlap) continue;
    sawOverlap = true;
    EXPECT_EQ(c.distance, 0.0);
    EXPECT_EQ(length(c.normal), 0.0);
    EXPECT_GT(c.direction.z, 0.5) << "from the floor (second) into the box (first)";
  }
  EXPECT_TRUE(sawOverlap);
}

TEST(Contacts, FarMeshesHaveNoneAndBadInputThrows) {
  const TriangleSoA a = flatten(primitives::icosphere(1));
  const TriangleSoA b = flatten(primitives::icosphere(1, 1.0, {10, 0, 0}));
  EXPECT_TRUE(contacts(a, b, 1.0).empty());
  for (double epsilon : {0.0, -1.0, double(NAN), double(INFINITY)})
    EXPECT_THROW(contacts(a, b, epsilon), Error);
  EXPECT_THROW(contacts(TriangleSoA(), b, 0.1), Error);
}

TEST(Contacts, SameOrderForAnyThreadCountAndFromManyThreads) {
  const Scene scene = scenes()[1];
  const TriangleSoA first = flatten(scene.first), second = flatten(scene.second);
  omp_set_num_threads(1);
  const std::vector<ContactPoint> serial = contacts(first, second, scene.epsilon);
  omp_set_num_threads(2);
  const auto same = [&](const std::vector<ContactPoint>& other) {
    ASSERT_EQ(other.size(), serial.size());
    for (std::size_t k = 0; k < serial.size(); ++k) {
      EXPECT_EQ(other[k].first, serial[k].first);
      EXPECT_EQ(other[k].second, serial[k].second);
      EXPECT_EQ(other[k].x, serial[k].x);
    }
  };
  same(contacts(first, second, scene.epsilon));
  std::vector<std::vector<ContactPoint>> answers(3);
  std::vector<std::thread> callers;
  for (auto& answer : answers)
    callers.emplace_back([&] { answer = contacts(first, second, scene.epsilon); });
  for (std::thread& caller : callers)
    caller.join();
  for (const auto& answer : answers)
    same(answer);
}

TEST(Contacts, PreparedMeshesGiveTheSameContactsWhateverTheTriangleOrder) {
  // elephant.off lists its triangles in no spatial order: blocks of 64 in file order span the
  // mesh. QueryMesh works in its tree order and maps the ids back.
  const Mesh elephant = io::load(std::string(DELTA_DATA_DIR) + "/meshes/elephant.off");
  // Under the sanitizers (where the hybrid kernel runs a hundred times slower) its first 1500
  // triangles in file order, as scattered.
  const std::size_t kept = test::kSlowBuild ? 1500 : elephant.triangleCount();
  const Mesh first(std::vector<Vec3>(elephant.vertices().begin(), elephant.vertices().end()),
                   std::vector<TriangleIndices>(
                       elephant.triangles().begin(),
                       elephant.triangles().begin() + static_cast<std::ptrdiff_t>(kept)));
  Mesh second = first;
  second.rotate({0, 1, 0}, 0.4, first.bounds().center()).translate({0.05, 0.02, 0});
  const double epsilon = 0.002;
  const std::vector<ContactPoint> flat = contacts(flatten(first), flatten(second), epsilon);
  const std::vector<ContactPoint> prepared = contacts(QueryMesh(first), QueryMesh(second), epsilon);
  ASSERT_GT(flat.size(), 100u);
  ASSERT_EQ(prepared.size(), flat.size());
  const double size = first.bounds().diagonal();
  for (std::size_t k = 0; k < flat.size(); ++k) {
    ASSERT_EQ(prepared[k].first, flat[k].first) << k;
    ASSERT_EQ(prepared[k].second, flat[k].second) << k;
    EXPECT_NEAR(prepared[k].distance, flat[k].distance, 1e-12 * size) << k;
    EXPECT_TRUE(prepared[k].overlap || !flat[k].overlap) << k;
  }
}

TEST(Contacts, OverlapsMarkedOncePerPointAreEachPointsOwn) {
  // A box sunk 1e-9 into the centre of a CAD cylinder's fan cap (its bottom face parallel to
  // the cap, not crossing it), and one resting 1e-12 above it: most contacts share a point (each
  // sliver takes its centre vertex against the box's faces), which is asked for once. Each
  // contact whose triangles do not cross is marked overlapping exactly where its point lies
  // inside both meshes (their signed distances).
  const QueryMesh cylinder(primitives::cylinder(1.0, 1.0, 500));
  for (const double depth : {1e-9, -1e-12}) {
    const QueryMesh box(primitives::box({1e-3, 1e-3, 1e-3}, {0, 0, 0.5 + 0.5e-3 - depth}));
    const std::vector<ContactPoint> found = contacts(cylinder, box, 1e-6);
    ASSERT_GT(found.size(), 500u) << depth;
    std::vector<Vec3> points;
    for (const ContactPoint& c : found)
      points.push_back(c.x);
    const PointQuery request{.signedDistance = true};
    const auto inCylinder = distances(cylinder, points, request);
    const auto inBox = distances(box, points, request);
    std::size_t marked = 0;
    for (std::size_t k = 0; k < found.size(); ++k) {
      const Triangle a = cylinder.triangles().triangle(found[k].first);
      const Triangle b = box.triangles().triangle(found[k].second);
      if (kernels::trianglesIntersect(a, b)) continue;  // marked for crossing
      EXPECT_EQ(found[k].overlap, inCylinder[k].inside && inBox[k].inside) << depth << " " << k;
      marked += found[k].overlap;
    }
    if (depth > 0) {
      EXPECT_GT(marked, 500u);
    }
    std::printf("[ stats    ] box %g deep: %zu contacts, %zu marked by their points\n", depth,
                found.size(), marked);
  }
}

}  // namespace
}  // namespace delta::contactdetection
