// How the parts of closed meshes nest (query/part_nesting.h): parts nested as a solid's
// boundary (cavities, islands, an inside-out mesh as a whole) pass; an inside-out part, a shell
// inside a shell of the same orientation, parts touching at a vertex, a flat part, a lattice of
// translated parts; the signs of every query against the exact winding number over all
// triangles, and the refusals of pseudonormal signs, the overlap query and particle shapes.

#include "delta/query/part_nesting.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/dem/particle_shape.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/primitives.h"
#include "delta/query/contacts.h"
#include "delta/query/overlap.h"
#include "delta/query/point_distance.h"
#include "delta/query/self_intersections.h"
#include "delta/query/winding_number.h"

#include "query/detail/query_mesh_data.h"

namespace delta {
namespace {

using contactdetection::PointDistance;
using contactdetection::PointQuery;
using contactdetection::Sign;

/// A part of a joined mesh: `mesh`, its triangles reversed where `inverted`.
struct Part {
  Mesh mesh;
  bool inverted = false;
};

/// The parts as one mesh, their vertices and triangles in turn.
Mesh joined(const std::vector<Part>& parts) {
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  for (const Part& part : parts) {
    const auto offset = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), part.mesh.vertices().begin(), part.mesh.vertices().end());
    for (const TriangleIndices& t : part.mesh.triangles())
      triangles.push_back(part.inverted
                              ? TriangleIndices{t[0] + offset, t[2] + offset, t[1] + offset}
                              : TriangleIndices{t[0] + offset, t[1] + offset, t[2] + offset});
  }
  return Mesh(std::move(vertices), std::move(triangles));
}

/// Random points in the mesh's box grown by a quarter, with those within 1e-6 of the diagonal
/// of the surface left out (the exact winding number's solid angles are sure off it).
std::vector<Vec3> probes(const Mesh& mesh, std::size_t count) {
  const QueryMesh query(mesh);
  const Aabb box = mesh.bounds();
  const Vec3 lower = box.lower - box.extent() * 0.25, extent = box.extent() * 1.5;
  std::mt19937_64 random(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<Vec3> points;
  while (points.size() < count) {
    const Vec3 p =
        lower + Vec3{unit(random) * extent.x, unit(random) * extent.y, unit(random) * extent.z};
    if (contactdetection::distance(query, p).distance > 1e-6 * box.diagonal()) points.push_back(p);
  }
  return points;
}

PointQuery signedBy(Sign sign) {
  PointQuery query;
  query.signedDistance = true;
  query.sign = sign;
  return query;
}

/// Every probe's winding sign is the exact winding number's (times the orientation, above ½),
/// and, where the mesh bounds a solid, so is its pseudonormal sign; returns how many were inside.
std::size_t expectWindingSigns(const Mesh& mesh) {
  const QueryMesh query(mesh);
  const TriangleSoA triangles = flatten(mesh);
  const double orientation = query.data().orientation;
  const std::vector<Vec3> points = probes(mesh, 600);
  const std::vector<PointDistance> winding = distances(query, points, signedBy(Sign::winding));
  std::vector<PointDistance> pseudonormal;
  if (boundsSolid(query)) pseudonormal = distances(query, points, signedBy(Sign::pseudonormal));
  std::size_t inside = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const bool expected = windingNumber(triangles, points[i]) * orientation > 0.5;
    inside += expected;
    EXPECT_EQ(winding[i].inside, expected) << toString(points[i]);
    if (!pseudonormal.empty()) {
      EXPECT_EQ(pseudonormal[i].inside, expected) << toString(points[i]);
    }
  }
  return inside;
}

TEST(PartNesting, PartsNestedAsASolidsBoundaryPass) {
  const Mesh ball = primitives::icosphere(2);
  const std::vector<std::vector<Part>> solids = {
      {{ball}, {primitives::icosphere(2, 0.5, {3, 0.2, 0.1})}},  // two apart
      {{primitives::icosphere(2, 2.0)},
       {primitives::box({1, 1.2, 0.8}, {0.3, 0.1, 0}), true}},  // a cavity
      {{primitives::icosphere(2, 3.0)},
       {primitives::icosphere(2, 2.0, {0.1, 0, 0}), true},
       {primitives::box({1, 1, 1}, {0.2, 0.3, 0.1})}},  // an island in a cavity
      {{primitives::icosphere(2, 2.0), true}, {primitives::granulate(3, {0.5, 0.6, 0.7})}},
  };
  for (const std::vector<Part>& parts : solids) {
    const Mesh mesh = joined(parts);
    const QueryMesh query(mesh);
    ASSERT_TRUE(query.closed());
    ASSERT_FALSE(selfIntersections(query).any());
    const PartNesting& found = partNesting(query);
    EXPECT_EQ(found.parts, parts.size());
    EXPECT_EQ(found.misoriented, 0u);
    EXPECT_EQ(found.undecided, 0u);
    EXPECT_TRUE(found.misorientedTriangles.empty());
    EXPECT_TRUE(boundsSolid(query));
    EXPECT_GT(expectWindingSigns(mesh), 0u);
  }
}

