// Winding-number signs of point queries (PointQuery::sign = Sign::winding): on open meshes
// (CGAL's ChineseDragon-10kv, a closed mesh with a cut hole) and self-intersecting ones (camel,
// bull) against the exact winding number over all triangles (delta::windingNumber); on closed
// meshes that do not cross themselves against the pseudonormal sign, on random and adversarial
// points; poses, orientation, tolerance, thread counts.

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/triangle_triangle.h"
#include "delta/mesh/primitives.h"
#include "delta/query/contacts.h"
#include "delta/query/point_distance.h"
#include "delta/query/self_intersections.h"
#include "delta/query/winding_number.h"

#include "kernels/detail/exact_predicates.h"
#include "kernels/triangle_pairs.h"
#include "query/detail/query_mesh_data.h"
#include "query/probe_points.h"

namespace delta::contactdetection {
namespace {

namespace fs = std::filesystem;

const fs::path kMeshes = fs::path(DELTA_DATA_DIR) / "meshes";

PointQuery windingQuery(double tolerance = 0.05) {
  PointQuery query;
  query.signedDistance = true;
  query.sign = Sign::winding;
  query.windingTolerance = tolerance;
  return query;
}

/// `mesh` less its triangles whose centroid lies within `radius` of the centroid of triangle
/// `centre`: a hole, and the mesh no longer closed.
Mesh cutHole(const Mesh& mesh, std::size_t centre, double radius) {
  const Vec3 at = mesh.triangle(centre).centroid();
  std::vector<TriangleIndices> kept;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t)
    if (length(mesh.triangle(t).centroid() - at) > radius) kept.push_back(mesh.triangles()[t]);
  return Mesh({mesh.vertices().begin(), mesh.vertices().end()}, kept);
}

/// Points within `reach` of the surface (a random point of a random triangle, moved by a random
/// offset of length up to `reach`), then `far` points uniform in the box grown by 50% per side.
std::vector<Vec3> nearAndFar(const Mesh& mesh, std::size_t near, double reach, std::size_t far,
                             std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::vector<Vec3> points;
  for (std::size_t i = 0; i < near; ++i) {
    const Triangle t = mesh.triangle(random() % mesh.triangleCount());
    double u = test::unit(random), v = test::unit(random);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    const Vec3 onSurface = t.a + (t.b - t.a) * u + (t.c - t.a) * v;
    const Vec3 direction = normalized(
        Vec3{test::unit(random) - 0.5, test::unit(random) - 0.5, test::unit(random) - 0.5});
    points.push_back(onSurface + direction * (reach * test::unit(random)));
  }
  const std::vector<Vec3> uniform = test::uniformAround(mesh.bounds(), far, 0.5, random);
  points.insert(points.end(), uniform.begin(), uniform.end());
  return points;
}

/// Sign::winding against the exact winding number w over all triangles (times the mesh's
/// orientation `orientation`): inside where w > ½ and ambiguous where |w − ½| ≤ tolerance, for
/// every point further than 1e-9 from both thresholds (the two sums round differently).
/// Returns the number of ambiguous points.
std::size_t expectExactSigns(const Mesh& mesh, const std::vector<Vec3>& points, double orientation,
                             double tolerance = 0.05) {
  const QueryMesh query(mesh);
  const TriangleSoA triangles = flatten(mesh);
  const std::vector<PointDistance> answers = distances(query, points, windingQuery(tolerance));
  std::size_t ambiguous = 0, checked = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double w = windingNumber(triangles, points[i]) * orientation;
    ambiguous += answers[i].ambiguous;
    if (!(answers[i].distance > 0.0)) {
      EXPECT_FALSE(answers[i].inside || answers[i].ambiguous) << i;
      continue;
    }
    const double margin = std::abs(w - 0.5);
    if (margin > 1e-9) {
      EXPECT_EQ(answers[i].inside, w > 0.5) << "point " << i << " w " << w;
    }
    if (std::abs(margin - tolerance) > 1e-9) {
      EXPECT_EQ(answers[i].ambiguous, margin <= tolerance) << "point " << i << " w " << w;
    }
    ++checked;
  }
  EXPECT_GT(checked, points.size() / 2);
  return ambiguous;
}

