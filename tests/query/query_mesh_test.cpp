#include "delta/query/query_mesh.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include "delta/core/error.h"
#include "delta/io/mesh_io.h"
#include "delta/mesh/primitives.h"
#include "delta/mesh/triangle_soa.h"
#include "delta/query/contacts.h"
#include "delta/query/minimum_distance.h"
#include "delta/query/point_distance.h"

#include "query/detail/query_mesh_data.h"
#include "query/probe_points.h"

namespace delta::contactdetection {
namespace {

std::vector<Vec3> pointsAround(const Aabb& box, std::size_t count, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  return test::uniformAround(box, count, 0.2, random);
}

const RigidTransform kFirstMotion{Quaternion::fromAxisAngle({1, 2, 3}, 0.9), {1e3, -20, 7}};
const RigidTransform kSecondMotion{Quaternion::fromAxisAngle({0, -1, 1}, 2.5), {3, 1e-3, -2}};

TEST(QueryMesh, MovingItIsMovingTheMesh) {
  const Mesh mesh = io::load(std::string(DELTA_DATA_DIR) + "/meshes/elephant.off");
  const QueryMesh prepared(mesh);
  QueryMesh moved = prepared;
  moved.transform(kFirstMotion).transform(kSecondMotion);  // two moves compose
  EXPECT_TRUE(moved.moved());
  EXPECT_FALSE(prepared.moved());  // a copy has its own pose
  Mesh movedMesh = mesh;
  movedMesh.transform(kFirstMotion).transform(kSecondMotion);
  const QueryMesh rebuilt(movedMesh);
  const std::vector<Vec3> points = pointsAround(rebuilt.bounds(), 3000, 3);
  const std::vector<PointDistance> a = distances(moved, points, {.signedDistance = true});
  const std::vector<PointDistance> b = distances(rebuilt, points, {.signedDistance = true});
  const double size = movedMesh.bounds().diagonal();
  std::size_t inside = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_NEAR(a[i].distance, b[i].distance, 1e-12 * size) << i;
    // The closest point itself may differ where two triangles tie (rounding picks either).
    ASSERT_NEAR(distance(points[i], a[i].closest), a[i].distance, 1e-12 * size) << i;
    ASSERT_TRUE(b[i].distance <= 1e-9 * size || a[i].inside == b[i].inside) << i;
    inside += b[i].inside;
  }
  EXPECT_GT(inside, 0u);
  // Moving back restores the prepared frame (to rounding).
  QueryMesh back = moved;
  back.transform(moved.pose().inverse());
  const PointDistance home = distance(back, points[0]), original = distance(prepared, points[0]);
  EXPECT_NEAR(home.distance, original.distance, 1e-12 * size);
  EXPECT_EQ(home.triangle, original.triangle);
  // setPose puts it anywhere at once: where the two moves took it, and back home exactly.
  QueryMesh placed = prepared;
  placed.setPose(moved.pose());
  EXPECT_EQ(distance(placed, points[1]).distance, distance(moved, points[1]).distance);
  placed.setPose({});
  EXPECT_EQ(distance(placed, points[1]).distance, distance(prepared, points[1]).distance);
}

TEST(QueryMesh, MovedMeshesGiveTheContactsOfTheMovedMeshes) {
  const Mesh shape = primitives::granulate(11, {1, 0.7, 0.5}, 120);
  QueryMesh a(shape), b(shape);  // one shape, two particles
  const RigidTransform placeA{Quaternion::fromAxisAngle({1, 1, 0}, 0.3), {10, 20, 30}};
  const RigidTransform placeB{Quaternion::fromAxisAngle({0, 1, 1}, 1.7), {11.2, 20.1, 30.05}};
  a.transform(placeA);
  b.transform(placeB);
  const QueryMesh a2(Mesh(shape).transform(placeA)), b2(Mesh(shape).transform(placeB));
  const double epsilon = 0.02;
  const std::vector<ContactPoint> moved = contacts(a, b, epsilon);
  const std::vector<ContactPoint> rebuilt = contacts(a2, b2, epsilon);
  ASSERT_GT(rebuilt.size(), 3u);
  // A pair within rounding of 2ε could fall either way; none does here (the counts would differ).
  ASSERT_EQ(moved.size(), rebuilt.size());
  for (std::size_t k = 0; k < moved.size(); ++k) {
    EXPECT_EQ(moved[k].first, rebuilt[k].first);
    EXPECT_EQ(moved[k].second, rebuilt[k].second);
    EXPECT_NEAR(distance(moved[k].x, rebuilt[k].x), 0.0, 1e-12 * 40);
    EXPECT_NEAR(moved[k].distance, rebuilt[k].distance, 1e-12 * 40);
    EXPECT_NEAR(distance(moved[k].direction, rebuilt[k].direction), 0.0, 1e-9);
    EXPECT_EQ(moved[k].overlap, rebuilt[k].overlap);
  }
  const MinimumDistance m1 = minimumDistance(a, b), m2 = minimumDistance(a2, b2);
  EXPECT_NEAR(m1.distance, m2.distance, 1e-12 * 40);
  EXPECT_NEAR(distance(m1.p, m2.p), 0.0, 1e-11 * 40);
  b.transform(RigidTransform::translationBy({3, 0, 0}));  // apart now
  EXPECT_TRUE(contacts(a, b, epsilon).empty());
  EXPECT_GT(minimumDistance(a, b).distance, 1.0);
}

TEST(QueryMesh, MovedMeshesGiveTheMinimumDistanceOfTheMovedMeshes) {
  // Both trees moved (the second's boxes and octets carried into the first's frame), at gaps
  // from touching to a third of the size: the pruned descent of the prepared trees against the
  // flattened moved meshes' blocks.
  const Mesh mesh = io::load(std::string(DELTA_DATA_DIR) + "/meshes/elephant.off");
  const double size = mesh.bounds().diagonal();
  const QueryMesh prepared(mesh);
  std::mt19937_64 random(17);
  for (double gap : {1e-3, 2e-2, 0.3}) {
    const RigidTransform placeA{
        Quaternion::fromAxisAngle({test::unit(random), 1, 0.5}, 3.0 * test::unit(random)),
        {40, -3, 8}};
    const RigidTransform turn{
        Quaternion::fromAxisAngle({1, test::unit(random), -1}, 2.0 * test::unit(random)), {}};
    // The second copy moved along x until its gap to the first is about `gap` (bisection).
    const auto placed = [&](double shift) {
      return RigidTransform::translationBy({shift, 0.1 * size, 0}) * placeA * turn;
    };
    const TriangleSoA first = flatten(Mesh(mesh).transform(placeA));
    QueryMesh a = prepared, b = prepared;
    a.setPose(placeA);
    double low = 0.0, high = 2.0 * size;
    for (int step = 0; step < 24; ++step) {  // to 2^-23 of the size: "about" the gap
      const double middle = 0.5 * (low + high);
      b.setPose(placed(middle));
      (minimumDistance(a, b).distance < gap * size ? low : high) = middle;
    }
    b.setPose(placed(high));
    const MinimumDistance moved = minimumDistance(a, b);
    const MinimumDistance flat =
        minimumDistance(first, flatten(Mesh(mesh).transform(placed(high))));
    EXPECT_GT(flat.distance, 0.5 * gap * size) << gap;
    EXPECT_NEAR(moved.distance, flat.distance, 1e-12 * size) << gap;
    EXPECT_NEAR(distance(moved.p, flat.p), 0.0, 1e-6 * size) << gap;
  }
}

TEST(QueryMesh, ASmallParticleOnALargeMeshHasTheFlattenedContacts) {
  // A few leaf pairs against a tree of thousands of leaves (the contacts then sort their pairs
  // instead of tabling the large tree's leaves), the particle first and second.
  const Mesh large = io::load(std::string(DELTA_DATA_DIR) + "/meshes/armadillo.off");
  const Vec3 on = large.triangle(1000).centroid();
  Mesh small = primitives::icosphere(2);
  small.scale(0.01 * large.bounds().diagonal()).translate(on);
  const QueryMesh preparedLarge(large), preparedSmall(small);
  const TriangleSoA flatLarge = flatten(large), flatSmall = flatten(small);
  const double epsilon = 1e-3 * large.bounds().diagonal();
  for (bool smallFirst : {true, false}) {
    const std::vector<ContactPoint> prepared =
        smallFirst ? contacts(preparedSmall, preparedLarge, epsilon)
                   : contacts(preparedLarge, preparedSmall, epsilon);
    const std::vector<ContactPoint> flat = smallFirst ? contacts(flatSmall, flatLarge, epsilon)
                                                      : contacts(flatLarge, flatSmall, epsilon);
    ASSERT_GT(flat.size(), 10u);
    ASSERT_EQ(prepared.size(), flat.size()) << smallFirst;
    for (std::size_t k = 0; k < flat.size(); ++k) {
      EXPECT_EQ(prepared[k].first, flat[k].first) << smallFirst;
      EXPECT_EQ(prepared[k].second, flat[k].second) << smallFirst;
      EXPECT_NEAR(prepared[k].distance, flat[k].distance, 1e-12 * large.bounds().diagonal());
    }
  }
}

TEST(QueryMesh, RejectsNonFiniteMotionsAndEmptyMeshes) {
  QueryMesh box(primitives::box());
  EXPECT_THROW(box.transform(RigidTransform::translationBy({0, NAN, 0})), Error);
  EXPECT_THROW(box.transform({Quaternion{0, 0, 0, 0}, {}}), Error);
  EXPECT_THROW(box.setPose(RigidTransform::translationBy({INFINITY, 0, 0})), Error);
  EXPECT_THROW(box.setPose({Quaternion{0, 0, 0, 0}, {}}), Error);
  EXPECT_FALSE(box.moved());
  EXPECT_THROW(QueryMesh(Mesh({}, {})), Error);
}

TEST(QueryMesh, PosesThatOverflowAreRefusedAndLeaveThePose) {
  // An audit's cases: two translations of 1.5e308 composed to (∞, 0, 0), whose inverse is NaN,
  // and a turn of a pose at 1.7e308 overflowed, with no error.
  QueryMesh box(primitives::box());
  box.transform(RigidTransform::translationBy({1.5e308, 0, 0}));
  const RigidTransform before = box.pose();
  EXPECT_THROW(box.transform(RigidTransform::translationBy({1.5e308, 0, 0})), Error);
  EXPECT_EQ(box.pose().translation, before.translation);
  EXPECT_EQ(box.inversePose().translation, before.inverse().translation);
  box.setPose(RigidTransform::translationBy({1.7e308, 1.7e308, 0}));
  const RigidTransform far = box.pose();
  EXPECT_THROW(box.transform({Quaternion::fromAxisAngle({0, 0, 1}, 0.7853981633974483), {}}),
               Error);
  EXPECT_EQ(box.pose().translation, far.translation);
  EXPECT_EQ(box.pose().rotation.w, far.rotation.w);
  // Beyond the coordinate range but finite: kept, and the queries refuse the mesh there.
  box.setPose(RigidTransform::translationBy({0, 0, -1e100}));
  EXPECT_EQ(box.pose().translation.z, -1e100);
}

TEST(QueryMesh, SetPoseToAnothersPosePutsItExactlyThere) {
  // Normalising a unit quaternion again changed its last bits in some 2.5% of cases, so a mesh
  // put at another's pose (a pickled QueryMesh, an adaptive grid's boundary) answered up to
  // 1.1e-10 differently at 1e6 (an audit).
  std::mt19937_64 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const QueryMesh box(primitives::box());
  int changedByNormalising = 0;
  for (int i = 0; i < 400; ++i) {
    QueryMesh moved = box;
    moved.transform(
        {Quaternion::fromComponents(unit(random), unit(random), unit(random), unit(random)),
         {1e6, unit(random), unit(random)}});
    const Quaternion& q = moved.pose().rotation;
    const Quaternion again = Quaternion::fromComponents(q.w, q.x, q.y, q.z);
    changedByNormalising += again.w != q.w || again.x != q.x || again.y != q.y || again.z != q.z;
    QueryMesh placed = box;
    placed.setPose(moved.pose());
    ASSERT_EQ(placed.pose().rotation.w, q.w);
    ASSERT_EQ(placed.pose().rotation.x, q.x);
    ASSERT_EQ(placed.pose().rotation.y, q.y);
    ASSERT_EQ(placed.pose().rotation.z, q.z);
    ASSERT_EQ(placed.pose().translation, moved.pose().translation);
  }
  EXPECT_GT(changedByNormalising, 0);  // the case the test is for occurred
  // A rotation that is not a unit quaternion is still normalised.
  QueryMesh placed = box;
  placed.setPose({Quaternion{2, 0, 0, 0}, {}});
  EXPECT_EQ(placed.pose().rotation.w, 1.0);
}

TEST(QueryMesh, ManyThreadsQueryCopiesWithTheirOwnPoses) {
  const QueryMesh shape(primitives::icosphere(3));
  const std::vector<Vec3> points = pointsAround(shape.bounds(), 2000, 9);
  std::vector<std::vector<PointDistance>> answers(4);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < answers.size(); ++t)
    threads.emplace_back([&, t] {
      QueryMesh particle = shape;  // shares the prepared data
      particle.transform(RigidTransform::translationBy({double(t), 0, 0}));
      std::vector<Vec3> shifted = points;
      for (Vec3& p : shifted)
        p.x += double(t);
      answers[t] = distances(particle, shifted, {.signedDistance = true});
    });
  for (std::thread& thread : threads)
    thread.join();
  for (std::size_t t = 1; t < answers.size(); ++t)
    for (std::size_t i = 0; i < points.size(); ++i) {
      // Shifted points round differently, so a tie may go to another triangle: distances only.
      ASSERT_NEAR(answers[t][i].distance, answers[0][i].distance, 1e-14) << t << " " << i;
      ASSERT_EQ(answers[t][i].inside, answers[0][i].inside) << t << " " << i;
    }
}

