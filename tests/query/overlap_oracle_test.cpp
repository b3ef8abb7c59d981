// The overlap of two closed meshes (query/overlap.h, issue 24) against an exact oracle: CGAL's
// corefinement (Polygon_mesh_processing::corefine_and_compute_intersection on exact rationals)
// of the very doubles overlap() meets, the world-frame meshes (QueryMesh::mesh() moved by its
// pose as Mesh::transform moves it). The volume of A ∩ B must agree within 1e-12·L³, L the
// longest side of the intersection of the two world boxes, and so must the number of regions
// (the connected pieces of the result with positive volume). Cases: random rigid poses of CGAL's
// small clean meshes and of Δ's primitives, some 1e6 from the origin; shallow contacts of
// granulates (overlaps 1e-2 to 1e-6 of their radius deep); and the degenerate ones
// (nested, disjoint, touching faces, edges and vertices, coplanar faces, shared vertices and
// edges, edge-on-edge crossings, identical meshes), each also 1e6 from the origin. Without the
// oracle: the area vectors of ∂A in B and ∂B in A cancel, overlap(a, b) and overlap(b, a) agree,
// the curves are closed and curves off changes no integral.

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/connected_components.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Surface_mesh.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/rotation.h"
#include "delta/io/mesh_io.h"
#include "delta/mesh/mesh.h"
#include "delta/mesh/primitives.h"
#include "delta/query/minimum_distance.h"
#include "delta/query/overlap.h"
#include "delta/query/query_mesh.h"
#include "delta/query/self_intersections.h"

#include "kernels/triangle_pairs.h"

namespace delta::contactdetection {
namespace {

namespace fs = std::filesystem;
namespace PMP = CGAL::Polygon_mesh_processing;

using ExactKernel = CGAL::Exact_predicates_exact_constructions_kernel;
using RationalKernel = ExactKernel::Exact_kernel;  // what exact() gives: plain rationals
using SurfaceMesh = CGAL::Surface_mesh<ExactKernel::Point_3>;

const fs::path kMeshes = fs::path(DELTA_DATA_DIR) / "meshes";

/// The tolerance of every volume, in L³.
constexpr double kVolumeTolerance = 1e-12;
/// Of the area vectors' sum, in L² (each a sum of rounded triangle integrals).
constexpr double kAreaTolerance = 1e-10;
/// Of the centroid times the volume, in L⁴.
constexpr double kMomentTolerance = 1e-11;

/// The largest |V − V_exact| / L³ met so far, near the origin and 1e6 away from it (for the
/// summary line each test prints).
double worstVolumeError[2] = {0.0, 0.0};
std::size_t casesCompared = 0, casesOverlapping = 0, casesWithSeveralRegions = 0;

/// The mesh where overlap() sees it: the prepared mesh moved by the pose.
Mesh worldMesh(const QueryMesh& mesh) {
  Mesh moved = mesh.mesh();
  moved.transform(mesh.pose());
  return moved;
}

/// The longest side of the intersection of the two boxes; 0 where they do not meet.
double commonExtent(const Aabb& first, const Aabb& second) {
  double longest = 0.0;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const double side = std::min(first.upper[axis], second.upper[axis]) -
                        std::max(first.lower[axis], second.lower[axis]);
    if (side < 0.0) return 0.0;
    longest = std::max(longest, side);
  }
  return longest;
}

SurfaceMesh toSurfaceMesh(const Mesh& mesh) {
  SurfaceMesh surface;
  std::vector<SurfaceMesh::Vertex_index> vertices;
  vertices.reserve(mesh.vertexCount());
  for (const Vec3& v : mesh.vertices())
    vertices.push_back(surface.add_vertex({v.x, v.y, v.z}));
  for (const TriangleIndices& t : mesh.triangles())
    if (surface.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]) ==
        SurfaceMesh::null_face())
      ADD_FAILURE() << "CGAL refuses a triangle (non-manifold input)";
  return surface;
}

struct ExactRegion {
  double volume = 0.0;
  Vec3 centroid;
};