TEST(PartNesting, AnInsideOutPartAndAShellInASameShellAreFoundAndSignedByWindingNumber) {
  const Mesh ball = primitives::icosphere(2);  // 320 triangles
  struct Case {
    std::vector<Part> parts;
    std::uint32_t misoriented;  ///< the smallest triangle id of the misoriented part
  };
  const std::vector<Case> cases = {
      {{{ball}, {primitives::icosphere(2, 0.5, {3, 0.2, 0.1}), true}}, 320},  // inside-out
      {{{primitives::icosphere(2, 2.0)}, {primitives::icosphere(2, 1.0, {0.1, 0, 0})}}, 320},
      // the cavity's wall outside the solid, listed first
      {{{primitives::box({1, 1, 1}, {4, 0, 0}), true}, {primitives::icosphere(2, 2.0)}}, 0},
  };
  for (const Case& c : cases) {
    const Mesh mesh = joined(c.parts);
    const QueryMesh query(mesh);
    ASSERT_TRUE(query.closed());
    ASSERT_FALSE(selfIntersections(query).any());
    const PartNesting& found = partNesting(query);
    EXPECT_EQ(found.parts, 2u);
    EXPECT_EQ(found.misoriented, 1u);
    EXPECT_EQ(found.undecided, 0u);
    EXPECT_EQ(found.misorientedTriangles, std::vector<std::uint32_t>{c.misoriented});
    EXPECT_FALSE(boundsSolid(query));
    EXPECT_GT(expectWindingSigns(mesh), 0u);
    // Pseudonormal signs refuse it, naming the part and the winding sign.
    try {
      (void)contactdetection::distance(query, {0, 0, 0}, signedBy(Sign::pseudonormal));
      ADD_FAILURE() << "pseudonormal signs took a misoriented part";
    } catch (const Error& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find("1 of its 2 parts is oriented against"), std::string::npos) << message;
      EXPECT_NE(message.find("triangle " + std::to_string(c.misoriented)), std::string::npos)
          << message;
      EXPECT_NE(message.find("Sign::winding"), std::string::npos) << message;
    }
    // So do the overlap query and particle shapes, whose volumes it would get wrong.
    EXPECT_THROW((void)contactdetection::overlap(query, QueryMesh(ball)), Error);
    EXPECT_THROW(dem::ParticleShape(mesh, 1.0), Error);
  }
}

TEST(PartNesting, PointContactsMarkOverlapsByWindingNumber) {
  // A ball with a same-orientation shell inside it: between the shells the winding number is 1,
  // inside the inner one 2; the pseudonormals of the inner shell called the gap outside.
  const Mesh mesh = joined({{primitives::icosphere(3, 2.0)}, {primitives::icosphere(3, 1.0)}});
  const QueryMesh query(mesh);
  const TriangleSoA triangles = flatten(mesh);
  std::vector<Vec3> points;
  for (const double r : {0.8, 0.95, 1.05, 1.2, 1.9, 2.1})
    for (const Vec3& d : {Vec3{1, 0, 0}, Vec3{0, -0.6, 0.8}, Vec3{0.36, 0.48, -0.8}})
      points.push_back(d * r);
  const std::vector<ContactPoint> found = contactdetection::contacts(query, points, 0.3);
  ASSERT_EQ(found.size(), points.size());
  for (const ContactPoint& contact : found)
    EXPECT_EQ(contact.overlap, windingNumber(triangles, points[contact.first]) > 0.5)
        << toString(points[contact.first]);
}

