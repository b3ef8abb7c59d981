#include "delta/query/point_distance.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <thread>
#include <vector>

#include "delta/core/cancel.h"
#include "delta/core/error.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/primitives.h"
#include "delta/query/contacts.h"
#include "delta/query/winding_number.h"

#include "kernels/triangle_pairs.h"
#include "query/probe_points.h"

namespace delta::contactdetection {
namespace {

using test::probes;
using test::unit;

const std::filesystem::path kMeshes = std::filesystem::path(DELTA_DATA_DIR) / "meshes";

/// The reference: every triangle in id order, a strictly smaller distance replaces the best.
PointDistance byAllTriangles(const Mesh& mesh, const Vec3& point) {
  PointDistance best;
  double bestSquared = std::numeric_limits<double>::infinity();
  for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
    const kernels::PointTriangleResult r = kernels::closestPointOnTriangle(point, mesh.triangle(t));
    if (r.distanceSquared < bestSquared) {
      bestSquared = r.distanceSquared;
      best.distance = std::sqrt(r.distanceSquared);
      best.closest = r.closest;
      best.triangle = t;
    }
  }
  return best;
}

void expectSameAsAllTriangles(const Mesh& mesh, const std::vector<Vec3>& points, const char* name) {
  const QueryMesh query(mesh);
  const std::vector<PointDistance> found = distances(query, points);
  ASSERT_EQ(found.size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const PointDistance expected = byAllTriangles(mesh, points[i]);
    ASSERT_EQ(found[i].distance, expected.distance) << name << ", point " << i;
    ASSERT_EQ(found[i].triangle, expected.triangle) << name << ", point " << i;
    ASSERT_EQ(found[i].closest, expected.closest) << name << ", point " << i;
    ASSERT_FALSE(found[i].inside);
  }
}

TEST(PointDistance, SignNamesRoundTrip) {
  EXPECT_STREQ(signName(Sign::pseudonormal), "pseudonormal");
  EXPECT_STREQ(signName(Sign::winding), "winding");
  for (const Sign sign : {Sign::pseudonormal, Sign::winding})
    EXPECT_EQ(parseSign(signName(sign)), sign);
  EXPECT_FALSE(parseSign("Winding"));
  EXPECT_FALSE(parseSign(""));
}

TEST(PointDistance, SameAsEveryTriangleOnPrimitives) {
  Mesh far = primitives::granulate(5, {1, 0.5, 0.2});
  far.translate({1e6, -1e6, 3e5});
  // Beyond single precision (the tree's float boxes become infinite) and finer than its spacing
  // (a float box there is 2⁻⁴ wide around a triangle 10⁻³ across): pruning loosens, answers not.
  Mesh beyondFloat = primitives::granulate(8, {1, 2, 3});
  beyondFloat.translate({1e39, -2e39, 0});
  const Mesh finerThanFloat = primitives::icosphere(2, 1e-3, {1e6 + 0.01, 3e6, -1e6});
  const std::pair<const char*, Mesh> meshes[] = {
      {"granulate at 1e39", beyondFloat},
      {"icosphere of radius 1e-3 at 1e6", finerThanFloat},
      {"icosphere", primitives::icosphere(3)},
      {"box (ties on every face)", primitives::box({1, 2, 3})},
      {"cylinder", primitives::cylinder(0.5, 2, 17)},
      {"quad (open)", primitives::quad(2, 1)},
      {"flat granulate at 1e6", far},
      {"tiny icosphere", primitives::icosphere(2, 1e-9, {1, 1, 1})}};
  for (const auto& [name, mesh] : meshes)
    expectSameAsAllTriangles(mesh, probes(mesh, 400, 7), name);
}

TEST(PointDistance, SameAsEveryTriangleOnRealMeshes) {
  for (const char* file : {"fandisk.off", "elephant.off", "cube-meshed.off"}) {
    const Mesh mesh = io::load(kMeshes / file);
    expectSameAsAllTriangles(mesh, probes(mesh, test::kSlowBuild ? 100 : 300, 11), file);
  }
}

TEST(PointDistance, BatchOrderDoesNotChangeAnswers) {
  // Large batches are answered along a Morton curve of their points; every answer must be the
  // one the point gets alone.
  const QueryMesh mesh(io::load(kMeshes / "elephant.off"));
  const Aabb box = mesh.bounds();
  std::mt19937_64 random(17);
  std::uniform_real_distribution<double> unit(-0.1, 1.1);
  std::vector<Vec3> points(5000);
  const Vec3 size = box.upper - box.lower;
  for (Vec3& p : points)
    p = box.lower + Vec3{unit(random) * size.x, unit(random) * size.y, unit(random) * size.z};
  const std::vector<PointDistance> batch = distances(mesh, points, {.signedDistance = true});
  for (std::size_t i = 0; i < points.size(); i += 7) {
    const PointDistance alone = distance(mesh, points[i], {.signedDistance = true});
    ASSERT_EQ(batch[i].distance, alone.distance) << i;
    ASSERT_EQ(batch[i].triangle, alone.triangle) << i;
    ASSERT_EQ(batch[i].closest, alone.closest) << i;
    ASSERT_EQ(batch[i].inside, alone.inside) << i;
  }
}

TEST(PointDistance, UpperBoundsChangeNoAnswer) {
  // Bounds that are exact, loose, too small (a second search), zero, infinite: the answers are
  // those without bounds, bit for bit, in small (in order) and large (Morton order) batches. The
  // box has exact ties on every face, the moved elephant a pose to carry points through.
  QueryMesh elephant(io::load(kMeshes / "elephant.off"));
  elephant.transform(
      RigidTransform::rotationAbout(Quaternion::fromAxisAngle({1, 2, 3}, 0.4), {0.1, 0.2, 0.3}));
  for (const QueryMesh& mesh : {elephant, QueryMesh(primitives::box({1, 2, 3}))}) {
    const Aabb box = mesh.bounds();
    for (std::size_t count : {std::size_t{300}, std::size_t{3000}}) {
      std::mt19937_64 random(23);
      std::vector<Vec3> points(count);
      for (Vec3& p : points)
        p = box.lower - box.extent() * 0.1 +
            Vec3{box.extent().x * unit(random), box.extent().y * unit(random),
                 box.extent().z * unit(random)} *
                1.2;
      const std::vector<PointDistance> plain = distances(mesh, points, {.signedDistance = true});
      std::vector<double> bounds(points.size());
      for (std::size_t i = 0; i < points.size(); ++i) {
        const double scale[] = {1.0, 1.5, 0.5, 0.0, INFINITY};
        bounds[i] = plain[i].distance * scale[i % 5];
        if (i % 5 == 3) bounds[i] = 0.0;
      }
      std::vector<PointDistance> bounded(points.size());
      distances(mesh, points, bounds, {.signedDistance = true}, bounded);
      for (std::size_t i = 0; i < points.size(); ++i) {
        ASSERT_EQ(bounded[i].distance, plain[i].distance) << i;
        ASSERT_EQ(bounded[i].triangle, plain[i].triangle) << i;
        ASSERT_EQ(bounded[i].closest, plain[i].closest) << i;
        ASSERT_EQ(bounded[i].inside, plain[i].inside) << i;
      }
      // With ε, a bound beyond ε is ε.
      std::vector<PointDistance> near(points.size());
      const double epsilon = 0.05 * box.diagonal();
      distances(mesh, points, bounds, {.epsilon = epsilon}, near);
      const std::vector<PointDistance> nearPlain = distances(mesh, points, {.epsilon = epsilon});
      for (std::size_t i = 0; i < points.size(); ++i)
        ASSERT_EQ(near[i].distance, nearPlain[i].distance) << i;
      bounds[7] = -1.0;
      EXPECT_THROW(distances(mesh, points, bounds, {}, bounded), Error);
      bounds[7] = NAN;
      EXPECT_THROW(distances(mesh, points, bounds, {}, bounded), Error);
      bounds.pop_back();
      EXPECT_THROW(distances(mesh, points, bounds, {}, bounded), Error);
    }
  }
}

TEST(PointDistance, DegenerateTrianglesAndExactTies) {
  // A zero-area triangle, a needle and a repeated triangle among ordinary ones.
  const Mesh mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}, {1, 1e-300, 0}, {0.5, 0.5, 1}},
                  {{0, 1, 2}, {0, 1, 3}, {1, 3, 4}, {0, 1, 2}, {2, 1, 5}, {4, 4, 4}});
  std::vector<Vec3> points = probes(mesh, 200, 3);
  for (double x = -1; x <= 3; x += 0.25)
    points.push_back({x, 0.5, 0.5});
  expectSameAsAllTriangles(mesh, points, "degenerate");
}