/// CGAL's A ∩ B: its connected components (faces joined by edges), largest volume first.
struct ExactOverlap {
  bool corefined = false;  ///< false where CGAL could not make the result (non-manifold)
  double volume = 0.0;
  Vec3 centroid;
  std::vector<ExactRegion> regions;
};

/// Each face's signed volume against `origin` (near the result: small terms that hardly cancel)
/// exactly, in rationals, rounded once and summed in double: accurate to about 1e-16 of the sum
/// of their magnitudes, far inside the tolerance. (CGAL::to_double of a lazy exact sum promises
/// only a relative 1e-5, and an exact sum's denominators grow with every face.)
ExactOverlap exactOverlap(const Mesh& first, const Mesh& second, const Vec3& origin) {
  SurfaceMesh a = toSurfaceMesh(first), b = toSurfaceMesh(second), result;
  ExactOverlap exact;
  exact.corefined = PMP::corefine_and_compute_intersection(a, b, result);
  if (!exact.corefined || result.number_of_faces() == 0) return exact;

  const RationalKernel::Point_3 center(origin.x, origin.y, origin.z);
  std::vector<RationalKernel::Vector_3> offsets(result.number_of_vertices());
  std::vector<Vec3> approximate(result.number_of_vertices());
  for (const SurfaceMesh::Vertex_index v : result.vertices()) {
    offsets[v] = CGAL::exact(result.point(v)) - center;
    approximate[v] = {CGAL::to_double(offsets[v].x()), CGAL::to_double(offsets[v].y()),
                      CGAL::to_double(offsets[v].z())};
  }
  auto component = result.add_property_map<SurfaceMesh::Face_index, std::size_t>("f:piece").first;
  const std::size_t pieces = PMP::connected_components(result, component);
  std::vector<double> sixVolumes(pieces, 0.0);
  std::vector<Vec3> moments(pieces);  // 24·∫x dV about the origin
  for (const SurfaceMesh::Face_index f : result.faces()) {
    std::size_t corners[3], k = 0;
    for (const SurfaceMesh::Vertex_index v : CGAL::vertices_around_face(result.halfedge(f), result))
      if (k++ < 3) corners[k - 1] = v;
    EXPECT_EQ(k, 3u) << "CGAL's result has a face that is not a triangle";
    const double sixVolume = CGAL::to_double(
        CGAL::determinant(offsets[corners[0]], offsets[corners[1]], offsets[corners[2]]));
    sixVolumes[component[f]] += sixVolume;
    moments[component[f]] +=
        (approximate[corners[0]] + approximate[corners[1]] + approximate[corners[2]]) * sixVolume;
  }
  Vec3 moment;
  for (std::size_t piece = 0; piece < pieces; ++piece) {
    const double volume = sixVolumes[piece] / 6.0;
    exact.volume += volume;
    moment += moments[piece];
    if (volume > 0.0)
      exact.regions.push_back({volume, origin + moments[piece] / (4.0 * sixVolumes[piece])});
  }
  if (exact.volume > 0.0) exact.centroid = origin + moment / (24.0 * exact.volume);
  std::sort(exact.regions.begin(), exact.regions.end(),
            [](const ExactRegion& s, const ExactRegion& t) { return s.volume > t.volume; });
  return exact;
}

std::string format(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.17g", value);
  return text;
}

std::string format(const Vec3& v) {
  char text[96];
  std::snprintf(text, sizeof text, "{%.17g, %.17g, %.17g}", v.x, v.y, v.z);
  return text;
}

/// A pose as code that sets it again.
std::string describe(const RigidTransform& pose) {
  const Quaternion& q = pose.rotation;
  const Vec3& t = pose.translation;
  char text[256];
  std::snprintf(text, sizeof text,
                "RigidTransform{Quaternion::fromComponents(%.17g, %.17g, %.17g, %.17g), "
                "{%.17g, %.17g, %.17g}}",
                q.w, q.x, q.y, q.z, t.x, t.y, t.z);
  return text;
}

