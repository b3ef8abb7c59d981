// Contacts and minimum distances between copies of CGAL's real meshes (data/meshes) against an
// independent reference: the scalar brute force on every pair of triangles that could be closer
// than 2ε. It skips only pairs whose boxes lie at least 2ε·1.01 apart along an axis (two
// triangles are at least as far apart as their boxes; the 1% covers the boxes' rounding), which
// keeps it fast enough to run on every pair in a sanitizer build too.

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/point_triangle.h"
#include "delta/kernels/triangle_triangle.h"
#include "delta/mesh/mesh.h"
#include "delta/query/contacts.h"
#include "delta/query/minimum_distance.h"
#include "delta/query/query_mesh.h"

#include "kernels/triangle_pairs.h"

namespace delta::contactdetection {
namespace {

namespace fs = std::filesystem;

const fs::path kMeshes = fs::path(DELTA_DATA_DIR) / "meshes";
/// An organic shape (elk: 3,290 triangles) and a mechanical part with flat faces and sharp
/// edges (couplingdown: 3,714 triangles).
const char* const kMeshFiles[] = {"elk.off", "couplingdown.off"};

/// Missing test data fails a test (it must not pass by skipping).
::testing::AssertionResult dataPresent() {
  for (const char* file : kMeshFiles)
    if (!fs::exists(kMeshes / file))
      return ::testing::AssertionFailure()
             << "test data " << kMeshes / file << " is missing: run scripts/setup.sh";
  return ::testing::AssertionSuccess();
}

struct Scene {
  std::string name;
  Mesh first, second;
  double epsilon;
  double size;  ///< the diagonal of both meshes' box: the scale of every tolerance
};

/// A copy of `mesh` turned about its centre and put on its +x side, then pushed back along x
/// until the meshes are `gap` to 1.25·gap apart (each step moves it by the distance left minus
/// `gap`, so they never touch).
Mesh nearCopy(const Mesh& mesh, double gap) {
  const Aabb box = mesh.bounds();
  Mesh copy = mesh;
  copy.rotate({1, 2, 3}, 0.7, box.center())
      .translate({1.2 * box.diagonal(), 0.1 * box.extent().y, 0.05 * box.extent().z});
  const TriangleSoA fixed = flatten(mesh);
  for (int step = 0; step < 40; ++step) {
    const double distance = minimumDistance(fixed, flatten(copy)).distance;
    if (distance < 1.25 * gap) break;
    copy.translate({gap - distance, 0, 0});
  }
  return copy;
}

double diagonalOf(const Mesh& first, const Mesh& second) {
  Aabb box = first.bounds();
  box.extend(second.bounds());
  return box.diagonal();
}

/// Per mesh: (a) a turned copy a gap of 0.2% of the diagonal away, ε the gap (a few contacts);
/// (b) that copy pushed 5% of the diagonal into the mesh, ε 0.5% of the diagonal.
std::vector<Scene> makeScenes() {
  std::vector<Scene> scenes;
  for (const char* file : kMeshFiles) {
    const Mesh mesh = io::load(kMeshes / file);
    const double diagonal = mesh.bounds().diagonal();
    const double gap = 2e-3 * diagonal;
    const Mesh near = nearCopy(mesh, gap);
    scenes.push_back({std::string(file) + " and a turned copy a small gap apart", mesh, near, gap,
                      diagonalOf(mesh, near)});
    Mesh overlapping = near;
    overlapping.translate({-0.05 * diagonal, 0, 0});
    scenes.push_back({std::string(file) + " and a turned copy 5% deep in it", mesh, overlapping,
                      5e-3 * diagonal, diagonalOf(mesh, overlapping)});
  }
  return scenes;
}

const std::vector<Scene>& scenes() {
  static const std::vector<Scene> all = makeScenes();
  return all;
}

/// A reference contact: the brute force's answer for the pair.
struct Reference {
  std::uint32_t first, second;
  kernels::TriangleDistanceResult result;
};

/// Every pair closer than 2ε by the scalar brute force, sorted by (first, second) like the
/// library's contacts.
std::vector<Reference> referenceContacts(const Scene& scene) {
  const double reach = 2.0 * scene.epsilon;
  std::vector<Aabb> secondBoxes;
  for (std::size_t j = 0; j < scene.second.triangleCount(); ++j)
    secondBoxes.push_back(scene.second.triangle(j).bounds());
  std::vector<Reference> all;
  for (std::uint32_t i = 0; i < scene.first.triangleCount(); ++i) {
    const Triangle one = scene.first.triangle(i);
    const Aabb box = one.bounds();
    for (std::uint32_t j = 0; j < scene.second.triangleCount(); ++j) {
      if (apart(box, secondBoxes[j], 1.01 * reach)) continue;
      const auto r = kernels::triangleDistanceBruteForce(one, scene.second.triangle(j));
      if (r.distanceSquared < reach * reach) all.push_back({i, j, r});
    }
  }
  return all;
}

/// Whether `x` lies on `triangle` within `tolerance`.
bool onTriangle(const Vec3& x, const Triangle& triangle, double tolerance) {
  return kernels::closestPointOnTriangle(x, triangle).distanceSquared <= tolerance * tolerance;
}

/// The same pairs in the same order, `distance` within 1e-12 of the scene's size, the same
/// `overlap`, and `x` within 1e-12 of the scene's size of the expected x where the closest points
/// are unique (apart); where the triangles intersect any common point is right, so there `x` must
/// lie on both.
void expectSameContacts(const Scene& scene, const std::vector<ContactPoint>& actual,
                        const std::vector<ContactPoint>& expected, const std::string& label) {
  ASSERT_EQ(actual.size(), expected.size()) << label;
  const double tolerance = 1e-12 * scene.size;
  for (std::size_t k = 0; k < actual.size(); ++k) {
    const ContactPoint& a = actual[k];
    const ContactPoint& e = expected[k];
    ASSERT_EQ(a.first, e.first) << label << ", contact " << k;
    ASSERT_EQ(a.second, e.second) << label << ", contact " << k;
    const std::string pair =
        label + ", pair " + std::to_string(a.first) + "-" + std::to_string(a.second);
    EXPECT_NEAR(a.distance, e.distance, tolerance) << pair;
    EXPECT_EQ(a.overlap, e.overlap) << pair;
    if (e.overlap) {
      EXPECT_EQ(a.distance, 0.0) << pair;
      EXPECT_TRUE(onTriangle(a.x, scene.first.triangle(a.first), tolerance)) << pair;
      EXPECT_TRUE(onTriangle(a.x, scene.second.triangle(a.second), tolerance)) << pair;
    } else {
      EXPECT_LE(distance(a.x, e.x), tolerance) << pair;
    }
  }
}

std::vector<ContactPoint> asContacts(const std::vector<Reference>& references) {
  std::vector<ContactPoint> contacts;
  for (const Reference& r : references) {
    ContactPoint contact;
    contact.x = (r.result.p + r.result.q) * 0.5;
    contact.distance = std::sqrt(r.result.distanceSquared);
    contact.overlap = r.result.intersect;
    contact.first = r.first;
    contact.second = r.second;
    contacts.push_back(contact);
  }
  return contacts;
}

void expectBitwiseEqual(double a, double b, const std::string& label) {
  EXPECT_EQ(std::bit_cast<std::uint64_t>(a), std::bit_cast<std::uint64_t>(b))
      << label << ": " << a << " vs " << b;
}

void expectBitwiseEqual(const Vec3& a, const Vec3& b, const std::string& label) {
  for (std::size_t axis = 0; axis < 3; ++axis)
    expectBitwiseEqual(a[axis], b[axis], label + ", axis " + std::to_string(axis));
}

void expectBitwiseEqual(const std::vector<ContactPoint>& actual,
                        const std::vector<ContactPoint>& expected, const std::string& label) {
  ASSERT_EQ(actual.size(), expected.size()) << label;
  for (std::size_t k = 0; k < actual.size(); ++k) {
    const std::string where = label + ", contact " + std::to_string(k);
    const ContactPoint& a = actual[k];
    const ContactPoint& e = expected[k];
    EXPECT_EQ(a.first, e.first) << where;
    EXPECT_EQ(a.second, e.second) << where;
    expectBitwiseEqual(a.x, e.x, where + " x");
    expectBitwiseEqual(a.normal, e.normal, where + " normal");
    expectBitwiseEqual(a.direction, e.direction, where + " direction");
    expectBitwiseEqual(a.distance, e.distance, where + " distance");
    EXPECT_EQ(a.overlap, e.overlap) << where;
  }
}

void expectBitwiseEqual(const MinimumDistance& a, const MinimumDistance& b,
                        const std::string& label) {
  expectBitwiseEqual(a.distance, b.distance, label + " distance");
  EXPECT_EQ(a.first, b.first) << label;
  EXPECT_EQ(a.second, b.second) << label;
  expectBitwiseEqual(a.p, b.p, label + " p");
  expectBitwiseEqual(a.q, b.q, label + " q");
  EXPECT_EQ(a.intersect, b.intersect) << label;
}

constexpr kernels::Solver kExactSolvers[] = {kernels::Solver::Hybrid, kernels::Solver::BruteForce};

TEST(RealMeshContacts, ScenesHaveAFewContactsOrAnOverlap) {
  ASSERT_TRUE(dataPresent());
  for (const Scene& scene : scenes()) {
    const std::vector<Reference> expected = referenceContacts(scene);
    const auto overlaps = std::count_if(expected.begin(), expected.end(),
                                        [](const Reference& r) { return r.result.intersect; });
    if (scene.name.find("gap") != std::string::npos) {
      EXPECT_GE(expected.size(), 1u) << scene.name;
      EXPECT_LE(expected.size(), 100u) << scene.name << ": more than a handful";
      EXPECT_EQ(overlaps, 0) << scene.name;
    } else {
      EXPECT_GE(overlaps, 20) << scene.name;
    }
  }
}

TEST(RealMeshContacts, EachExactSolverFindsTheBruteForceContacts) {
  ASSERT_TRUE(dataPresent());
  for (const Scene& scene : scenes()) {
    const std::vector<ContactPoint> expected = asContacts(referenceContacts(scene));
    ASSERT_FALSE(expected.empty()) << scene.name;
    const TriangleSoA first = flatten(scene.first), second = flatten(scene.second);
    for (kernels::Solver solver : kExactSolvers)
      expectSameContacts(scene, contacts(first, second, scene.epsilon, solver), expected,
                         scene.name + ", " + kernels::name(solver));
  }
}

TEST(RealMeshContacts, HybridAndBruteForceFindTheSameContacts) {
  ASSERT_TRUE(dataPresent());
  for (const Scene& scene : scenes()) {
    const TriangleSoA first = flatten(scene.first), second = flatten(scene.second);
    const std::vector<ContactPoint> hybrid =
        contacts(first, second, scene.epsilon, kernels::Solver::Hybrid);
    EXPECT_FALSE(hybrid.empty()) << scene.name;
    expectSameContacts(scene, hybrid,
                       contacts(first, second, scene.epsilon, kernels::Solver::BruteForce),
                       scene.name);
  }
}

TEST(RealMeshContacts, MinimumDistanceIsTheBruteForceMinimum) {
  ASSERT_TRUE(dataPresent());
  for (const Scene& scene : scenes()) {
    // The minimum is closer than 2ε, so its pair is a reference contact: the smallest
    // (distance², first, second) among them.
    const std::vector<Reference> references = referenceContacts(scene);
    ASSERT_FALSE(references.empty()) << scene.name;
    const Reference& least = *std::min_element(
        references.begin(), references.end(), [](const Reference& a, const Reference& b) {
          if (a.result.distanceSquared != b.result.distanceSquared)
            return a.result.distanceSquared < b.result.distanceSquared;
          return a.first < b.first || (a.first == b.first && a.second < b.second);
        });
    const double expected = std::sqrt(least.result.distanceSquared);
    const double tolerance = 1e-12 * scene.size;
    for (kernels::Solver solver : kExactSolvers) {
      const std::string label = scene.name + ", " + kernels::name(solver);
      const MinimumDistance actual =
          minimumDistance(flatten(scene.first), flatten(scene.second), solver);
      EXPECT_NEAR(actual.distance, expected, tolerance) << label;
      EXPECT_EQ(actual.intersect, least.result.intersect) << label;
      // the pair found attains the minimum (the hybrid may break ties within rounding apart)
      const auto check = kernels::triangleDistanceBruteForce(scene.first.triangle(actual.first),
                                                             scene.second.triangle(actual.second));
      EXPECT_NEAR(std::sqrt(check.distanceSquared), expected, tolerance) << label;
      EXPECT_NEAR(distance(actual.p, actual.q), actual.distance, tolerance) << label;
      if (solver == kernels::Solver::BruteForce || least.result.intersect) {
        // The scalar brute force computes every pair to the bit, and intersecting pairs are
        // exactly 0 apart: the very pair of the reference, the smallest ids among equals.
        EXPECT_EQ(actual.first, least.first) << label;
        EXPECT_EQ(actual.second, least.second) << label;
      }
      if (solver == kernels::Solver::BruteForce) {
        expectBitwiseEqual(actual.distance, expected, label);
        expectBitwiseEqual(actual.p, least.result.p, label + " p");
        expectBitwiseEqual(actual.q, least.result.q, label + " q");
      }
    }
  }
}

TEST(RealMeshContacts, SameResultsForOneAndTwoThreads) {
  ASSERT_TRUE(dataPresent());
  const int threads = omp_get_max_threads();
  for (const Scene& scene : scenes()) {
    const TriangleSoA first = flatten(scene.first), second = flatten(scene.second);
    for (kernels::Solver solver : kExactSolvers) {
      // the brute force on overlapping meshes is slow under the sanitizers (the hybrid is not)
      if (delta::test::kSlowBuild && solver == kernels::Solver::BruteForce &&
          scene.name.find("deep") != std::string::npos)
        continue;
      const std::string label = scene.name + ", " + kernels::name(solver);
      omp_set_num_threads(1);
      const std::vector<ContactPoint> serial = contacts(first, second, scene.epsilon, solver);
      const MinimumDistance serialMinimum = minimumDistance(first, second, solver);
      omp_set_num_threads(2);
      const std::vector<ContactPoint> parallel = contacts(first, second, scene.epsilon, solver);
      const MinimumDistance parallelMinimum = minimumDistance(first, second, solver);
      omp_set_num_threads(threads);
      EXPECT_FALSE(serial.empty()) << label;
      expectBitwiseEqual(parallel, serial, label);
      expectBitwiseEqual(parallelMinimum, serialMinimum, label);
    }
    // The prepared meshes (their contacts batch the pairs of runs of first leaves, fixed by
    // index, whatever the threads), the second moved a little so that its tree is carried.
    const QueryMesh preparedFirst(scene.first);
    QueryMesh preparedSecond(scene.second);
    preparedSecond.transform(RigidTransform::translationBy(Vec3{1, -2, 3} * (0.1 * scene.epsilon)));
    omp_set_num_threads(1);
    const std::vector<ContactPoint> serial = contacts(preparedFirst, preparedSecond, scene.epsilon);
    omp_set_num_threads(2);
    const std::vector<ContactPoint> parallel =
        contacts(preparedFirst, preparedSecond, scene.epsilon);
    omp_set_num_threads(threads);
    EXPECT_FALSE(serial.empty()) << scene.name;
    expectBitwiseEqual(parallel, serial, scene.name + ", QueryMesh");
  }
}

}  // namespace
}  // namespace delta::contactdetection