TEST(PartNesting, PartsTouchingAtAVertexArePinched) {
  // Two tetrahedra sharing one vertex (by index): one piece by vertices, two parts by edges, and
  // the shared vertex's triangles make two fans.
  const std::vector<Vec3> vertices = {{0, 0, 0},  {1, 0, 0},  {0, 1, 0}, {0, 0, 1},
                                      {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  const std::vector<TriangleIndices> outward = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  const auto second = [](bool inverted) {
    // The tetrahedron (0, 4, 5, 6), outward unless inverted.
    std::vector<TriangleIndices> t = {{0, 4, 5}, {0, 6, 4}, {0, 5, 6}, {4, 6, 5}};
    if (inverted)
      for (TriangleIndices& f : t)
        std::swap(f[1], f[2]);
    return t;
  };
  for (const bool inverted : {false, true}) {
    std::vector<TriangleIndices> triangles = outward;
    for (const TriangleIndices& t : second(inverted))
      triangles.push_back(t);
    const QueryMesh query(Mesh(vertices, triangles));
    ASSERT_TRUE(query.closed());
    const PartNesting& found = partNesting(query);
    EXPECT_EQ(found.parts, 2u);
    EXPECT_EQ(found.misoriented, inverted ? 1u : 0u);
    EXPECT_EQ(found.pinched, 1u);
    EXPECT_EQ(found.pinchedTriangle, 0u);
    EXPECT_EQ(found.undecided, 0u);
    EXPECT_FALSE(boundsSolid(query));
  }
  // The same with the shared vertex copied: joined by coordinates only, both copies pinched.
  std::vector<Vec3> copied = vertices;
  copied.push_back({0, 0, 0});
  std::vector<TriangleIndices> triangles = outward;
  for (TriangleIndices t : second(false)) {
    for (std::uint32_t& v : t)
      if (v == 0) v = 7;
    triangles.push_back(t);
  }
  const QueryMesh query(Mesh(copied, triangles));
  EXPECT_EQ(partNesting(query).misoriented, 0u);
  EXPECT_EQ(partNesting(query).pinched, 2u);
  const std::string text = describePartNesting(partNesting(query));
  EXPECT_NE(text.find("meets itself at 2 vertices"), std::string::npos) << text;
  // The overlap query refuses it (it walked the crossed part across edges, and the part joined
  // at the vertex was lost: a volume of 0.125 for 1.125).
  EXPECT_THROW((void)contactdetection::overlap(query, QueryMesh(primitives::box({2, 2, 2}))),
               Error);
}

TEST(PartNesting, TouchingPartsAreSignedByWindingNumber) {
  // A 3 × 3 × 3 block of unit cubes, all outward, sharing their faces by coordinates (a voxel
  // block); the same with the middle cube inside out; a ball with a tetrahedron inscribed on
  // its vertices; a ball stored twice. Each is closed and crosses itself nowhere by the
  // self-intersection count, which does not count triangles that share a vertex.
  const auto block = [](bool middleInverted) {
    std::vector<Part> parts;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k)
          parts.push_back({primitives::box({1, 1, 1}, {i + 0.5, j + 0.5, k + 0.5}),
                           middleInverted && i == 1 && j == 1 && k == 1});
    return joined(parts);
  };
  const Mesh ball = primitives::icosphere(1, 2.0);
  const Mesh tetrahedron(
      {ball.vertices()[0], ball.vertices()[3], ball.vertices()[7], ball.vertices()[10]},
      {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}});
  const bool outward = signedVolume(tetrahedron) > 0.0;
  for (const Mesh& mesh : {block(false), block(true), joined({{ball}, {tetrahedron, !outward}}),
                           joined({{ball}, {ball}})}) {
    const QueryMesh query(mesh);
    ASSERT_TRUE(query.closed());
    ASSERT_FALSE(selfIntersections(query).any());
    EXPECT_GT(partNesting(query).pinched, 0u);
    EXPECT_FALSE(boundsSolid(query));
    EXPECT_THROW((void)contactdetection::distance(query, {0, 0, 0}, signedBy(Sign::pseudonormal)),
                 Error);
    EXPECT_THROW(dem::ParticleShape(mesh, 1.0), Error);
    expectWindingSigns(mesh);
  }
  // Points inside the block, 0.15–0.17 from faces its cubes share: inside (the build before
  // part nesting called both outside, by either sign).
  const QueryMesh voxels(block(false));
  for (const Vec3& p :
       {Vec3{2.67972934, 1.17311689, 1.67853728}, Vec3{1.3325924, 0.18255011, 1.15120675}})
    EXPECT_TRUE(contactdetection::distance(voxels, p, signedBy(Sign::winding)).inside);
  EXPECT_FALSE(
      contactdetection::distance(QueryMesh(block(true)), {1.5, 1.5, 1.4}, signedBy(Sign::winding))
          .inside);
}