/// Overlap on both orders and without curves, against CGAL's exact intersection and the
/// invariants. `name` says how to make the meshes again; the poses are printed with it. Where
/// the meshes are in `general` position, the order of the meshes changes no area vector either
/// (where faces lie on one another, the perturbation of the second mesh decides which mesh
/// bounds the overlap there, so the area vectors of both orders differ).
void expectExact(const QueryMesh& a, const QueryMesh& b, const std::string& name, bool general) {
  const std::string where =
      name + "\n  pose A: " + describe(a.pose()) + "\n  pose B: " + describe(b.pose());
  SCOPED_TRACE(where);
  OverlapOptions quietOptions;
  quietOptions.curves = false;
  Overlap ab, ba, quiet;
  try {
    ab = overlap(a, b);
    ba = overlap(b, a);
    quiet = overlap(a, b, quietOptions);
  } catch (const std::exception& error) {
    ADD_FAILURE() << "overlap() threw: " << error.what();
    return;
  }

  const Mesh first = worldMesh(a), second = worldMesh(b);
  const Aabb firstBox = first.bounds(), secondBox = second.bounds();
  const double extent = commonExtent(firstBox, secondBox);
  const double cube = extent * extent * extent, tolerance = kVolumeTolerance * cube;
  Vec3 origin;  // the centre of the common box, or any point where there is none
  for (std::size_t axis = 0; axis < 3; ++axis)
    origin[axis] = 0.5 * (std::max(firstBox.lower[axis], secondBox.lower[axis]) +
                          std::min(firstBox.upper[axis], secondBox.upper[axis]));
  ExactOverlap exact;
  try {
    exact = exactOverlap(first, second, origin);
  } catch (const std::exception& error) {
    FAIL() << "CGAL threw: " << error.what();
  }
  ASSERT_TRUE(exact.corefined) << "CGAL could not corefine: the oracle has no answer here";

  // The volume, in total and per region.
  const double error = std::abs(ab.total.volume - exact.volume);
  ++casesCompared;
  casesOverlapping += !exact.regions.empty();
  casesWithSeveralRegions += exact.regions.size() > 1;
  const bool far = std::max({std::abs(origin.x), std::abs(origin.y), std::abs(origin.z)}) > 1e3;
  if (extent > 0.0) worstVolumeError[far] = std::max(worstVolumeError[far], error / cube);
  EXPECT_LE(error, tolerance) << "volume " << format(ab.total.volume) << ", exact "
                              << format(exact.volume) << ", L = " << format(extent);
  if (exact.regions.empty()) {
    EXPECT_EQ(ab.total.volume, 0.0);
  }
  // A piece of the exact result within the tolerance of no volume may be one that only
  // touches, whose rounded volume is not 0: Δ may leave it out.
  const std::size_t certain = static_cast<std::size_t>(
      std::count_if(exact.regions.begin(), exact.regions.end(),
                    [&](const ExactRegion& region) { return region.volume > tolerance; }));
  EXPECT_GE(ab.regions.size(), certain) << "exact regions: " << exact.regions.size();
  EXPECT_LE(ab.regions.size(), exact.regions.size())
      << "exact regions above the tolerance: " << certain;
  double sum = 0.0;
  for (std::size_t r = 0; r < ab.regions.size(); ++r) {
    sum += ab.regions[r].volume;
    if (r > 0) {
      EXPECT_GE(ab.regions[r - 1].volume, ab.regions[r].volume);
    }
    if (r < exact.regions.size()) {
      EXPECT_LE(std::abs(ab.regions[r].volume - exact.regions[r].volume), tolerance)
          << "region " << r << ": " << format(ab.regions[r].volume) << ", exact "
          << format(exact.regions[r].volume);
    }
  }
  EXPECT_LE(std::abs(sum - ab.total.volume), tolerance);
  if (exact.volume > 0.0) {
    EXPECT_LE(length(ab.total.centroid - exact.centroid) * exact.volume,
              kMomentTolerance * cube * extent)
        << "centroid " << format(ab.total.centroid) << ", exact " << format(exact.centroid);
  }

  // Invariants: ∂(A ∩ B) is closed; the order of the meshes changes no integral; curves off
  // change nothing but the curves.
  const double area = kAreaTolerance * extent * extent;
  EXPECT_LE(length(ab.total.areaVector + ab.total.areaVectorB), area)
      << format(ab.total.areaVector) << " and " << format(ab.total.areaVectorB);
  EXPECT_LE(std::abs(ba.total.volume - ab.total.volume), 2.0 * tolerance)
      << "overlap(b, a) " << format(ba.total.volume) << ", overlap(a, b) "
      << format(ab.total.volume);
  EXPECT_EQ(ba.regions.size(), ab.regions.size());
  if (general) {
    EXPECT_LE(length(ba.total.areaVector - ab.total.areaVectorB), area)
        << format(ba.total.areaVector) << " and " << format(ab.total.areaVectorB);
  }
  EXPECT_EQ(quiet.total.volume, ab.total.volume);
  EXPECT_EQ(quiet.regions.size(), ab.regions.size());
  EXPECT_TRUE(quiet.curves.empty());
  std::size_t segments = 0;
  for (const IntersectionCurve& curve : ab.curves) {
    EXPECT_TRUE(curve.closed);
    EXPECT_EQ(curve.points.size(), curve.trianglesA.size() + 1);
    EXPECT_EQ(curve.trianglesB.size(), curve.trianglesA.size());
    EXPECT_LT(curve.region, ab.regions.size());
    segments += curve.trianglesA.size();
  }
  EXPECT_LE(segments, ab.segments);
}