TEST(PointDistance, EpsilonIsStrict) {
  const QueryMesh box(primitives::box());  // faces at ±0.5
  const std::vector<Vec3> points = {{0, 0, 0.75}, {0, 0, 0.7}, {0, 0, 5}};
  const std::vector<PointDistance> found = distances(box, points, {.epsilon = 0.25});
  EXPECT_FALSE(found[0].found());  // exactly 0.25 away
  EXPECT_TRUE(std::isinf(found[0].distance));
  ASSERT_TRUE(found[1].found());
  EXPECT_DOUBLE_EQ(found[1].distance, 0.2);
  EXPECT_FALSE(found[2].found());
  EXPECT_TRUE(distances(box, points, {.epsilon = std::nextafter(0.25, 1.0)})[0].found());
}

TEST(PointDistance, WithinEpsilonAgreesWithTheFullQuery) {
  // Batches over several of the grid sieve's blocks, with the mesh where it was built and moved
  // (the sieve reads the grid in the mesh's frame).
  const Mesh mesh = io::load(kMeshes / "fandisk.off");
  QueryMesh moved(mesh);
  moved.transform(
      RigidTransform::rotationAbout(Quaternion::fromAxisAngle({3, 1, 2}, 0.7), {0.5, -0.2, 0.1}));
  for (const QueryMesh& query : {QueryMesh(mesh), moved}) {
    std::vector<Vec3> points = probes(mesh, test::scaledCount(6000), 5);
    for (Vec3& p : points)
      p = query.pose().apply(p);
    const double epsilon = 0.01 * mesh.bounds().diagonal();
    const std::vector<PointDistance> all = distances(query, points);
    const std::vector<PointDistance> near = distances(query, points, {.epsilon = epsilon});
    std::size_t within = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      ASSERT_EQ(near[i].found(), all[i].distance < epsilon) << i;
      if (!near[i].found()) continue;
      ++within;
      EXPECT_EQ(near[i].distance, all[i].distance);
      EXPECT_EQ(near[i].triangle, all[i].triangle);
      EXPECT_EQ(near[i].closest, all[i].closest);
    }
    EXPECT_GT(within, points.size() / 4);  // the nudged points at least
  }
}