TEST(QueryMesh, MemoryPerTriangle) {
  // What the parts take a triangle: the vertices (24 bytes each, about half a vertex a triangle)
  // and three corner indices (12), the single-precision copy for the leaf bounds (36), the tree
  // order (4), the tree's boxes, octets and slabs (about 16) and the bound grid (about 2): about
  // 82. A copy of the triangles in double (72) breaks the upper bound. The pseudonormals (24:
  // 12 for the vertices, 12 for each triangle's neighbours) appear with the first signed query,
  // the mesh-order triangles (72) once triangles() is called.
  const Mesh closed = primitives::icosphere(5);  // 20,480 triangles
  const auto perTriangle = [](const QueryMesh& query) {
    return static_cast<double>(query.memoryBytes()) / static_cast<double>(query.size());
  };
  const QueryMesh query(closed);
  const double prepared = perTriangle(query);
  EXPECT_GT(prepared, 12.0 + 12.0 + 36.0 + 4.0);
  EXPECT_LT(prepared, 90.0);
  const PointDistance outside = distance(query, {2, 0, 0}, {.signedDistance = true});
  EXPECT_FALSE(outside.inside);
  EXPECT_NEAR(perTriangle(query), prepared + 24.0, 0.5);
  ASSERT_EQ(query.triangles().size(), closed.triangleCount());
  EXPECT_NEAR(perTriangle(query), prepared + 24.0 + 72.0, 1.0);
}