/// The mesh moved to the origin and scaled to a box diagonal of 2 (so every shape meets the
/// others at the same scale).
Mesh normalized(Mesh mesh) {
  const Aabb box = mesh.bounds();
  mesh.translate(-box.center()).scale(2.0 / box.diagonal());
  return mesh;
}

/// Uniform in [0, 1), from the raw output (the same on every standard library).
double unit(std::mt19937_64& random) {
  return static_cast<double>(random() >> 11) * 0x1p-53;
}

/// A rotation uniform over all rotations (a point uniform in the 4-ball, normalised).
Quaternion randomRotation(std::mt19937_64& random) {
  for (;;) {
    const double w = 2.0 * unit(random) - 1.0, x = 2.0 * unit(random) - 1.0,
                 y = 2.0 * unit(random) - 1.0, z = 2.0 * unit(random) - 1.0;
    const double norm = w * w + x * x + y * y + z * z;
    if (norm <= 1.0 && norm > 0.01) return Quaternion::fromComponents(w, x, y, z);
  }
}

Vec3 randomDirection(std::mt19937_64& random) {
  for (;;) {
    const Vec3 v{2.0 * unit(random) - 1.0, 2.0 * unit(random) - 1.0, 2.0 * unit(random) - 1.0};
    const double norm = lengthSquared(v);
    if (norm <= 1.0 && norm > 0.01) return v / std::sqrt(norm);
  }
}

struct NamedMesh {
  std::string name;  ///< how to make it again
  Mesh mesh;
};

/// CGAL's small closed meshes that do not cross themselves and have no zero-area triangle (which
/// CGAL's corefinement refuses: mpi.off has one), from 24 to 634 triangles (tori, letters, a
/// star, mechanical parts), and Δ's primitives, each normalised.
std::vector<NamedMesh> shapes() {
  std::vector<NamedMesh> all;
  for (const char* file : {"3torus.off", "P.off", "cross.off", "u.off", "tripod.off", "star.off",
                           "dragknob.off", "joint.off", "double-torus-example.off", "eight.off"})
    all.push_back({std::string("normalized(io::load(\"") + file + "\"))",
                   normalized(io::load(kMeshes / file))});
  all.push_back({"normalized(primitives::icosphere(2))", normalized(primitives::icosphere(2))});
  all.push_back(
      {"normalized(primitives::box({1, 2, 0.5}))", normalized(primitives::box({1.0, 2.0, 0.5}))});
  for (const std::uint64_t seed : {1u, 2u, 3u})
    all.push_back({"normalized(primitives::granulate(" + std::to_string(seed) + ", {1, 0.7, 0.5}))",
                   normalized(primitives::granulate(seed, {1.0, 0.7, 0.5}))});
  return all;
}