TEST(PointDistance, ClusteredPointsWithinEpsilonGetTheirOwnAnswers) {
  // An ε-limited batch searches the points the grid leaves in doubt a cell at a time, among the
  // leaves near the cell's points: clusters of points around vertices, edges and faces (the
  // box's ties, a sphere's curved faces), on a mesh where it was built and moved, through the
  // Vec3 and the coordinate-array calls and with bounds, must each get the answer the point
  // gets alone.
  QueryMesh sphere(primitives::icosphere(3));
  sphere.transform(
      RigidTransform::rotationAbout(Quaternion::fromAxisAngle({1, -2, 3}, 0.9), {2.0, -1.0, 0.5}));
  for (const QueryMesh& mesh : {QueryMesh(primitives::box({1, 2, 3})), sphere}) {
    std::mt19937_64 random(41);
    const Mesh& shape = mesh.mesh();
    const double epsilon = 0.05 * shape.bounds().diagonal();
    std::vector<Vec3> points;
    while (points.size() < 6000) {
      const Triangle t = shape.triangle(random() % shape.triangleCount());
      const Vec3 centre = random() % 2 ? t.a : (t.a + t.b) * 0.5;
      const double spread = random() % 2 ? 0.3 * epsilon : 3.0 * epsilon;
      for (std::size_t i = 0; i < 24; ++i)
        points.push_back(mesh.pose().apply(
            centre + Vec3{unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5} * spread));
    }
    std::vector<double> x, y, z, bounds;
    for (const Vec3& p : points) {
      x.push_back(p.x);
      y.push_back(p.y);
      z.push_back(p.z);
      bounds.push_back(unit(random) * 2.0 * epsilon);
    }
    const PointQuery query{.epsilon = epsilon};
    const std::vector<PointDistance> batch = distances(mesh, points, query);
    const std::vector<PointDistance> arrays = distances(mesh, x, y, z, query);
    std::vector<PointDistance> bounded(points.size());
    distances(mesh, points, bounds, query, bounded);
    std::size_t found = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const PointDistance alone = distance(mesh, points[i], query);
      found += alone.found();
      for (const std::vector<PointDistance>* answers :
           {&batch, &arrays, static_cast<const std::vector<PointDistance>*>(&bounded)}) {
        const PointDistance& a = (*answers)[i];
        ASSERT_EQ(a.triangle, alone.triangle) << i;
        ASSERT_EQ(a.distance, alone.distance) << i;
        ASSERT_EQ(a.closest, alone.closest) << i;
      }
    }
    EXPECT_GT(found, points.size() / 3);
    EXPECT_LT(found, points.size());
  }
}