TEST(WindingSign, OpenSphereWithACutHoleAgreesWithTheExactWindingNumber) {
  const Mesh sphere = primitives::icosphere(4);
  const Mesh open = cutHole(sphere, 0, 0.3);
  ASSERT_FALSE(QueryMesh(open).closed());
  std::vector<Vec3> points =
      nearAndFar(open, test::scaledCount(3000), 0.05, test::scaledCount(1000), 1);
  // along the hole's axis, through its middle, where w passes ½
  const Vec3 axis = normalized(sphere.triangle(0).centroid());
  for (int i = -20; i <= 20; ++i)
    points.push_back(axis * (1.0 + 0.004 * i));
  const std::size_t ambiguous = expectExactSigns(open, points, 1.0);
  EXPECT_GT(ambiguous, 0u);  // points across the hole
  EXPECT_LT(ambiguous, points.size() / 10);
  // Inside-out: the orientation (sign of the volume about the box's centre) keeps inside inside.
  std::vector<TriangleIndices> flipped(open.triangles().begin(), open.triangles().end());
  for (TriangleIndices& t : flipped)
    std::swap(t[1], t[2]);
  const Mesh insideOut({open.vertices().begin(), open.vertices().end()}, flipped);
  expectExactSigns(insideOut, points, -1.0);
  EXPECT_TRUE(distance(QueryMesh(insideOut), {0.1, 0.0, -0.2}, windingQuery()).inside);
}

TEST(WindingSign, BesideAnOpenSheetAmbiguousPointsAgreeWithTheExactWindingNumber) {
  // Beside an open sheet w is near ½ on one side: every such point is ambiguous, and each went
  // to the exact O(n) sum (a grid around a sheet of 33,000 triangles took 49 s). The hierarchy
  // now decides them where its bound puts w within the tolerance and on one side of ½.
  constexpr std::size_t n = 60;  // 7200 triangles, gently curved
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  for (std::size_t j = 0; j <= n; ++j)
    for (std::size_t i = 0; i <= n; ++i) {
      const double x = static_cast<double>(i) / n, y = static_cast<double>(j) / n;
      vertices.push_back({x, y, 0.05 * std::sin(3.0 * x) * std::cos(2.0 * y)});
    }
  const auto at = [](std::size_t i, std::size_t j) {
    return static_cast<std::uint32_t>(j * (n + 1) + i);
  };
  for (std::size_t j = 0; j < n; ++j)
    for (std::size_t i = 0; i < n; ++i) {
      triangles.push_back({at(i, j), at(i + 1, j), at(i + 1, j + 1)});
      triangles.push_back({at(i, j), at(i + 1, j + 1), at(i, j + 1)});
    }
  const Mesh sheet(std::move(vertices), std::move(triangles));
  const std::vector<Vec3> points = nearAndFar(sheet, test::scaledCount(2000), 0.03, 300, 4);
  const std::size_t ambiguous = expectExactSigns(sheet, points, 1.0);
  EXPECT_GT(ambiguous, points.size() / 5);
  expectExactSigns(sheet, points, 1.0, 0.3);
}

TEST(WindingSign, ToleranceZeroAndLarge) {
  const Mesh open = cutHole(primitives::icosphere(3), 5, 0.4);
  const std::vector<Vec3> points = nearAndFar(open, 1000, 0.1, 500, 2);
  EXPECT_EQ(expectExactSigns(open, points, 1.0, 0.0), 0u);
  expectExactSigns(open, points, 1.0, 0.45);
  for (double bad : {-0.1, 0.5, std::nan("")})
    EXPECT_THROW(distance(QueryMesh(open), {0, 0, 0}, windingQuery(bad)), Error) << bad;
}