/// Missing test data fails the test (it must not pass by skipping).
::testing::AssertionResult dataPresent() {
  for (const char* file : {"3torus.off", "eight.off"})
    if (!fs::exists(kMeshes / file))
      return ::testing::AssertionFailure()
             << "test data " << kMeshes / file << " is missing: run scripts/setup.sh";
  return ::testing::AssertionSuccess();
}

void printSummary() {
  std::printf(
      "[ oracle   ] %zu cases so far (%zu overlapping, %zu in several regions), max |V - "
      "V_exact| / L^3 = %.3g near the origin, %.3g 1e6 away\n",
      casesCompared, casesOverlapping, casesWithSeveralRegions, worstVolumeError[0],
      worstVolumeError[1]);
}

/// Random rigid poses of random pairs of shapes (a shape with itself too), B's centre at up to
/// 0.6 of the sum of their radii (1) from A's: from deep overlaps to none. Every
/// fourth pair is moved 1e6 from the origin.
TEST(OverlapOracle, RandomPoses) {
  ASSERT_TRUE(dataPresent());
  const std::vector<NamedMesh> all = shapes();
  std::vector<QueryMesh> prepared;
  for (const NamedMesh& shape : all) {
    prepared.emplace_back(shape.mesh);
    ASSERT_TRUE(prepared.back().closed()) << shape.name;
    ASSERT_FALSE(selfIntersections(prepared.back()).any()) << shape.name;
    for (std::size_t t = 0; t < shape.mesh.triangleCount(); ++t) {
      const Triangle corners = shape.mesh.triangle(t);
      ASSERT_GT(lengthSquared(cross(corners.b - corners.a, corners.c - corners.a)), 0.0)
          << shape.name << ": triangle " << t << " has no area";
    }
  }
  std::mt19937_64 random(24);
  const std::size_t cases = test::scaledCount(128);
  for (std::size_t c = 0; c < cases; ++c) {
    const std::size_t i = random() % all.size(), j = random() % all.size();
    const Vec3 offset = c % 4 == 3 ? Vec3{1e6, -1e6, 1e6} : Vec3{};
    QueryMesh a = prepared[i], b = prepared[j];
    a.setPose({randomRotation(random), offset});
    const Quaternion turn = randomRotation(random);
    const Vec3 direction = randomDirection(random);
    b.setPose({turn, offset + direction * (1.2 * unit(random))});
    expectExact(a, b, "case " + std::to_string(c) + ": A = " + all[i].name + ", B = " + all[j].name,
                true);
  }
  printSummary();
}

/// DEM contacts: granulates (80 triangles) turned at random and moved along x until they touch
/// (bisection on the minimum distance, to 1e-9 of the radius), then 1e-2, 1e-4 or 1e-6 of the
/// radius further in: thin lens-shaped overlaps, L the small extent of the box they share.
TEST(OverlapOracle, ShallowGranulateContacts) {
  std::mt19937_64 random(7);
  const std::size_t pairs = test::scaledCount(16);
  for (std::size_t k = 0; k < pairs; ++k) {
    const std::uint64_t firstSeed = 2 * k + 11, secondSeed = 2 * k + 12;
    const QueryMesh a(primitives::granulate(firstSeed));
    QueryMesh b(primitives::granulate(secondSeed));
    const Quaternion turn = randomRotation(random);
    double touching = 0.0, apart = 4.0;  // the radii are 1
    while (apart - touching > 1e-9) {
      const double middle = 0.5 * (touching + apart);
      b.setPose({turn, {middle, 0, 0}});
      (minimumDistance(a, b).distance > 0.0 ? apart : touching) = middle;
    }
    const double depth = std::pow(10.0, -2.0 - 2.0 * static_cast<double>(k % 3));
    b.setPose({turn, {touching - depth, 0, 0}});
    expectExact(a, b,
                "A = primitives::granulate(" + std::to_string(firstSeed) +
                    "), B = primitives::granulate(" + std::to_string(secondSeed) + ")",
                true);
  }
  printSummary();
}