/// Inside by the generalized winding number over all triangles.
void expectSignsOfTheWindingNumber(const Mesh& mesh, const std::vector<Vec3>& points,
                                   const char* name) {
  const QueryMesh query(mesh);
  ASSERT_TRUE(query.closed()) << name;
  const TriangleSoA flat = flatten(mesh);
  const std::vector<PointDistance> found = distances(query, points, {.signedDistance = true});
  const double orientation = signedVolume(mesh) < 0 ? -1.0 : 1.0;
  const double surface = 1e-9 * mesh.bounds().diagonal();
  std::size_t inside = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (found[i].distance <= surface) continue;
    const bool expected = orientation * windingNumber(flat, points[i]) > 0.5;
    ASSERT_EQ(found[i].inside, expected)
        << name << ", point " << i << " at distance " << found[i].distance;
    inside += expected;
  }
  EXPECT_GT(inside, 0u) << name;
  EXPECT_LT(inside, points.size()) << name;
}

/// Points along the pseudonormal directions of vertices and through the middles of edges, close
/// to the surface: where a nearest triangle's own face normal would give the wrong sign.
std::vector<Vec3> featureProbes(const Mesh& mesh, std::size_t count, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::vector<Vec3> points = probes(mesh, count, seed);
  const double step = 1e-4 * mesh.bounds().diagonal();
  for (std::size_t i = 0; i < count; ++i) {
    const Triangle t = mesh.triangle(random() % mesh.triangleCount());
    const Vec3 normal = normalized(t.areaVector());
    for (const Vec3& on : {t.b, (t.b + t.c) * 0.5})
      for (double side : {-3.0, -1.0, 1.0, 3.0})
        points.push_back(on + (normal + Vec3{unit(random), unit(random), unit(random)} * 0.5) *
                                  (side * step));
  }
  return points;
}

TEST(PointDistance, SignedAgreesWithTheWindingNumber) {
  const Mesh sphere = primitives::icosphere(2);
  std::vector<TriangleIndices> reversed(sphere.triangles().begin(), sphere.triangles().end());
  for (TriangleIndices& t : reversed)
    std::swap(t[1], t[2]);  // every face turned inward
  const Mesh insideOut({sphere.vertices().begin(), sphere.vertices().end()}, reversed);
  const std::pair<const char*, Mesh> meshes[] = {
      {"icosphere", primitives::icosphere(3)},
      {"box", primitives::box({1, 2, 3}, {1e6, 0, 0})},
      {"granulate", primitives::granulate(9, {1, 0.3, 0.6})},
      {"inside-out icosphere", insideOut},
      {"elephant", io::load(kMeshes / "elephant.off")},
      {"knot1", io::load(kMeshes / "knot1.off")}};
  for (const auto& [name, mesh] : meshes)
    expectSignsOfTheWindingNumber(mesh, featureProbes(mesh, test::kSlowBuild ? 150 : 400, 13),
                                  name);
}

TEST(PointDistance, SignedOnAClosedMeshWithZeroAreaTriangles) {
  // Triangle (a, b, c) of an icosphere split at the middle m of ab into (a, m, c) and (m, b, c),
  // with the collinear sliver (a, b, m) closing the gap toward the neighbour across ab, and a
  // fold (c, c, a): still closed and consistently oriented, with two zero-area triangles whose
  // normals sign nothing.
  const Mesh sphere = primitives::icosphere(1);
  std::vector<Vec3> vertices(sphere.vertices().begin(), sphere.vertices().end());
  std::vector<TriangleIndices> triangles(sphere.triangles().begin(), sphere.triangles().end());
  const auto [a, b, c] = triangles[0];
  vertices.push_back((vertices[a] + vertices[b]) * 0.5);
  const auto m = static_cast<std::uint32_t>(vertices.size() - 1);
  triangles[0] = {a, m, c};
  triangles.push_back({m, b, c});
  triangles.push_back({a, b, m});
  triangles.push_back({c, c, a});
  const Mesh split(vertices, triangles);
  ASSERT_TRUE(QueryMesh(split).closed());
  std::vector<Vec3> points = featureProbes(split, 200, 17);
  const Vec3 outward = normalized(vertices[m]);
  for (double step : {1e-6, 1e-3, 0.1})  // along the sliver's line, both sides of the surface
    for (double side : {-1.0, 1.0})
      for (const Vec3& on : {vertices[m], vertices[a] * 0.75 + vertices[b] * 0.25})
        points.push_back(on + outward * (side * step));
  expectSignsOfTheWindingNumber(split, points, "split icosphere");
}