TEST(PartNesting, AThinInsideOutPartIsPlacedByItsExactVolume) {
  // A square prism 1 × t × t in 1,000 segments beside a unit cube, inside out: its volume lies
  // below the float sum's rounding bound, and the exact sum decides it.
  const auto needle = [](int segments, double t) {
    std::vector<Vec3> vertices;
    std::vector<TriangleIndices> triangles;
    const double h = t / 2;
    const Vec3 ring[4] = {{0, -h, -h}, {0, h, -h}, {0, h, h}, {0, -h, h}};
    for (int i = 0; i <= segments; ++i)
      for (const Vec3& r : ring)
        vertices.push_back({-0.5 + static_cast<double>(i) / segments, r.y, r.z});
    for (std::uint32_t i = 0; i < static_cast<std::uint32_t>(segments); ++i)
      for (std::uint32_t j = 0; j < 4; ++j) {
        const std::uint32_t a = 4 * i + j, b = 4 * i + (j + 1) % 4;
        triangles.push_back({a, b, a + 4});
        triangles.push_back({b, b + 4, a + 4});
      }
    const auto e = static_cast<std::uint32_t>(4 * segments);
    triangles.insert(triangles.end(), {{0, 2, 1}, {0, 3, 2}, {e, e + 1, e + 2}, {e, e + 2, e + 3}});
    return Mesh(vertices, triangles);
  };
  for (const double t : {1e-5, 1e-6}) {
    const Mesh thin = needle(1000, t);
    ASSERT_GT(signedVolume(thin), 0.0);
    const Mesh mesh = joined({{primitives::box({1, 1, 1}, {0, 3, 0})}, {thin, true}});
    const QueryMesh query(mesh);
    EXPECT_EQ(partNesting(query).misoriented, 1u) << t;
    EXPECT_FALSE(boundsSolid(query));
    // Just off the needle, where its winding number is 0: outside.
    for (const double x : {-0.3, 0.0, 0.21})
      EXPECT_FALSE(contactdetection::distance(query, {x, t, 0}, signedBy(Sign::winding)).inside);
  }
}

TEST(PartNesting, APartNoExactRayPlacesIsUndecidedAndBoundsNoSolid) {
  // A box reaching down to 1e-300 (below the exact predicates' 2^-250) around a ball of the same
  // orientation: neither the box's volume nor a ray from it is exact.
  const Mesh mesh = joined({{Mesh({{1e-300, 1e-300, 1e-300},
                                   {4, 1e-300, 1e-300},
                                   {1e-300, 4, 1e-300},
                                   {4, 4, 1e-300},
                                   {1e-300, 1e-300, 4},
                                   {4, 1e-300, 4},
                                   {1e-300, 4, 4},
                                   {4, 4, 4}},
                                  {{0, 2, 3},
                                   {0, 3, 1},
                                   {4, 5, 7},
                                   {4, 7, 6},
                                   {0, 1, 5},
                                   {0, 5, 4},
                                   {2, 6, 7},
                                   {2, 7, 3},
                                   {0, 4, 6},
                                   {0, 6, 2},
                                   {1, 3, 7},
                                   {1, 7, 5}})},
                            {primitives::icosphere(1, 1.0, {2, 2, 2})}});
  const QueryMesh query(mesh);
  ASSERT_TRUE(query.closed());
  EXPECT_GT(partNesting(query).undecided, 0u);
  EXPECT_FALSE(boundsSolid(query));
  const std::string text = describePartNesting(partNesting(query));
  EXPECT_NE(text.find("not placed exactly"), std::string::npos) << text;
  // The winding number signs it: 2 inside the ball, 1 around it.
  EXPECT_TRUE(contactdetection::distance(query, {2, 2, 2}, signedBy(Sign::winding)).inside);
  EXPECT_TRUE(contactdetection::distance(query, {0.5, 0.5, 0.5}, signedBy(Sign::winding)).inside);
}