struct Scene {
  std::string name;
  Mesh a, b;
  std::size_t regions;
  double volume = -1.0;  ///< known exactly (−1: CGAL's only)
};

Mesh unitCube() {
  return primitives::box({1.0, 1.0, 1.0}, {0.5, 0.5, 0.5});
}

/// One mesh of two (closed, disjoint: closed too).
Mesh joined(const Mesh& first, const Mesh& second) {
  std::vector<Vec3> vertices(first.vertices().begin(), first.vertices().end());
  std::vector<TriangleIndices> triangles(first.triangles().begin(), first.triangles().end());
  const auto base = static_cast<std::uint32_t>(vertices.size());
  vertices.insert(vertices.end(), second.vertices().begin(), second.vertices().end());
  for (const TriangleIndices& t : second.triangles())
    triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
  return Mesh(std::move(vertices), std::move(triangles));
}

Mesh moved(Mesh mesh, const std::function<void(Mesh&)>& move) {
  move(mesh);
  return mesh;
}

std::vector<Scene> degenerateScenes() {
  const Mesh cube = unitCube();
  const Mesh sphere = primitives::icosphere(1, 0.5, {0.5, 0.5, 0.5});
  const Vec3 z{0, 0, 1};
  const double quarter = std::atan(1.0);  // 45°
  std::vector<Scene> scenes;
  // Nested.
  scenes.push_back({"sphere inside a box", sphere, primitives::box({2, 2, 2}, {0.5, 0.5, 0.5}), 1});
  scenes.push_back({"box around a sphere", primitives::box({2, 2, 2}, {0.5, 0.5, 0.5}), sphere, 1});
  scenes.push_back({"half cube in a corner of the cube (a shared vertex, three shared faces)", cube,
                    primitives::box({0.5, 0.5, 0.5}, {0.25, 0.25, 0.25}), 1, 0.125});
  scenes.push_back({"cube around a half cube in its corner",
                    primitives::box({0.5, 0.5, 0.5}, {0.25, 0.25, 0.25}), cube, 1, 0.125});
  // Disjoint.
  scenes.push_back({"far apart", cube, primitives::box({1, 1, 1}, {5, 0.5, 0.5}), 0, 0.0});
  scenes.push_back({"a sphere and a box in its box's corner", primitives::icosphere(3, 1.0),
                    primitives::box({0.2, 0.2, 0.2}, {0.9, 0.9, 0.9}), 0, 0.0});
  // Touching.
  scenes.push_back(
      {"cubes sharing a face", cube, primitives::box({1, 1, 1}, {1.5, 0.5, 0.5}), 0, 0.0});
  scenes.push_back(
      {"cubes sharing an edge", cube, primitives::box({1, 1, 1}, {1.5, 1.5, 0.5}), 0, 0.0});
  scenes.push_back(
      {"cubes sharing a vertex", cube, primitives::box({1, 1, 1}, {1.5, 1.5, 1.5}), 0, 0.0});
  scenes.push_back(
      {"cubes sharing half a face", cube, primitives::box({1, 1, 1}, {1.5, 0.5, 1.0}), 0, 0.0});
  // Coplanar faces.
  scenes.push_back({"cubes offset by 0.5 along x (y and z faces coplanar)", cube,
                    primitives::box({1, 1, 1}, {1.0, 0.5, 0.5}), 1, 0.5});
  scenes.push_back({"cubes offset by 0.3 along x", cube,
                    moved(cube,
                          [](Mesh& m) {
                            m.translate({0.3, 0, 0});
                          }),
                    1});
  scenes.push_back({"cubes offset by 0.25 along x and y (z faces coplanar)", cube,
                    primitives::box({1, 1, 1}, {0.75, 0.75, 0.5}), 1, 0.5625});
  scenes.push_back({"the same cube twice", cube, cube, 1, 1.0});
  scenes.push_back({"the same sphere twice", sphere, sphere, 1});
  scenes.push_back(
      {"the same granulate twice", primitives::granulate(5), primitives::granulate(5), 1});
  // Two regions, both crossed by the same (long) triangles of the bar.
  scenes.push_back({"a bar through two slabs 1.25 apart",
                    primitives::box({3, 1, 1}, {1.5, 0.5, 0.5}),
                    joined(primitives::box({0.5, 2, 2}, {0.75, 0.5, 0.5}),
                           primitives::box({0.5, 2, 2}, {2.25, 0.5, 0.5})),
                    2, 1.0});
  // Shared edges and vertices, edge-on-edge crossings.
  scenes.push_back({"cube turned 45° about its edge on the z axis (a shared edge)", cube,
                    moved(cube, [&](Mesh& m) { m.rotate(z, quarter); }), 1});
  scenes.push_back({"cube turned 45° about its vertical axis (edges cross edges in z = 0, 1)", cube,
                    moved(cube,
                          [&](Mesh& m) {
                            m.rotate(z, quarter, {0.5, 0.5, 0});
                          }),
                    1});
  scenes.push_back(
      {"cube turned 45° about z, its vertical edge crossing the cube's edge at "
       "(0.5, 0, 1), its vertex on the face y = 0",
       cube,
       moved(cube,
             [&](Mesh& m) {
               m.rotate(z, quarter).translate({0.5, 0, 0.5});
             }),
       1});
  scenes.push_back({"cube turned 30° about its diagonal through the origin (a shared vertex)", cube,
                    moved(cube,
                          [](Mesh& m) {
                            m.rotate({1, 1, 1}, std::atan(1.0) * 4.0 / 6.0);
                          }),
                    1});
  scenes.push_back({"tetrahedra sharing a vertex, one poking into the other",
                    Mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                         {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}),
                    Mesh({{0, 0, 0}, {1, 0.5, 0.25}, {0.25, 1, 0.5}, {0.5, 0.25, 1}},
                         {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}),
                    1});
  return scenes;
}