TEST(PointDistance, OpenMeshRefusesSignedButAnswersUnsigned) {
  const QueryMesh quad(primitives::quad());
  EXPECT_FALSE(quad.closed());
  try {
    distances(quad, std::vector<Vec3>{{0, 0, 1}}, {.signedDistance = true});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("4 boundary"), std::string::npos) << e.what();
  }
  EXPECT_EQ(distance(quad, {0, 0, 1}).distance, 1.0);
}

TEST(PointDistance, BadInputThrows) {
  const QueryMesh box(primitives::box());
  const std::vector<Vec3> points = {{0, 0, 0}, {0, std::nan(""), 0}};
  for (double epsilon : {0.0, -1.0, std::nan("")})
    EXPECT_THROW(distances(box, points, {.epsilon = epsilon}), Error);
  try {
    distances(box, points);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("point 1 "), std::string::npos) << e.what();
  }
  EXPECT_THROW(distance(box, {0, INFINITY, 0}), Error);
  // A large batch (sieved by the grid in blocks when ε is finite) names its first bad point.
  std::vector<Vec3> many(20000, Vec3{2, 0, 0});
  many[17000].z = INFINITY;
  many[9000].y = std::nan("");
  for (double epsilon : {0.5, std::numeric_limits<double>::infinity()}) {
    try {
      distances(box, many, {.epsilon = epsilon});
      FAIL() << "no error";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("point 9000 "), std::string::npos) << e.what();
    }
  }
  const std::vector<double> x = {0, 1}, y = {0, 1}, z = {0};
  EXPECT_THROW(distances(box, x, y, z), Error);
  std::vector<PointDistance> small(1);
  EXPECT_THROW(distances(box, points, {}, small), Error);
  EXPECT_TRUE(distances(box, std::vector<Vec3>{}).empty());
  EXPECT_THROW(QueryMesh(Mesh({}, {})), Error);
  EXPECT_THROW(contacts(box, points, INFINITY), Error);
}

TEST(PointDistance, StructureOfArraysGivesTheSameAnswers) {
  const Mesh mesh = primitives::granulate(2);
  const QueryMesh query(mesh);
  const std::vector<Vec3> points = probes(mesh, 300, 19);
  std::vector<double> x, y, z;
  for (const Vec3& p : points) {
    x.push_back(p.x);
    y.push_back(p.y);
    z.push_back(p.z);
  }
  const std::vector<PointDistance> a = distances(query, points, {.signedDistance = true});
  const std::vector<PointDistance> b = distances(query, x, y, z, {.signedDistance = true});
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].distance, b[i].distance);
    EXPECT_EQ(a[i].triangle, b[i].triangle);
    EXPECT_EQ(a[i].inside, b[i].inside);
  }
}

TEST(PointDistance, PointContactsAreThePointsWithinEpsilon) {
  const Mesh mesh = primitives::icosphere(3);
  const QueryMesh query(mesh);
  const std::vector<Vec3> points = probes(mesh, 500, 23);
  const double epsilon = 0.05;
  const std::vector<ContactPoint> found = contacts(query, points, epsilon);
  const std::vector<PointDistance> all = distances(query, points, {.signedDistance = true});
  std::size_t k = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!(all[i].distance < epsilon)) continue;
    ASSERT_LT(k, found.size());
    const ContactPoint& c = found[k++];
    EXPECT_EQ(c.first, i);
    EXPECT_EQ(c.second, all[i].triangle);
    EXPECT_EQ(c.distance, all[i].distance);
    EXPECT_EQ(c.overlap, all[i].inside);
    EXPECT_NEAR(length(c.direction), 1.0, 1e-15);
    // normal = P − x, rounded: x + normal is P to within the roundings of the difference and
    // the sum (exactly P where x is within a factor 2 of P, as most are: not a promise).
    const double rounding =
        2 * std::numeric_limits<double>::epsilon() * (maxAbs(points[i]) + maxAbs(c.x));
    EXPECT_LE(maxAbs(c.x + c.normal - points[i]), rounding) << i;
    // The direction points from the surface to the point: outward for a point outside (off
    // the surface by more than rounding: the probes include points exactly on faces).
    if (c.distance > 1e-9) {
      EXPECT_EQ(dot(c.direction, points[i]) > 0, !c.overlap) << i;
    }
  }
  EXPECT_EQ(k, found.size());
  EXPECT_GT(found.size(), 100u);
}