TEST(QueryMesh, MeshOrderTrianglesMadeOnceForManyThreads) {
  // triangles() is made on the first call, whichever thread makes it; every thread and copy gets
  // the same object, in the mesh's order.
  const Mesh mesh = primitives::granulate(4, {1, 2, 0.5}, 300);
  const QueryMesh query(mesh);
  std::vector<const TriangleSoA*> seen(8, nullptr);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < seen.size(); ++t)
    threads.emplace_back([&, t] {
      const QueryMesh copy = query;
      seen[t] = &copy.triangles();
    });
  for (std::thread& thread : threads)
    thread.join();
  for (const TriangleSoA* soa : seen)
    EXPECT_EQ(soa, &query.triangles());
  for (std::size_t i = 0; i < mesh.triangleCount(); ++i) {
    const Triangle expected = mesh.triangle(i), found = query.triangles().triangle(i);
    ASSERT_EQ(found.a, expected.a) << i;
    ASSERT_EQ(found.b, expected.b) << i;
    ASSERT_EQ(found.c, expected.c) << i;
  }
}

TEST(QueryMesh, PseudonormalsMadeOnceForManyThreads) {
  // The first signed queries of eight threads at once, on copies of one prepared mesh, make its
  // pseudonormals once (ThreadSanitizer checks the race) and every thread signs as a mesh that
  // made them alone does.
  const Mesh mesh = primitives::granulate(4, {1, 2, 0.5}, 300);
  const QueryMesh query(mesh), alone(mesh);
  std::vector<Vec3> points(64);
  std::mt19937_64 random(3);
  std::uniform_real_distribution<double> unit(-1.5, 1.5);
  for (Vec3& p : points)
    p = {unit(random), 2.0 * unit(random), 0.5 * unit(random)};
  std::vector<std::vector<PointDistance>> answers(8);
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < answers.size(); ++t)
    threads.emplace_back([&, t] {
      const QueryMesh copy = query;
      for (const Vec3& p : points)
        answers[t].push_back(distance(copy, p, {.signedDistance = true}));
    });
  for (std::thread& thread : threads)
    thread.join();
  int inside = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const PointDistance expected = distance(alone, points[i], {.signedDistance = true});
    inside += expected.inside;
    for (const std::vector<PointDistance>& some : answers) {
      ASSERT_EQ(some[i].distance, expected.distance) << i;
      ASSERT_EQ(some[i].inside, expected.inside) << i;
    }
  }
  EXPECT_GT(inside, 5);
  EXPECT_LT(inside, 60);
}