/// Each degenerate scene as it is, then 1e6 from the origin twice: by the poses (the prepared
/// meshes where they are; not in a slow build) and in the meshes (prepared 1e6 away, identity
/// poses).
TEST(OverlapOracle, DegenerateScenes) {
  const Vec3 far{1e6, -1e6, 1e6};
  for (const Scene& scene : degenerateScenes()) {
    for (int placement = 0; placement < 3; ++placement) {
      if (placement == 1 && test::kSlowBuild) continue;
      const Vec3 meshOffset = placement == 2 ? far : Vec3{};
      const Mesh first = moved(scene.a, [&](Mesh& m) { m.translate(meshOffset); });
      const Mesh second = moved(scene.b, [&](Mesh& m) { m.translate(meshOffset); });
      QueryMesh a(first), b(second);
      ASSERT_TRUE(a.closed() && b.closed()) << scene.name;
      if (placement == 1) {
        a.setPose(RigidTransform::translationBy(far));
        b.setPose(RigidTransform::translationBy(far));
      }
      const std::string name = scene.name + (placement == 0   ? ""
                                             : placement == 1 ? " (poses 1e6 away)"
                                                              : " (meshes 1e6 away)");
      SCOPED_TRACE(name);
      expectExact(a, b, name, false);
      const Overlap found = overlap(a, b);
      EXPECT_EQ(found.regions.size(), scene.regions);
      if (scene.volume == 0.0) {
        EXPECT_EQ(found.total.volume, 0.0);
        EXPECT_FALSE(found.any());
      } else if (scene.volume > 0.0) {
        EXPECT_LE(std::abs(found.total.volume - scene.volume), kVolumeTolerance)
            << format(found.total.volume);
      }
    }
  }
  printSummary();
}

}  // namespace
}  // namespace delta::contactdetection