TEST(PointDistance, MeshContactsMarkPointsInsideBothMeshes) {
  // A sphere pokes up through the bottom face (z = 0) of a box. Its triangles just above z = 0
  // are inside the box and closer than 2ε to the bottom face without crossing it; below them,
  // the contact point lies inside both meshes: an overlap that no triangle pair shows.
  const Mesh box = primitives::box({4, 4, 2}, {0, 0, 1});
  const Mesh sphere = primitives::icosphere(3, 1.0, {0.1, 0.05, -0.6});
  const QueryMesh a(box), b(sphere);
  const double epsilon = 0.05;
  const std::vector<ContactPoint> flat = contacts(a.triangles(), b.triangles(), epsilon);
  const std::vector<ContactPoint> full = contacts(a, b, epsilon);
  ASSERT_EQ(flat.size(), full.size());
  std::size_t insideBoth = 0, outside = 0;
  for (std::size_t k = 0; k < full.size(); ++k) {
    ASSERT_EQ(full[k].first, flat[k].first);
    ASSERT_EQ(full[k].second, flat[k].second);
    if (flat[k].overlap) {
      EXPECT_TRUE(full[k].overlap) << k;
      continue;
    }
    const Vec3 x = full[k].x;
    if (distance(a, x).distance < 1e-9 || distance(b, x).distance < 1e-9) continue;  // on one
    const bool expected =
        windingNumber(a.triangles(), x) > 0.5 && windingNumber(b.triangles(), x) > 0.5;
    EXPECT_EQ(full[k].overlap, expected) << k;
    (expected ? insideBoth : outside) += 1;
  }
  EXPECT_GT(insideBoth, 0u);
  EXPECT_GT(outside, 0u);
  // Open meshes have no inside: the marker is the triangles' intersection alone.
  const QueryMesh floor(primitives::quad(4, 4));
  const std::vector<ContactPoint> open = contacts(floor, b, epsilon);
  const std::vector<ContactPoint> openFlat = contacts(floor.triangles(), b.triangles(), epsilon);
  ASSERT_EQ(open.size(), openFlat.size());
  for (std::size_t k = 0; k < open.size(); ++k)
    EXPECT_EQ(open[k].overlap, openFlat[k].overlap);
}

/// Each point's answer alone (no batch: no sieve, no shared buffers), at `epsilon`.
std::vector<PointDistance> oneByOne(const QueryMesh& mesh, const std::vector<Vec3>& points,
                                    double epsilon) {
  std::vector<PointDistance> answers;
  for (const Vec3& p : points)
    answers.push_back(distance(mesh, p, {.epsilon = epsilon}));
  return answers;
}

void expectSameAnswers(const std::vector<PointDistance>& found,
                       const std::vector<PointDistance>& expected, const char* what) {
  ASSERT_EQ(found.size(), expected.size()) << what;
  for (std::size_t i = 0; i < found.size(); ++i) {
    ASSERT_EQ(found[i].found(), expected[i].found()) << what << ", point " << i;
    ASSERT_EQ(found[i].distance, expected[i].distance) << what << ", point " << i;
    ASSERT_EQ(found[i].triangle, expected[i].triangle) << what << ", point " << i;
    ASSERT_EQ(found[i].closest, expected[i].closest) << what << ", point " << i;
  }
}

TEST(PointDistance, EpsilonBatchesOfEverySizeInTurnGetTheirOwnAnswers) {
  // A thread keeps an ε-limited batch's buffers for the next batch: larger, smaller and larger
  // batches again, on two meshes in turn (one moved), must each get every point's own answer,
  // nothing of the batch before.
  const Mesh fandisk = io::load(kMeshes / "fandisk.off");
  const Mesh sphere = primitives::icosphere(3);
  QueryMesh moved(sphere);
  moved.transform(
      RigidTransform::rotationAbout(Quaternion::fromAxisAngle({1, 2, -1}, 0.4), {0.3, 0.1, -2.0}));
  const QueryMesh still(fandisk);
  std::uint64_t seed = 11;
  for (const std::size_t count : {6000, 1100, 9000, 1500, 6000}) {
    for (const QueryMesh* mesh : {&still, static_cast<const QueryMesh*>(&moved)}) {
      std::vector<Vec3> points = probes(mesh->mesh(), test::scaledCount(count), seed++);
      for (Vec3& p : points)
        p = mesh->pose().apply(p);
      const double epsilon = 0.02 * mesh->mesh().bounds().diagonal();
      expectSameAnswers(distances(*mesh, points, {.epsilon = epsilon}),
                        oneByOne(*mesh, points, epsilon), mesh == &still ? "fandisk" : "sphere");
    }
  }
}