/// Issue 22: ChineseDragon-10kv (6 boundary edges), a cut hole in elk, and camel and bull,
/// closed but self-intersecting: points within 1% of the diagonal of the surface and far ones.
TEST(WindingSign, RealMeshesAgreeWithTheExactWindingNumber) {
  struct Case {
    const char* file;
    bool cut;
  };
  for (const Case& c : {Case{"ChineseDragon-10kv.off", false}, Case{"elk.off", true},
                        Case{"camel.off", false}, Case{"bull.off", false}}) {
    SCOPED_TRACE(c.file);
    if (!fs::exists(kMeshes / c.file)) GTEST_SKIP() << kMeshes / c.file << " is missing";
    Mesh mesh = io::load(kMeshes / c.file);
    if (c.cut) mesh = cutHole(mesh, 100, 0.05 * mesh.bounds().diagonal());
    const std::vector<Vec3> points = nearAndFar(
        mesh, test::scaledCount(1500), 0.01 * mesh.bounds().diagonal(), test::scaledCount(300), 3);
    expectExactSigns(mesh, points, 1.0);
  }
}

/// Points off the surface of a closed mesh that does not cross itself: the winding sign is the
/// pseudonormal sign, and no point is ambiguous.
void expectPseudonormalSigns(const QueryMesh& query, const std::vector<Vec3>& points) {
  ASSERT_TRUE(query.closed());
  ASSERT_FALSE(selfIntersections(query).any());
  PointQuery pseudonormal;
  pseudonormal.signedDistance = true;
  const std::vector<PointDistance> expected = distances(query, points, pseudonormal);
  const std::vector<PointDistance> answers = distances(query, points, windingQuery());
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(answers[i].distance, expected[i].distance) << i;
    EXPECT_EQ(answers[i].triangle, expected[i].triangle) << i;
    EXPECT_EQ(answers[i].inside, expected[i].inside)
        << "point " << i << " distance " << expected[i].distance;
    EXPECT_FALSE(answers[i].ambiguous) << i;
    EXPECT_FALSE(expected[i].ambiguous) << i;
  }
}

TEST(WindingSign, ClosedMeshesAgreeWithPseudonormalsOnRandomAndAdversarialPoints) {
  std::vector<Mesh> meshes = {primitives::icosphere(3), primitives::box({1, 2, 3}),
                              primitives::cylinder(1, 3, 40), primitives::granulate(11)};
  for (const char* file : {"elephant.off", "armadillo.off"})
    if (fs::exists(kMeshes / file)) meshes.push_back(io::load(kMeshes / file));
  for (const Mesh& mesh : meshes) {
    // uniform, and on and ±1e-6 of the diagonal off vertices, edge midpoints and centroids
    std::vector<Vec3> points = test::probes(mesh, test::scaledCount(2000), 4);
    const double size = mesh.bounds().diagonal();
    const Vec3 centre = mesh.bounds().center();
    for (const double far : {10.0, 1e6, 1e15})
      for (const Vec3& direction : {Vec3{1, 0, 0}, Vec3{-0.6, 0.8, 0}, Vec3{0.3, -0.4, 0.866}})
        points.push_back(centre + direction * (far * size));
    // within 1e-9 of the diagonal of random vertices, in every direction
    std::mt19937_64 random(5);
    for (std::size_t i = 0; i < 500; ++i) {
      const Vec3 v = mesh.vertices()[random() % mesh.vertexCount()];
      points.push_back(
          v + Vec3{test::unit(random) - 0.5, test::unit(random) - 0.5, test::unit(random) - 0.5} *
                  (1e-9 * size));
    }
    const QueryMesh query(mesh);
    expectPseudonormalSigns(query, points);
    // The exact rays (the pseudonormal sign's last resort where the offset is all but tangent)
    // agree everywhere they answer: nearly everywhere but on a box, whose faces hold the rays
    // from its edges.
    PointQuery signedQuery;
    signedQuery.signedDistance = true;
    const std::vector<PointDistance> expected = distances(query, points, signedQuery);
    std::size_t answered = 0;
    for (std::size_t i = 0; i < points.size(); ++i)
      if (const std::optional<bool> inside = detail::insideByExactRays(query.data(), points[i])) {
        ++answered;
        EXPECT_EQ(*inside, expected[i].inside) << toString(points[i]);
      }
    EXPECT_GT(answered, points.size() * 9 / 10) << mesh.triangleCount();
  }
}