TEST(PartNesting, AFlatPartBoundsNoSolidAndAnOpenMeshHasNoParts) {
  // A triangle covered twice, back to back (closed, no volume), beside a ball: its faces'
  // pseudonormals tie, and a point 0.1 above it was inside (either sign), where the winding
  // number is 0.
  const Mesh ball = primitives::icosphere(1);
  std::vector<Vec3> vertices(ball.vertices().begin(), ball.vertices().end());
  std::vector<TriangleIndices> triangles(ball.triangles().begin(), ball.triangles().end());
  const auto v = static_cast<std::uint32_t>(vertices.size());
  vertices.insert(vertices.end(), {{3, 0, 0}, {4, 0, 0}, {3, 1, 0}});
  triangles.push_back({v, v + 1, v + 2});
  triangles.push_back({v, v + 2, v + 1});
  const QueryMesh flat(Mesh(vertices, triangles));
  ASSERT_TRUE(flat.closed());
  EXPECT_EQ(partNesting(flat).parts, 2u);
  EXPECT_EQ(partNesting(flat).misoriented, 0u);
  EXPECT_EQ(partNesting(flat).flat, 1u);
  EXPECT_FALSE(boundsSolid(flat));
  const std::string text = describePartNesting(partNesting(flat));
  EXPECT_NE(text.find("1 of its 2 parts is flat"), std::string::npos) << text;
  for (const double side : {0.1, -0.1}) {
    const Vec3 p{3.25, 0.25, side};
    EXPECT_FALSE(contactdetection::distance(flat, p, signedBy(Sign::winding)).inside) << side;
    EXPECT_THROW((void)contactdetection::distance(flat, p, signedBy(Sign::pseudonormal)), Error);
  }
  // Flat or not is decided exactly: three exactly collinear points (whose rounded cross product
  // is not 0) stored twice enclose nothing and have no area, and pass; a needle 2⁻¹⁰⁰ wide (whose
  // rounded cross product is 0) stored twice is flat.
  const Mesh box = primitives::box();
  const auto withDoubled = [&box](const Vec3& a, const Vec3& b, const Vec3& c) {
    return joined({{box}, {Mesh({a, b, c}, {{0, 1, 2}, {0, 2, 1}})}});
  };
  const Vec3 first{0x1.10c67fd361120p+2, 0x1.9929bfbd119b0p+2, 0x1.54f81fc839568p+2};
  const Vec3 second{1236, 1854, 1545}, third{47132, 70698, 58915};
  ASSERT_NE(lengthSquared(cross(second - first, third - first)), 0.0);
  const QueryMesh collinear(withDoubled(first, second, third));
  EXPECT_EQ(partNesting(collinear).flat, 0u);
  EXPECT_TRUE(boundsSolid(collinear));
  const Vec3 tip{-4, -4, 10}, b{0, 0x1p-50, 10}, c{0x1p-50, 0x1p-49, 10};
  ASSERT_EQ(lengthSquared(cross(b - tip, c - tip)), 0.0);
  const QueryMesh needle(withDoubled(tip, b, c));
  EXPECT_EQ(partNesting(needle).flat, 1u);
  EXPECT_FALSE(boundsSolid(needle));
  // Alone, it is flat too.
  const QueryMesh alone(Mesh({{3, 0, 0}, {4, 0, 0}, {3, 1, 0}}, {{0, 1, 2}, {0, 2, 1}}));
  ASSERT_TRUE(alone.closed());
  EXPECT_EQ(partNesting(alone).flat, 1u);
  EXPECT_FALSE(boundsSolid(alone));

  const QueryMesh open(primitives::quad());
  EXPECT_EQ(partNesting(open).parts, 0u);
  EXPECT_FALSE(boundsSolid(open));
}

TEST(PartNesting, ALatticeOfTranslatedPartsWithOneInverted) {
  // 4 × 4 × 4 translated copies of one ball: every axis ray from a vertex meets the copies of
  // that vertex, and only the skewed rays place a part.
  const Mesh ball = primitives::icosphere(1, 0.4);  // 80 triangles
  std::vector<Part> parts;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 4; ++k) {
        Mesh copy = ball;
        copy.translate({1.0 * i, 1.0 * j, 1.0 * k});
        parts.push_back({copy, parts.size() == 37});
      }
  const Mesh mesh = joined(parts);
  const QueryMesh query(mesh);
  const PartNesting& found = partNesting(query);
  EXPECT_EQ(found.parts, 64u);
  EXPECT_EQ(found.misoriented, 1u);
  EXPECT_EQ(found.undecided, 0u);
  EXPECT_EQ(found.misorientedTriangles, std::vector<std::uint32_t>{37 * 80});
  const std::string text = describePartNesting(found);
  EXPECT_NE(text.find("1 of its 64 parts is oriented against"), std::string::npos) << text;
  EXPECT_NE(text.find("triangle 2960"), std::string::npos) << text;
  EXPECT_EQ(describePartNesting(partNesting(QueryMesh(ball))), "");
  // The winding number inside the inverted ball is −1, and 0 just outside it: outside.
  const PointQuery winding = signedBy(Sign::winding);
  const Vec3 centre{2, 1, 1};  // part 37's
  EXPECT_FALSE(contactdetection::distance(query, centre, winding).inside);
  EXPECT_FALSE(contactdetection::distance(query, centre + Vec3{0.45, 0, 0}, winding).inside);
  EXPECT_TRUE(contactdetection::distance(query, Vec3{1, 1, 1}, winding).inside);
}

}  // namespace
}  // namespace delta