TEST(PointDistance, ABatchRunFromAnotherOnesCancellationPollKeepsBothAnswers) {
  // The calling thread's batch buffers are the outer batch's while its poll runs: a batch run
  // from the poll (a Python signal handler may) must use buffers of its own.
  const Mesh fandisk = io::load(kMeshes / "fandisk.off");
  const Mesh sphere = primitives::icosphere(3);
  const QueryMesh outer(fandisk), inner(sphere);
  const std::vector<Vec3> outerPoints = probes(fandisk, test::scaledCount(6000), 3);
  const std::vector<Vec3> innerPoints = probes(sphere, test::scaledCount(3000), 4);
  const double outerEpsilon = 0.02 * fandisk.bounds().diagonal();
  const double innerEpsilon = 0.05 * sphere.bounds().diagonal();
  const std::vector<PointDistance> outerExpected = oneByOne(outer, outerPoints, outerEpsilon);
  const std::vector<PointDistance> innerExpected = oneByOne(inner, innerPoints, innerEpsilon);
  for (const int threads : {1, 2}) {
    omp_set_num_threads(threads);
    std::vector<std::vector<PointDistance>> innerRuns;
    bool polling = false;
    std::vector<PointDistance> outerFound;
    {
      const CancelScope scope([&] {
        if (polling || innerRuns.size() >= 3) return false;
        polling = true;
        innerRuns.push_back(distances(inner, innerPoints, {.epsilon = innerEpsilon}));
        polling = false;
        return false;
      });
      outerFound = distances(outer, outerPoints, {.epsilon = outerEpsilon});
    }
    ASSERT_FALSE(innerRuns.empty()) << threads << " threads";  // the caller polls before its chunks
    expectSameAnswers(outerFound, outerExpected, "the outer batch");
    for (const std::vector<PointDistance>& run : innerRuns)
      expectSameAnswers(run, innerExpected, "an inner batch");
  }
  omp_set_num_threads(2);
}

TEST(PointDistance, SameAnswersForAnyThreadCountAndFromManyThreads) {
  const Mesh mesh = io::load(kMeshes / "elephant.off");
  const QueryMesh query(mesh);
  const std::vector<Vec3> points = probes(mesh, 4000, 29);
  omp_set_num_threads(1);
  const std::vector<PointDistance> serial = distances(query, points, {.signedDistance = true});
  omp_set_num_threads(2);
  const auto same = [&](const std::vector<PointDistance>& other) {
    ASSERT_EQ(other.size(), serial.size());
    for (std::size_t i = 0; i < serial.size(); ++i) {
      ASSERT_EQ(other[i].distance, serial[i].distance);
      ASSERT_EQ(other[i].triangle, serial[i].triangle);
      ASSERT_EQ(other[i].inside, serial[i].inside);
    }
  };
  same(distances(query, points, {.signedDistance = true}));
  // ε-limited batches too, whose buffers each calling thread keeps (one batch after another).
  const double epsilon = 0.02 * mesh.bounds().diagonal();
  const std::vector<PointDistance> near = oneByOne(query, points, epsilon);
  std::vector<std::vector<PointDistance>> answers(4), nearAnswers(4);
  std::vector<std::thread> callers;
  for (std::size_t c = 0; c < answers.size(); ++c)
    callers.emplace_back([&, c] {
      answers[c] = distances(query, points, {.signedDistance = true});
      nearAnswers[c] = distances(query, points, {.epsilon = epsilon});
      nearAnswers[c] = distances(query, points, {.epsilon = epsilon});
    });
  for (std::thread& caller : callers)
    caller.join();
  for (const auto& answer : answers)
    same(answer);
  for (const auto& answer : nearAnswers)
    expectSameAnswers(answer, near, "an ε-limited batch from a thread of its own");
}

TEST(PointDistance, TinyTrianglesOffAnEdgeAreNotTouched) {
  // A triangle of size s beside one of size 1 (the mesh in range), a point 1.4e-3·s off the
  // middle of its edge (0, 0, 0)–(s, s, s), inside that edge's box: the exact on-edge test's
  // products underflowed below about 1e-146, and the point was on the edge (distance 0).
  for (const double scale : {1.0, 0x1p-400, 1e-150, 1e-160, 1e-200, 1e-300}) {
    const std::vector<Vec3> v = {
        {0, 0, 0}, {scale, scale, scale}, {scale, 0, 0}, {5, 5, 5}, {6, 5, 5}, {5, 6, 5}};
    const QueryMesh mesh(Mesh(v, {{0, 1, 2}, {3, 4, 5}}));
    const Vec3 p = Vec3{0.5, 0.5, 0.5} * scale + Vec3{-1e-3, 1e-3, 0} * scale;
    // The offset is square to the edge and points away from the third corner: the edge is
    // nearest, 1e-3·s·√2 away.
    const double expected = 1e-3 * scale * std::sqrt(2.0);
    const PointDistance d = distance(mesh, p);
    EXPECT_EQ(d.triangle, 0u) << scale;
    EXPECT_NEAR(d.distance / expected, 1.0, 1e-9) << scale;
    EXPECT_NEAR(kernels::distanceAtScale(p, {v[0], v[1], v[2]}) / expected, 1.0, 1e-9) << scale;
    // And a point exactly on the edge's middle is on it.
    EXPECT_EQ(kernels::distanceAtScale(Vec3{0.5, 0.5, 0.5} * scale, {v[0], v[1], v[2]}), 0.0);
  }
}