/// The hierarchical winding sign itself (which the queries use on open and crossing meshes
/// only) on closed meshes that do not cross themselves: the pseudonormal sign at every point
/// further than 1e-9 of the diagonal from the surface, where the solid angles' rounding cannot
/// flip a triangle's side; none ambiguous.
TEST(WindingSign, TheHierarchyAgreesWithPseudonormalsOnClosedMeshes) {
  std::vector<Mesh> meshes = {primitives::icosphere(4), primitives::box({1, 2, 3}),
                              primitives::granulate(12)};
  for (const char* file : {"elephant.off", "armadillo.off"})
    if (fs::exists(kMeshes / file)) meshes.push_back(io::load(kMeshes / file));
  for (const Mesh& mesh : meshes) {
    const QueryMesh query(mesh);
    const double size = mesh.bounds().diagonal();
    std::vector<Vec3> points = test::probes(mesh, test::scaledCount(3000), 9);
    const std::vector<Vec3> near = nearAndFar(mesh, test::scaledCount(3000), 1e-3 * size, 0, 10);
    points.insert(points.end(), near.begin(), near.end());
    PointQuery pseudonormal;
    pseudonormal.signedDistance = true;
    const std::vector<PointDistance> expected = distances(query, points, pseudonormal);
    std::size_t checked = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!(expected[i].distance > 1e-9 * size)) continue;
      const detail::WindingSign sign = detail::windingSign(query.data(), points[i], 0.05);
      EXPECT_EQ(sign.inside, expected[i].inside) << i << " w " << sign.winding;
      EXPECT_FALSE(sign.ambiguous) << i;
      ++checked;
    }
    EXPECT_GT(checked, points.size() / 2);
  }
}

TEST(WindingSign, HugeOffsets) {
  // A small sphere far from the origin, and points at the edge of the coordinate range.
  const QueryMesh query(primitives::icosphere(3, 1e-3, {1e12, -3e11, 7e11}));
  const std::vector<Vec3> points = {{1e12, -3e11, 7e11},        {1e12 + 2e-3, -3e11, 7e11},
                                    {1e12 + 5e-4, -3e11, 7e11}, {0, 0, 0},
                                    {1e59, 1e59, -1e59},        {-1.5e60, 0, 0}};
  expectPseudonormalSigns(query, points);
  const std::vector<PointDistance> answers = distances(query, points, windingQuery());
  EXPECT_TRUE(answers[0].inside);
  EXPECT_FALSE(answers[1].inside);
  EXPECT_TRUE(answers[2].inside);
  EXPECT_FALSE(answers[4].inside);
}

TEST(WindingSign, PointsOnTheSurfaceAreNeitherInsideNorAmbiguous) {
  const Mesh open = cutHole(primitives::icosphere(2), 0, 0.3);
  const QueryMesh query(open);
  for (std::size_t t = 0; t < open.triangleCount(); t += 7) {
    const PointDistance answer = distance(query, open.triangle(t).b, windingQuery());
    EXPECT_EQ(answer.distance, 0.0);
    EXPECT_FALSE(answer.inside);
    EXPECT_FALSE(answer.ambiguous);
  }
}

/// The side of `p` of a convex closed mesh, exactly: outside (1) above some face's plane, on the
/// surface (0) where none is above and one holds it, else inside (−1).
int exactSideOfConvex(const Mesh& convex, const Vec3& p) {
  bool above = false, on = false;
  for (std::size_t t = 0; t < convex.triangleCount(); ++t) {
    const Triangle f = convex.triangle(t);
    const int side = detail::orientSign(f.a, f.b, f.c, p);  // filtered, then exact
    above = above || side > 0;
    on = on || side == 0;
  }
  return above ? 1 : on ? 0 : -1;
}