TEST(QueryMesh, TreeBuiltOnManyThreadsIsTheTreeOfOne) {
  // The subtrees below the top splits are ordered on all threads at once (ThreadSanitizer checks
  // that they share nothing): the same tree order as on one thread, a permutation of the ids.
  const Mesh mesh = primitives::icosphere(5, 1.0, {1e3, -2e3, 5e2});  // 20,480 triangles
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const QueryMesh serial(mesh);
  omp_set_num_threads(4);
  const QueryMesh parallel(mesh);
  omp_set_num_threads(threads);
  const std::vector<std::uint32_t>& order = parallel.data().order;
  ASSERT_EQ(order, serial.data().order);
  std::vector<std::uint32_t> ids = order;
  std::sort(ids.begin(), ids.end());
  for (std::size_t i = 0; i < ids.size(); ++i)
    ASSERT_EQ(ids[i], i);
  // Compact leaves: each leaf's box is a small part of the sphere's (a tree order that lost its
  // sort would put far triangles together).
  double widest = 0.0;
  for (const Aabb& leaf : parallel.data().levels[0])
    widest = std::max(widest, leaf.diagonal());
  EXPECT_LT(widest, 0.35);  // 0.23 measured; a leaf of far triangles spans about 2
}

TEST(QueryMesh, PseudonormalsMadeOnManyThreadsAreThoseOfOne) {
  // The corners' weights, the vertex sums (each in the mesh's triangle order) and the edge
  // buckets run on all threads: the same bits as on one (ThreadSanitizer checks the sharing).
  const Mesh mesh = io::load(std::string(DELTA_DATA_DIR) + "/meshes/elephant.off");
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const QueryMesh serial(mesh);
  const detail::Pseudonormals& one = serial.data().pseudonormals();
  omp_set_num_threads(4);
  const QueryMesh parallel(mesh);
  const detail::Pseudonormals& many = parallel.data().pseudonormals();
  omp_set_num_threads(threads);
  ASSERT_EQ(many.vertices.size(), one.vertices.size());
  for (std::size_t v = 0; v < one.vertices.size(); ++v)
    for (std::size_t axis = 0; axis < 3; ++axis)
      ASSERT_EQ(std::bit_cast<std::uint64_t>(many.vertices[v][axis]),
                std::bit_cast<std::uint64_t>(one.vertices[v][axis]))
          << v;
  ASSERT_EQ(many.across, one.across);
  for (const std::array<std::uint32_t, 3>& across : one.across)
    for (const std::uint32_t other : across)
      ASSERT_NE(other, detail::Pseudonormals::kNone);  // closed: every edge has its partner
}

}  // namespace
}  // namespace delta::contactdetection