TEST(PointDistance, APointBeyondANeedlesTipIsNotTakenForOneOverItsFace) {
  // An audit's case: a needle 1 long, its third corner 1e-12 off its middle, and a point 2.905e-11
  // beyond its tip, where the edges' lines lie within rounding of each other; a plain triangle
  // 2e-11 from the point. The face test took the point for one over the needle's face and
  // measured 1.0e-11 to its plane: the needle won, and ε = 1.5e-11 found it.
  const Vec3 a{-0x1.bf5c869a397aap-1, 0x1.ef34bc49cd08p-4, -0x1.b04c9c28fe40ep-1};
  const Vec3 b{0x1.c1dca28d6d9ep-5, 0x1.d0bf663edb8c5p-2, -0x1.5c9c4e45d99a3p-1};
  const Vec3 c{-0x1.a33ebc7161b01p-2, 0x1.26464aa8a6dfap-2, -0x1.867475376e0f4p-1};
  const Vec3 p{0x1.c1dca291536b7p-5, 0x1.d0bf663eda42bp-2, -0x1.5c9c4e45cbc5p-1};
  const Vec3 up = normalized(Vec3{0.3, -0.5, 0.8}), side = normalized(cross(up, Vec3{1, 0, 0}));
  const Vec3 o = p + up * 2e-11, other = cross(up, side);
  const QueryMesh mesh(Mesh(
      {a, b, c, o + side * 1e-3, o - side * 1e-3 + other * 1e-3, o - side * 1e-3 - other * 1e-3},
      {{0, 1, 2}, {3, 4, 5}}));
  const PointDistance nearest = distance(mesh, p);
  EXPECT_EQ(nearest.triangle, 1u);
  EXPECT_NEAR(nearest.distance, 2e-11, 1e-15);
  EXPECT_FALSE(distance(mesh, p, {.epsilon = 1.5e-11}).found());
  EXPECT_NEAR(std::sqrt(kernels::closestPointOnTriangle(p, {a, b, c}).distanceSquared), 2.905e-11,
              1e-14);
}

TEST(PointDistance, SubnormalSquaresAreRankedByTheirDistancesAtScale) {
  // Two triangles 1e-160 across, 4.5e-162 (id 0) and 4.19e-162 (id 1) from a point: their
  // squares round to the same subnormal, and the smaller id won at 7% too far.
  const double s = 1e-160, above = 4.5e-162, below = -4.19e-162;
  const QueryMesh mesh(Mesh({{0, 0, above},
                             {s, 0, above},
                             {0, s, above},
                             {0, 0, below},
                             {s, 0, below},
                             {0, s, below},
                             {5, 5, 5},
                             {6, 5, 5},
                             {5, 6, 5}},
                            {{0, 1, 2}, {3, 4, 5}, {6, 7, 8}}));
  const PointDistance d = distance(mesh, {1e-162, 1e-162, 0});
  EXPECT_EQ(d.triangle, 1u);
  EXPECT_DOUBLE_EQ(d.distance, -below);
}

TEST(PointDistance, AnUpperBoundJustBelowEpsilonKeepsEpsilonStrict) {
  // A point exactly 1 from the mesh, ε = 1: not closer than ε, with or without a bound (a bound
  // just below ε, grown past ε², found it).
  const QueryMesh mesh(Mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}));
  const std::vector<Vec3> points = {{0.25, 0.25, 1.0}};
  const PointQuery query{.epsilon = 1.0};
  EXPECT_FALSE(distances(mesh, points, query)[0].found());
  for (const double bound : {std::nextafter(1.0, 0.0), 0.5, 1.0, 2.0}) {
    std::vector<PointDistance> out(1);
    const std::vector<double> bounds = {bound};
    distances(mesh, points, bounds, query, out);
    EXPECT_FALSE(out[0].found()) << bound;
  }
}

}  // namespace
}  // namespace delta::contactdetection