/// Points within rounding of faces of `sphere` (convex), `perFace` on each of `faces` of its
/// faces (every one where `faces` is 0), offset by ±5e-17 … ±2e-16 and 0, and the faces' edge
/// midpoints, rounded; `extra` first.
std::vector<Vec3> pointsWithinRoundingOfFaces(const Mesh& sphere, std::size_t faces,
                                              std::vector<Vec3> extra) {
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const std::size_t count = faces == 0 ? sphere.triangleCount() : faces;
  for (std::size_t i = 0; i < count; ++i) {
    const Triangle f = sphere.triangle(faces == 0 ? i : random() % sphere.triangleCount());
    const Vec3 normal = normalized(cross(f.b - f.a, f.c - f.a));
    for (int k = 0; k < 6; ++k) {
      double u = unit(random), v = unit(random);
      if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
      const Vec3 onFace = f.a + (f.b - f.a) * u + (f.c - f.a) * v;
      for (const double offset : {-2e-16, -1e-16, -5e-17, 0.0, 5e-17, 1e-16, 2e-16})
        extra.push_back(onFace + normal * offset);
    }
    extra.push_back((f.a + f.b) * 0.5);
  }
  return extra;
}

/// Both sign rules of the point queries give every point of `points` the exact side of `sphere`
/// (convex): on the surface is not inside.
void expectExactSidesOfConvex(const Mesh& sphere, const std::vector<Vec3>& points) {
  const QueryMesh query(sphere);
  std::size_t near = 0, wrongPseudonormal = 0, wrongWinding = 0;
  for (const Vec3& p : points) {
    const int side = exactSideOfConvex(sphere, p);
    const PointDistance byNormals = distance(query, p, {.signedDistance = true});
    const PointDistance byWinding = distance(query, p, windingQuery(0.0));
    near += byNormals.distance < 1e-15;
    wrongPseudonormal += byNormals.inside != (side < 0);
    wrongWinding += byWinding.inside != (side < 0) || byWinding.ambiguous;
    if (byNormals.inside != (side < 0) || byWinding.inside != (side < 0))
      ADD_FAILURE() << toString(p) << ": exact side " << side << ", pseudonormal inside "
                    << byNormals.inside << ", winding inside " << byWinding.inside;
  }
  EXPECT_GT(near, points.size() * 3 / 4);
  EXPECT_EQ(wrongPseudonormal, 0u);
  EXPECT_EQ(wrongWinding, 0u);
}

TEST(WindingSign, PointsWithinRoundingOfTheSurfaceAreSignedExactly) {
  // Within rounding of a face the closest point's own rounding turns the offset from it, and the
  // nearest faces' solid angles lose their sign: points 3e-17 outside an icosphere were inside,
  // one 4e-17 inside was outside, and one exactly on a face was inside (found against an exact
  // oracle: 26 of 1800 such points wrong by pseudonormals, 30 by winding numbers).
  const Mesh sphere = primitives::icosphere(1);
  expectExactSidesOfConvex(sphere,
                           pointsWithinRoundingOfFaces(
                               sphere, 0,
                               {{1.0, -9.23999565833207e-19, -8.309746309022489e-17},
                                {-0.1545084971874737, -0.9045084971874737, -0.25},
                                {-0.9045084971874737, 0.25000000000000006, 0.0},
                                {0.9149169506817468, 0.12499999999999993, 0.20868702662352026}}));
}

TEST(WindingSign, PointsWithinRoundingOfALargeMeshAreSignedExactlyThroughItsTree) {
  // The exact rays walk the tree (the leaves on the ray's line), where they first tested every
  // triangle: 10³ such points on an icosphere of 3.3·10⁵ triangles took 5.4 s, now 10⁵ take
  // 0.5 s. The answers on a mesh of many leaves, against the exact side.
  const Mesh sphere = primitives::icosphere(5);
  ASSERT_GT(sphere.triangleCount(), 20000u);
  expectExactSidesOfConvex(sphere, pointsWithinRoundingOfFaces(sphere, 40, {}));
}

