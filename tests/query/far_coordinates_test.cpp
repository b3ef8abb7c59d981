// Coordinates over the whole double range (mesh/coordinate_range.h): every query either answers
// correctly or throws delta::Error naming the point or mesh and the range; never a signal, never
// +∞ or NaN as an answer. Each reproducer of issue 21 ("Far coordinates") is here, and the tiny
// end (coordinates and gaps near 1e-300).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "delta/cache/spatial_cache.h"
#include "delta/core/error.h"
#include "delta/core/sphere.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/point_triangle.h"
#include "delta/kernels/triangle_triangle.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/measures.h"
#include "delta/mesh/primitives.h"
#include "delta/mesh/triangle_soa.h"
#include "delta/query/contacts.h"
#include "delta/query/minimum_distance.h"
#include "delta/query/point_distance.h"
#include "delta/query/sphere_contacts.h"
#include "delta/query/winding_number.h"

#include "core/expect_error.h"
#include "mesh/tetrahedron.h"
#include "query/detail/query_mesh_data.h"
#include "query/probe_points.h"

namespace delta::contactdetection {
namespace {

TEST(FarCoordinates, FarPointIsRefusedNotACrash) {
  // Issue 21: a point at 1e155 segfaulted the unlimited search (every distance overflowed, and
  // the tree's empty slots, at +∞, were not above a limit of +∞).
  const std::filesystem::path armadillo =
      std::filesystem::path(DELTA_DATA_DIR) / "meshes" / "armadillo.off";
  for (const Mesh& mesh : {primitives::granulate(1), io::load(armadillo)}) {
    const QueryMesh query(mesh);
    for (const double far : {1e155, -1e300, 1e61, std::numeric_limits<double>::max()}) {
      const std::vector<Vec3> one = {{far, 0, 0}};
      expectErrorSaying([&] { distances(query, one); }, {"point 0", "±2^200"});
      expectErrorSaying([&] { distance(query, one[0]); }, {"point 0", "±2^200"});
      expectErrorSaying([&] { distances(query, one, {.epsilon = 0.5}); }, {"point 0"});
      expectErrorSaying([&] { contacts(query, one, 0.5); }, {"point 0"});
      // Large batches (the sieve's blocks with ε, the Morton order without) name the first.
      std::vector<Vec3> many(5000, Vec3{0.1, 0.2, 0.3});
      many[4321] = {0, far, 0};
      many[4500] = {0, 0, far};
      for (const double epsilon : {0.5, std::numeric_limits<double>::infinity()})
        expectErrorSaying([&] { distances(query, many, {.epsilon = epsilon}); },
                          {"point 4321 ", "beyond"});
    }
  }
}

TEST(FarCoordinates, PointsAtTheEdgeOfTheRangeGetFiniteExactAnswers) {
  const Mesh mesh = primitives::granulate(2);
  const QueryMesh query(mesh);
  for (const Vec3& point : std::vector<Vec3>{{kLargestCoordinate, 0, 0},
                                             {-kLargestCoordinate, kLargestCoordinate, 1},
                                             {1e60, -1e60, 1e60}}) {
    const PointDistance d = distance(query, point, {.signedDistance = true});
    ASSERT_TRUE(d.found());
    EXPECT_TRUE(std::isfinite(d.distance));
    EXPECT_NEAR(d.distance, length(point), 1e-12 * length(point));
    EXPECT_FALSE(d.inside);
    // The loop over all triangles agrees.
    double best = std::numeric_limits<double>::infinity();
    std::uint32_t id = 0;
    for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
      const double squared =
          kernels::closestPointOnTriangle(point, mesh.triangle(t)).distanceSquared;
      if (squared < best) best = squared, id = t;
    }
    EXPECT_EQ(d.triangle, id);
    EXPECT_EQ(d.distance, std::sqrt(best));
  }
}

TEST(FarCoordinates, MeshesBeyondSinglePrecisionAnswerOnEveryIsa) {
  // Within the range but beyond single precision (the tree's float boxes, cylinders and leaf
  // copies round to ±∞ or the largest float there): the bounds loosen, never wrongly, on every
  // ISA's descent, and every answer is the loop over all triangles'.
  for (const double offset : {1e39, 1e50, 1e59}) {
    Mesh mesh = primitives::granulate(9, {1e40, 2e40, 3e40});
    mesh.translate({offset, -offset, 0.5 * offset});
    const QueryMesh query(mesh);
    for (const Vec3& point : test::probes(mesh, 100, 11)) {
      double best = std::numeric_limits<double>::infinity();
      std::uint32_t id = kNoTriangle;
      for (std::uint32_t t = 0; t < mesh.triangleCount(); ++t) {
        const double d = kernels::closestPointOnTriangle(point, mesh.triangle(t)).distanceSquared;
        if (d < best) best = d, id = t;
      }
      ASSERT_TRUE(std::isfinite(best));
      for (const kernels::Isa isa : kernels::supportedIsas()) {
        const detail::Nearest nearest = detail::nearestTriangle(
            query.data(), point, std::numeric_limits<double>::infinity(), isa);
        ASSERT_EQ(nearest.triangle, id) << offset << ", " << kernels::name(isa);
        ASSERT_EQ(nearest.distanceSquared, best) << offset << ", " << kernels::name(isa);
      }
    }
  }
}

TEST(FarCoordinates, MovedMeshCarriesPointsOutOfRange) {
  // `delta ib --translate 1e155,0,0`: grid vertices near the origin, the boundary far away.
  QueryMesh query(primitives::granulate(3));
  query.transform(RigidTransform::translationBy({1e155, 0, 0}));
  const std::vector<Vec3> points = {{0, 0, 0}};
  expectErrorSaying([&] { distances(query, points); },
                    {"point 0", "carried into the moved mesh's frame", "±2^200"});
  // Far from the origin but near each other: answered (in the mesh's frame).
  QueryMesh near(primitives::granulate(3));
  near.transform(RigidTransform::translationBy({1e40, 0, 0}));
  const PointDistance d = distance(near, {1e40, 0, 0});
  EXPECT_TRUE(d.found());
  EXPECT_TRUE(std::isfinite(d.distance));
}

TEST(FarCoordinates, MeshesOutOfRangeAreRefused) {
  const Mesh huge = scaled(primitives::granulate(4), 1e300);
  const Mesh tiny = scaled(primitives::granulate(4), 1e-300);
  expectErrorSaying([&] { QueryMesh{huge}; }, {"QueryMesh: the mesh", "e+299", "±2^200"});
  expectErrorSaying([&] { QueryMesh{tiny}; }, {"QueryMesh: the mesh", "2^-200"});
  // minimum_distance on meshes scaled by 1e300 crashed (NaN sort keys); now refused.
  const TriangleSoA hugeSoA(huge), tinySoA(tiny), unit(primitives::granulate(5));
  expectErrorSaying([&] { minimumDistance(hugeSoA, hugeSoA); }, {"minimumDistance", "first"});
  expectErrorSaying([&] { minimumDistance(unit, hugeSoA); }, {"minimumDistance", "second"});
  expectErrorSaying([&] { minimumDistance(unit, tinySoA); }, {"2^-200"});
  expectErrorSaying([&] { contacts(hugeSoA, unit, 0.1); }, {"contacts: the first mesh"});
  expectErrorSaying(
      [&] {
        sphereContacts(Sphere{{0, 0, 0}, 1}, hugeSoA, 0.1);
      },
      {"sphereContacts: the mesh"});
  expectErrorSaying([&] { SpatialCache{hugeSoA}; }, {"SpatialCache: the mesh"});
}

TEST(FarCoordinates, FarApartTetrahedraAreNotReportedIntersecting) {
  // Issue 21: two 3e38-sized tetrahedra 1e300 apart were "intersect, distance 0".
  const Mesh first = scaled(kTetra, 3e38);
  Mesh second = scaled(kTetra, 3e38);
  second.translate({1e300, 0, 0});
  const TriangleSoA a(first), b(second);
  expectErrorSaying([&] { minimumDistance(a, b); }, {"minimumDistance: the second mesh"});
  expectErrorSaying([&] { contacts(a, b, 1.0); }, {"contacts: the second mesh"});
  // In range they are answered: 1e50 apart.
  Mesh inRange = scaled(kTetra, 3e38);
  inRange.translate({1e50, 0, 0});
  const MinimumDistance d = minimumDistance(a, TriangleSoA(inRange));
  EXPECT_FALSE(d.intersect);
  EXPECT_NEAR(d.distance, 1e50 - 3e38, 1e-12 * 1e50);
  EXPECT_NEAR(minimumDistance(QueryMesh(first), QueryMesh(inRange)).distance, d.distance,
              1e-12 * 1e50);
}

TEST(FarCoordinates, ShortLeavesAreNotPadding) {
  // Two tetrahedra (one short leaf each) 9 apart: the prepared meshes' minimum distance was 0,
  // "intersect", at any distance: before the first pair the best is +∞, which the empty slots of
  // a short leaf (at +∞) are not above, so its padding was measured as triangles at the origin.
  Mesh moved = kTetra;
  moved.translate({10, 0, 0});
  for (const kernels::Solver solver : {kernels::Solver::Hybrid, kernels::Solver::BruteForce}) {
    const MinimumDistance d = minimumDistance(QueryMesh(kTetra), QueryMesh(moved), solver);
    EXPECT_EQ(d.distance, 9.0);
    EXPECT_FALSE(d.intersect);
    EXPECT_EQ(d.distance,
              minimumDistance(TriangleSoA(kTetra), TriangleSoA(moved), solver).distance);
  }
}

TEST(FarCoordinates, MovedQueryMeshPairsAreCheckedWhereTheyAre) {
  // `delta contact A B --translate-b 1e155,0,0` printed "minimum distance inf" with exit 0.
  const QueryMesh a(primitives::granulate(6));
  QueryMesh b(primitives::granulate(7));
  b.transform(RigidTransform::translationBy({1e155, 0, 0}));
  expectErrorSaying([&] { minimumDistance(a, b); }, {"minimumDistance: the second mesh", "1e+155"});
  expectErrorSaying([&] { contacts(a, b, 0.1); }, {"contacts: the second mesh"});
  // Both far from the origin but near each other: answered where they meet.
  QueryMesh c(primitives::granulate(6)), d(primitives::granulate(7));
  c.transform(RigidTransform::translationBy({1e150, 0, 0}));
  d.transform(RigidTransform::translationBy({1e150, 0, 0}));
  EXPECT_THROW(minimumDistance(c, d), Error);  // each where it is: beyond the range
  QueryMesh e(primitives::granulate(6)), f(primitives::granulate(7));
  e.transform(RigidTransform::translationBy({1e15, 0, 0}));
  f.transform(RigidTransform::translationBy({1e15 + 3.0, 0, 0}));
  const MinimumDistance apart = minimumDistance(e, f);
  EXPECT_TRUE(std::isfinite(apart.distance));
  EXPECT_GT(apart.distance, 0.0);
}

TEST(FarCoordinates, MovedPairsNearTheEdgeOfTheRangeAreDecidedByTheirExactBoxes) {
  // The pair check's quick test (a ball about the moved box) cannot tell near the edge of the
  // range; the moved boxes' corners decide there: within it, the pair is answered.
  const double near = 0.75 * kLargestCoordinate;
  QueryMesh a(scaled(kTetra, 0.25 * kLargestCoordinate)),
      b(scaled(kTetra, 0.25 * kLargestCoordinate));
  a.transform(RigidTransform::translationBy({near - 0.25 * kLargestCoordinate, 0, 0}));
  b.transform(RigidTransform::translationBy({near - 0.25 * kLargestCoordinate, 0, 0}));
  EXPECT_NO_THROW(contacts(a, b, 1.0));
  EXPECT_EQ(minimumDistance(a, b).distance, 0.0);
  // One ulp of the range beyond it, by the same corners: refused.
  b.setPose(RigidTransform::translationBy(
      {std::nextafter(kLargestCoordinate, 1e300) - 0.25 * kLargestCoordinate, 0, 0}));
  expectErrorSaying([&] { contacts(a, b, 1.0); }, {"contacts: the second mesh"});
  EXPECT_TRUE(boxInCoordinateRange(Aabb{}));
  EXPECT_TRUE(boxInCoordinateRange(Aabb{{-kLargestCoordinate, 0, 0}, {kLargestCoordinate, 1, 1}}));
  EXPECT_FALSE(
      boxInCoordinateRange(Aabb{{0, 0, 0}, {1, std::nextafter(kLargestCoordinate, 1e300), 1}}));
  EXPECT_FALSE(
      boxInCoordinateRange(Aabb{{0, std::numeric_limits<double>::quiet_NaN(), 0}, {1, 1, 1}}));
}

TEST(FarCoordinates, ContactsFarFromTheOriginKeepTheKernelsDistance) {
  // Found by an audit: two granulates 0.37 apart at an offset of 1e8 had contacts whose distance,
  // taken from P and Q rounded to the world's coordinates, came out 6e-8 short of the exact
  // 0.3710971948411078 that minimumDistance gave (and above 2ε where ε was just above it). The
  // oracle: the brute force on each pair moved back by the offset, exactly (Sterbenz).
  const double offset = 0x1p27;  // 1.3e8: every coordinate within [offset / 2, 2 · offset]
  const Vec3 shift{offset, offset, offset};
  const Mesh a = primitives::granulate(11).translate(shift);
  const Mesh b = primitives::granulate(12).translate(Vec3{1.7, 0.1, 0.0} + shift);
  const QueryMesh qa(a), qb(b);
  const TriangleSoA sa(a), sb(b);
  const double epsilon = 0.1;
  const auto back = [&shift](const Triangle& t) {
    return Triangle{t.a - shift, t.b - shift, t.c - shift};
  };
  for (const kernels::Solver solver : {kernels::Solver::Hybrid, kernels::Solver::BruteForce}) {
    for (const std::vector<ContactPoint>& found :
         {contacts(qa, qb, epsilon, solver), contacts(sa, sb, epsilon, solver)}) {
      ASSERT_GT(found.size(), 10u);
      std::size_t apart = 0;
      for (const ContactPoint& c : found) {
        const kernels::TriangleDistanceResult exact = kernels::triangleDistanceBruteForce(
            back(a.triangle(c.first)), back(b.triangle(c.second)));
        const double d = std::sqrt(exact.distanceSquared);
        EXPECT_NEAR(c.distance, d, 1e-15) << c.first << " " << c.second;
        EXPECT_LT(c.distance, 2.0 * epsilon);
        EXPECT_NEAR(length(c.normal), 0.5 * c.distance, 1e-15);
        if (d > 0.0) {
          ++apart;
          EXPECT_LT(length(c.direction - (exact.p - exact.q) / d), 1e-14);
          EXPECT_LT(length(c.normal - c.direction * (0.5 * c.distance)), 1e-15);
        }
      }
      EXPECT_GT(apart, 10u);
    }
  }
}

TEST(FarCoordinates, SpheresOutOfRangeNameTheirIndex) {
  const TriangleSoA wall(primitives::quad(2, 2));
  const std::vector<Sphere> spheres = {{{0, 0, 0.5}, 1}, {{1e155, 0, 0}, 1}, {{0, 0, 0}, 1e250}};
  expectErrorSaying([&] { sphereContacts(spheres, wall, 0.1); }, {"sphere 1 ", "±2^200"});
  expectErrorSaying([&] { sphereContacts(spheres[2], wall, 0.1); }, {"sphere 0 "});
}

TEST(FarCoordinates, WindingNumberRescales) {
  // Solid angles depend on directions only; their degree-3 products overflowed from 1e102 on.
  for (const double factor : {1e-300, 1e-120, 1.0, 1e120, 1e300}) {
    const TriangleSoA tetra(scaled(kTetra, factor));
    EXPECT_NEAR(windingNumber(tetra, Vec3{0.1, 0.2, 0.3} * factor), 1.0, 1e-12) << factor;
    EXPECT_NEAR(windingNumber(tetra, Vec3{-0.1, 0.2, 0.3} * factor), 0.0, 1e-12) << factor;
  }
  // Coordinates near the largest double, whose differences overflow.
  Mesh edge({{-1.5e308, -1e308, 0}, {1.5e308, -1e308, 0}, {0, 1.5e308, 0}, {0, 0, 1.5e308}},
            {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
  EXPECT_NEAR(windingNumber(TriangleSoA(edge), {0, 0, 1e307}), 1.0, 1e-12);
}

/// A tetrahedron of size `size` (1e-300 unless given) at the origin beside one of size 1 at
/// (2, 2, 2), in one mesh (its scale is 3: in range); the big one's vertices follow the small
/// one's.
Mesh tinyBesideUnitTetrahedron(double size = 1e-300) {
  const Mesh small = scaled(kTetra, size);
  Mesh big = kTetra;
  big.translate({2, 2, 2});
  std::vector<Vec3> vertices(small.vertices().begin(), small.vertices().end());
  std::vector<TriangleIndices> triangles(small.triangles().begin(), small.triangles().end());
  for (const TriangleIndices& t : big.triangles())
    triangles.push_back({t[0] + 4, t[1] + 4, t[2] + 4});
  vertices.insert(vertices.end(), big.vertices().begin(), big.vertices().end());
  return Mesh(vertices, triangles);
}

TEST(FarCoordinates, TinyGapsAreNotReportedZero) {
  // A tetrahedron of size 1e-300 beside one of size 1 (the mesh's scale is 3: in range). A
  // point 1e-301 off the small one's face has a squared distance that underflows to 0 (it was
  // reported on the surface); its distance is 1e-301, and its side is decided.
  const QueryMesh query(tinyBesideUnitTetrahedron());
  ASSERT_TRUE(query.closed());
  const PointDistance outside =
      distance(query, {0.25e-300, 0.25e-300, -1e-301}, {.signedDistance = true});
  EXPECT_EQ(outside.distance, 1e-301);
  EXPECT_EQ(outside.triangle, 0u);
  EXPECT_FALSE(outside.inside);
  const PointDistance inside =
      distance(query, {0.25e-300, 0.25e-300, 1e-301}, {.signedDistance = true});
  EXPECT_EQ(inside.distance, 1e-301);
  EXPECT_TRUE(inside.inside);
  const PointDistance on = distance(query, {0.25e-300, 0.25e-300, 0}, {.signedDistance = true});
  EXPECT_EQ(on.distance, 0.0);
  EXPECT_FALSE(on.inside);
  // The batch (grid sieve with ε, and without) agrees.
  std::vector<Vec3> many(3000, Vec3{0.25e-300, 0.25e-300, -1e-301});
  for (const double epsilon : {1e-3, std::numeric_limits<double>::infinity()})
    EXPECT_EQ(distances(query, many, {.epsilon = epsilon})[2999].distance, 1e-301);
  // The kernel's distance at scale: bit for bit √distanceSquared where nothing underflows.
  const Triangle unit{{0.1, 0.2, 0.3}, {1.7, -0.3, 0.9}, {0.4, 1.1, -0.2}};
  for (const Vec3& p : std::vector<Vec3>{{0.5, 0.25, 3.0}, {-2, 0.3, 0.1}, {0.4, 0.3, 0.2}})
    EXPECT_EQ(kernels::distanceAtScale(p, unit),
              std::sqrt(kernels::closestPointOnTriangle(p, unit).distanceSquared));
  EXPECT_EQ(kernels::distanceAtScale(unit.b, unit), 0.0);
}

TEST(FarCoordinates, TinyTrianglesAreSolvedAtTheirOwnScale) {
  // A triangle less than about 2⁻²⁴⁰ across has a normal whose square (degree 4) underflows: it
  // was taken for flat, and a point over its face measured to its edges (1e-100: 2.7e-101 for
  // 1e-101), the wrong triangle could win, the closest point was the point itself where the
  // square underflowed, and below 2⁻¹⁰²² (subnormal) the distance came out +∞. The point queries
  // now solve such a triangle scaled up by a power of two, on every ISA alike.
  for (const double size : {1e-70, 1e-100, 1e-140, 1e-200, 1e-300, 1e-310}) {
    const QueryMesh query(tinyBesideUnitTetrahedron(size));
    const Vec3 point{size / 4, size / 4, -size / 10};  // over face 0 (z = 0, outward −z)
    const double ulp = std::nextafter(size, 1.0) - size;
    const double tolerance = 8 * ulp + 2 * std::numeric_limits<double>::denorm_min();
    const PointDistance answer = distance(query, point, {.signedDistance = true});
    EXPECT_EQ(answer.triangle, 0u) << size;
    EXPECT_NEAR(answer.distance, size / 10, tolerance) << size;
    EXPECT_NEAR(answer.closest.x, size / 4, tolerance) << size;
    EXPECT_NEAR(answer.closest.y, size / 4, tolerance) << size;
    EXPECT_NEAR(answer.closest.z, 0.0, tolerance) << size;
    EXPECT_FALSE(answer.inside) << size;
    EXPECT_TRUE(distance(query, {size / 4, size / 4, size / 10}, {.signedDistance = true}).inside)
        << size;
    // Every ISA's descent and exact lanes give the scalar kernel's bits.
    const detail::Nearest scalar = detail::nearestTriangle(
        query.data(), point, std::numeric_limits<double>::infinity(), kernels::Isa::Scalar);
    for (const kernels::Isa isa : kernels::supportedIsas()) {
      const detail::Nearest nearest = detail::nearestTriangle(
          query.data(), point, std::numeric_limits<double>::infinity(), isa);
      EXPECT_EQ(nearest.triangle, scalar.triangle) << size << ", " << kernels::name(isa);
      EXPECT_EQ(nearest.distanceSquared, scalar.distanceSquared)
          << size << ", " << kernels::name(isa);
    }
    // The batch (the grid's sieve with ε, and without) agrees.
    const std::vector<Vec3> many(3000, point);
    for (const double epsilon : {1e-3, std::numeric_limits<double>::infinity()})
      EXPECT_EQ(distances(query, many, {.epsilon = epsilon})[2999].distance, answer.distance)
          << size;
    // The mesh–mesh kernels would still take it for flat: refused, saying what to do.
    if (size < kSmallestTriangleExtent)
      expectErrorSaying([&] { static_cast<void>(contacts(query, query, 1e-3)); },
                        {"contacts: the first mesh's triangle 0 spans only", "scale the mesh up"});
  }
}

TEST(FarCoordinates, AnEpsilonWhoseSquareUnderflowsStillFindsWhatIsCloser) {
  // ε² below about 1e-324 is 0, and d² < ε² missed even a point on the mesh (distance 0); the
  // search now runs with a limit that does not underflow and cuts its answers at ε by their
  // distances at scale. The same tetrahedra as above: a point 1e-301 off the small one's face.
  const QueryMesh query(tinyBesideUnitTetrahedron());
  const Vec3 off{0.25e-300, 0.25e-300, -1e-301}, on{0.25e-300, 0.25e-300, 0},
      vertex = query.mesh().vertices()[4];                                // the big one's first
  for (const std::size_t copies : {std::size_t{1}, std::size_t{3000}}) {  // one point, the sieve
    for (const double epsilon : {1e-163, 1e-200, 1e-301, std::nextafter(1e-301, 1.0), 5e-324}) {
      std::vector<Vec3> points(copies, off);
      points.push_back(on);
      points.push_back(vertex);
      const std::vector<PointDistance> found = distances(query, points, {.epsilon = epsilon});
      // Strictly closer than ε: 1e-301 is not closer than 1e-301.
      EXPECT_EQ(found[0].found(), 1e-301 < epsilon) << epsilon;
      if (found[0].found()) {
        EXPECT_EQ(found[0].distance, 1e-301);
      }
      EXPECT_TRUE(found[copies].found()) << epsilon;
      EXPECT_EQ(found[copies].distance, 0.0);
      EXPECT_TRUE(found[copies + 1].found()) << epsilon;
      EXPECT_EQ(found[copies + 1].distance, 0.0);
    }
  }
  // Points–mesh contacts take the same path.
  EXPECT_EQ(contacts(query, std::vector<Vec3>{vertex, off}, 1e-200).size(), 2u);
  // Mesh–mesh contacts cannot tell pairs apart there: such an ε is refused, with the reason.
  const QueryMesh box(primitives::box());
  expectErrorSaying([&] { (void)contacts(box, box, 1e-163); }, {"below 2^-481"});
  EXPECT_FALSE(contacts(box, box, 0x1p-481).empty());
}

}  // namespace
}  // namespace delta::contactdetection