TEST(WindingSign, MovedMeshes) {
  const Mesh open = cutHole(primitives::icosphere(3), 0, 0.3);
  const std::vector<Vec3> points = nearAndFar(open, 1000, 0.05, 300, 6);
  const RigidTransform pose{Quaternion::fromAxisAngle({1, 2, 3}, 0.8), {1e3, -20, 5}};
  QueryMesh moved(open);
  moved.setPose(pose);
  std::vector<Vec3> movedPoints;
  for (const Vec3& p : points)
    movedPoints.push_back(pose.apply(p));
  const std::vector<PointDistance> expected = distances(QueryMesh(open), points, windingQuery());
  const std::vector<PointDistance> answers = distances(moved, movedPoints, windingQuery());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!(expected[i].distance > 1e-9)) continue;  // the motion's rounding may put it on
    EXPECT_EQ(answers[i].inside, expected[i].inside) << i;
    EXPECT_NEAR(answers[i].distance, expected[i].distance, 1e-9) << i;
  }
}

TEST(WindingSign, TheSameForAnyThreadCountAndOneByOne) {
  const Mesh open = cutHole(primitives::icosphere(4), 3, 0.5);
  const QueryMesh query(open);
  const std::vector<Vec3> points = nearAndFar(open, 4000, 0.2, 2000, 7);
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const std::vector<PointDistance> one = distances(query, points, windingQuery());
  omp_set_num_threads(std::max(threads, 4));
  const std::vector<PointDistance> many = distances(query, points, windingQuery());
  omp_set_num_threads(threads);
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(one[i].inside, many[i].inside) << i;
    EXPECT_EQ(one[i].ambiguous, many[i].ambiguous) << i;
    const PointDistance single = distance(query, points[i], windingQuery());
    EXPECT_EQ(single.inside, many[i].inside) << i;
    EXPECT_EQ(single.ambiguous, many[i].ambiguous) << i;
  }
}

TEST(WindingSign, PseudonormalsRefuseAnOpenMeshAndNameTheWindingSign) {
  const QueryMesh query(cutHole(primitives::icosphere(2), 0, 0.3));
  PointQuery request;
  request.signedDistance = true;
  try {
    distance(query, {0, 0, 0}, request);
    FAIL() << "no error";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("boundary"), std::string::npos) << message;
    EXPECT_NE(message.find("Sign::winding"), std::string::npos) << message;
  }
  EXPECT_TRUE(distance(query, {0, 0, 0}, windingQuery()).inside);
  EXPECT_GT(query.memoryBytes(), 0u);
}

TEST(WindingSign, ContactsOfACrossingClosedMeshMarkOverlapsByWindingNumber) {
  // An icosphere with a vertex pushed through it (closed, crossing itself): contacts() does not
  // refuse it, and its overlap marks are the winding number's.
  const Mesh sphere = primitives::icosphere(2);
  std::vector<Vec3> vertices(sphere.vertices().begin(), sphere.vertices().end());
  vertices[0] = vertices[0] * -1.3;
  const Mesh crossing(vertices, {sphere.triangles().begin(), sphere.triangles().end()});
  const QueryMesh query(crossing);
  ASSERT_TRUE(selfIntersections(query).any());
  const std::vector<Vec3> points = nearAndFar(crossing, 500, 0.1, 0, 8);
  const std::vector<ContactPoint> found = contacts(query, points, 0.2);
  const TriangleSoA triangles = flatten(crossing);
  for (const ContactPoint& contact : found) {
    const double w = windingNumber(triangles, points[contact.first]);
    if (contact.distance > 0.0 && std::abs(w - 0.5) > 1e-9) {
      EXPECT_EQ(contact.overlap, w > 0.5);
    }
  }
}

TEST(WindingSign, MeshContactsOfACrossingMeshMarkOverlapsByWindingNumber) {
  // The crossing icosphere against a smaller sphere around its pushed-through spike: a contact
  // point inside both is marked where the winding numbers say so, not the pseudonormals.
  const Mesh sphere = primitives::icosphere(2);
  std::vector<Vec3> vertices(sphere.vertices().begin(), sphere.vertices().end());
  const Vec3 spike = vertices[0] * -1.3;
  vertices[0] = spike;
  const Mesh crossing(vertices, {sphere.triangles().begin(), sphere.triangles().end()});
  const Mesh ball = primitives::icosphere(3, 0.5, spike * 0.8);
  const std::vector<ContactPoint> found = contacts(QueryMesh(crossing), QueryMesh(ball), 0.05);
  ASSERT_FALSE(found.empty());
  const TriangleSoA first = flatten(crossing), second = flatten(ball);
  std::size_t checked = 0;
  for (const ContactPoint& contact : found) {
    const double wa = windingNumber(first, contact.x), wb = windingNumber(second, contact.x);
    if (std::abs(wa - 0.5) < 0.01 || std::abs(wb - 0.5) < 0.01) continue;  // on a surface
    if (kernels::trianglesIntersect(crossing.triangle(contact.first),
                                    ball.triangle(contact.second)))
      continue;  // marked by the intersection itself
    EXPECT_EQ(contact.overlap, wa > 0.5 && wb > 0.5) << wa << " " << wb;
    ++checked;
  }
  EXPECT_GT(checked, 0u);
}

}  // namespace
}  // namespace delta::contactdetection

namespace delta::contactdetection {
namespace {

/// The box [−1, 1]³ with each face's diagonal split at its midpoint m on one side and a triangle
/// of zero area (its ends and m) filling the edge: closed, with a flat triangle across every face.
Mesh boxWithFlatDiagonals() {
  const Mesh box = primitives::box({2, 2, 2});
  std::vector<Vec3> vertices(box.vertices().begin(), box.vertices().end());
  std::vector<TriangleIndices> triangles;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> split;
  for (const TriangleIndices& t : box.triangles()) {
    bool done = false;
    for (std::size_t e = 0; e < 3 && !done; ++e) {
      const std::uint32_t from = t[(e + 2) % 3], to = t[e], apex = t[(e + 1) % 3];
      const Vec3 d = vertices[to] - vertices[from];
      if ((d.x != 0) + (d.y != 0) + (d.z != 0) != 2) continue;  // not the face's diagonal
      const std::pair<std::uint32_t, std::uint32_t> key{std::min(from, to), std::max(from, to)};
      if (std::find(split.begin(), split.end(), key) != split.end()) break;
      split.push_back(key);
      // t = (to, apex, from): the diagonal traversed from → to; split there at m.
      const auto m = static_cast<std::uint32_t>(vertices.size());
      vertices.push_back((vertices[from] + vertices[to]) * 0.5);
      triangles.push_back({to, apex, m});
      triangles.push_back({m, apex, from});
      triangles.push_back({to, m, from});  // zero area: to → m → from, against the other side
      done = true;
    }
    if (!done) triangles.push_back(t);
  }
  return Mesh(vertices, triangles);
}

TEST(WindingSign, ExactRaysPassOverTrianglesOfZeroArea) {
  const Mesh mesh = boxWithFlatDiagonals();
  const QueryMesh query(mesh);
  ASSERT_TRUE(query.closed());
  ASSERT_EQ(mesh.triangleCount(), 24u);
  std::mt19937_64 random(3);
  std::size_t inside = 0;
  for (std::size_t i = 0; i < 200; ++i) {
    const Vec3 p{3 * test::unit(random) - 1.5, 3 * test::unit(random) - 1.5,
                 3 * test::unit(random) - 1.5};
    const bool expected = std::abs(p.x) < 1 && std::abs(p.y) < 1 && std::abs(p.z) < 1;
    inside += expected;
    // Every axis ray from inside the box meets a flat triangle's box: they used to give nothing.
    const std::optional<bool> exact = detail::insideByExactRays(query.data(), p);
    ASSERT_TRUE(exact.has_value()) << toString(p);
    EXPECT_EQ(*exact, expected) << toString(p);
  }
  EXPECT_GT(inside, 20u);
}

}  // namespace
}  // namespace delta::contactdetection
