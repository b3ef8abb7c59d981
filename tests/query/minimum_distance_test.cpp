#include "delta/query/minimum_distance.h"

#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/kernels/pair_results.h"
#include "delta/kernels/triangle_batch.h"
#include "delta/kernels/triangle_triangle.h"
#include "delta/mesh/primitives.h"
#include "delta/query/query_mesh.h"

#include "kernels/triangle_pairs.h"
#include "query/detail/query_mesh_data.h"

namespace delta::contactdetection {
namespace {

/// Every pair by the scalar brute force: the reference.
MinimumDistance byAllPairs(const Mesh& first, const Mesh& second) {
  MinimumDistance best;
  best.distance = INFINITY;
  for (std::uint32_t i = 0; i < first.triangleCount(); ++i)
    for (std::uint32_t j = 0; j < second.triangleCount(); ++j) {
      const auto r = kernels::triangleDistanceBruteForce(first.triangle(i), second.triangle(j));
      if (std::sqrt(r.distanceSquared) < best.distance)
        best = {std::sqrt(r.distanceSquared), i, j, r.p, r.q, r.intersect};
    }
  return best;
}

struct Scene {
  Mesh first, second;
};

std::vector<Scene> scenes() {
  std::vector<Scene> all;
  // Two granulates a small gap apart, the second turned.
  Mesh a = primitives::granulate(1);
  Mesh b = primitives::granulate(2);
  b.rotate({1, 2, 3}, 0.7).translate({2.05, 0.1, -0.2});
  all.push_back({a, b});
  // Interpenetrating: distance 0, intersect.
  Mesh c = primitives::icosphere(2);
  Mesh d = primitives::box({1, 1, 1}, {0.9, 0, 0});
  all.push_back({c, d});
  // Far apart and far from the origin.
  Mesh e = primitives::cylinder(1, 2, 12, {1e6, 1e6, 0});
  Mesh f = primitives::icosphere(1, 0.5, {1e6 + 7, 1e6 + 1, 3});
  all.push_back({e, f});
  return all;
}

TEST(MinimumDistance, MatchesAllPairsByBruteForce) {
  for (const Scene& scene : scenes()) {
    const MinimumDistance expected = byAllPairs(scene.first, scene.second);
    const double size = scene.first.bounds().diagonal() + scene.second.bounds().diagonal();
    for (kernels::Solver solver : {kernels::Solver::Hybrid, kernels::Solver::BruteForce}) {
      const MinimumDistance actual =
          minimumDistance(flatten(scene.first), flatten(scene.second), solver);
      EXPECT_NEAR(actual.distance, expected.distance, 1e-12 * size) << kernels::name(solver);
      EXPECT_EQ(actual.intersect, expected.intersect);
      // the pair found attains the minimum (several pairs may tie)
      const auto check = kernels::triangleDistanceBruteForce(scene.first.triangle(actual.first),
                                                             scene.second.triangle(actual.second));
      EXPECT_NEAR(std::sqrt(check.distanceSquared), expected.distance, 1e-12 * size);
      EXPECT_NEAR(distance(actual.p, actual.q), actual.distance, 1e-12 * size);
    }
  }
}

/// `mesh` without its first `drop` triangles (its vertices all kept).
Mesh withoutFirst(const Mesh& mesh, std::size_t drop) {
  return Mesh(std::vector<Vec3>(mesh.vertices().begin(), mesh.vertices().end()),
              std::vector<TriangleIndices>(mesh.triangles().begin() + static_cast<long>(drop),
                                           mesh.triangles().end()));
}

/// The least distance over every pair, the pairs taken in ascending order of their boxes'
/// distance until that exceeds the best (exact, as byAllPairs, and cheap enough for many poses).
double byNearestBoxesFirst(const Mesh& first, const Mesh& second) {
  std::vector<std::pair<double, std::pair<std::uint32_t, std::uint32_t>>> pairs;
  for (std::uint32_t i = 0; i < first.triangleCount(); ++i)
    for (std::uint32_t j = 0; j < second.triangleCount(); ++j)
      pairs.push_back(
          {distanceSquared(first.triangle(i).bounds(), second.triangle(j).bounds()), {i, j}});
  std::sort(pairs.begin(), pairs.end());
  double best = INFINITY;
  for (const auto& [boxes, pair] : pairs) {
    if (boxes > best) break;
    best = std::min(best, kernels::triangleDistanceBruteForce(first.triangle(pair.first),
                                                              second.triangle(pair.second))
                              .distanceSquared);
  }
  return std::sqrt(best);
}

/// The centroid of the triangles of a prepared mesh's last tree leaf (in the mesh's frame).
Vec3 lastLeafCentre(const QueryMesh& query, const Mesh& mesh) {
  const detail::QueryMeshData& data = query.data();
  const std::size_t first = (data.size() - 1) / detail::kFanout * detail::kFanout;
  Vec3 sum{};
  for (std::size_t k = first; k < data.size(); ++k)
    sum = sum + mesh.triangle(data.order[k]).centroid();
  return sum * (1.0 / static_cast<double>(data.size() - first));
}

TEST(MinimumDistance, LastLeavesOfFewerThanEightTrianglesMatchBruteForce) {
  // 317 and 314 triangles: each tree's last leaf holds 5 or 2. The second is turned and placed
  // so that its last leaf faces the first's across a small gap, so that the search meets both
  // last leaves first, and must still find every other leaf's triangles where they are.
  const Mesh first = withoutFirst(primitives::icosphere(2), 3);
  const Mesh second = withoutFirst(primitives::icosphere(2, 0.7), 6);
  const QueryMesh a(first), b(second);
  ASSERT_EQ(a.size() % detail::kFanout, 5u);
  ASSERT_EQ(b.size() % detail::kFanout, 2u);
  const Vec3 centreA = lastLeafCentre(a, first), centreB = lastLeafCentre(b, second);
  const Vec3 outward = normalized(centreA), facing = normalized(centreB);
  const Vec3 axis = cross(facing, outward * -1.0);
  const double angle = std::acos(std::clamp(dot(facing, outward * -1.0), -1.0, 1.0));
  // Under the sanitizers every third turn (each round's brute force takes a third of a second).
  const int turnStep = test::kSlowBuild ? 3 : 1;
  int rounds = 0;
  for (const double gap : {0.002, 0.02, 0.1})
    for (int turn = 0; turn < 12; turn += turnStep) {
      const Quaternion spin = Quaternion::fromAxisAngle(outward, 0.5236 * turn) *
                              Quaternion::fromAxisAngle(axis, angle);
      const RigidTransform pose{spin, centreA + outward * gap - spin.rotate(centreB)};
      QueryMesh moved = b;
      moved.setPose(pose);
      Mesh placed = second;
      placed.transform(pose);
      const double expected = byNearestBoxesFirst(first, placed);
      const MinimumDistance actual = minimumDistance(a, moved);
      ASSERT_NEAR(actual.distance, expected, 1e-12) << gap << " " << turn;
      const auto check = kernels::triangleDistanceBruteForce(first.triangle(actual.first),
                                                             placed.triangle(actual.second));
      ASSERT_NEAR(std::sqrt(check.distanceSquared), expected, 1e-12) << gap << " " << turn;
      ++rounds;
    }
  EXPECT_EQ(rounds, 36 / turnStep);
}

TEST(MinimumDistance, SameAnswerForAnyThreadCountAndFromManyThreads) {
  const Scene scene = scenes().front();
  const TriangleSoA first = flatten(scene.first), second = flatten(scene.second);
  omp_set_num_threads(1);
  const MinimumDistance serial = minimumDistance(first, second);
  omp_set_num_threads(2);
  const MinimumDistance parallel = minimumDistance(first, second);
  EXPECT_EQ(parallel.distance, serial.distance);
  EXPECT_EQ(parallel.first, serial.first);
  EXPECT_EQ(parallel.second, serial.second);
  std::vector<MinimumDistance> answers(3);
  std::vector<std::thread> callers;
  for (MinimumDistance& answer : answers)
    callers.emplace_back([&] { answer = minimumDistance(first, second); });
  for (std::thread& caller : callers)
    caller.join();
  for (const MinimumDistance& answer : answers) {
    EXPECT_EQ(answer.distance, serial.distance);
    EXPECT_EQ(answer.first, serial.first);
    EXPECT_EQ(answer.second, serial.second);
  }
}

// The pruned search against every pair, on meshes chosen to break it: exact ties spread over
// many blocks and out of id order, touching and intersecting meshes, coordinates near 1e6, a tiny
// mesh beside a big one, zero-area triangles.

/// Every pair by the scalar brute force, the smallest (distance², first, second): the documented
/// answer, whatever order the pairs are visited in.
MinimumDistance smallestPairByBruteForce(const Mesh& first, const Mesh& second) {
  MinimumDistance best;
  double bestSquared = INFINITY;
  for (std::uint32_t i = 0; i < first.triangleCount(); ++i)
    for (std::uint32_t j = 0; j < second.triangleCount(); ++j) {
      const auto r = kernels::triangleDistanceBruteForce(first.triangle(i), second.triangle(j));
      if (r.distanceSquared < bestSquared) {  // in (i, j) order: ties keep the smallest ids
        bestSquared = r.distanceSquared;
        best = {std::sqrt(r.distanceSquared), i, j, r.p, r.q, r.intersect};
      }
    }
  return best;
}

/// A grid of n × n unit squares, two triangles each, in the plane z = `z`, from (x0, y0); every
/// coordinate a small dyadic rational, so distances between parallel grids are exact.
Mesh grid(int n, double z, double x0 = 0.0, double y0 = 0.0) {
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x)
      vertices.push_back({x0 + x, y0 + y, z});
  const auto at = [n](int x, int y) { return static_cast<std::uint32_t>(y * (n + 1) + x); };
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      triangles.push_back({at(x, y), at(x + 1, y), at(x + 1, y + 1)});
      triangles.push_back({at(x, y), at(x + 1, y + 1), at(x, y + 1)});
    }
  return Mesh(std::move(vertices), std::move(triangles));
}

/// The same triangles in a random order (Fisher–Yates on std::mt19937_64's raw output, the
/// same on every standard library), so that id order and spatial order disagree.
Mesh shuffled(const Mesh& mesh, std::uint64_t seed) {
  std::vector<TriangleIndices> triangles(mesh.triangles().begin(), mesh.triangles().end());
  std::mt19937_64 engine(seed);
  for (std::size_t k = triangles.size(); k > 1; --k)
    std::swap(triangles[k - 1], triangles[engine() % k]);
  return Mesh(std::vector<Vec3>(mesh.vertices().begin(), mesh.vertices().end()),
              std::move(triangles));
}

/// `mesh` with zero-area triangles added: a point, a repeated vertex, collinear vertices.
Mesh withDegenerateTriangles(const Mesh& mesh, const Vec3& near) {
  std::vector<Vec3> vertices(mesh.vertices().begin(), mesh.vertices().end());
  std::vector<TriangleIndices> triangles(mesh.triangles().begin(), mesh.triangles().end());
  const auto add = [&](const Vec3& v) {
    vertices.push_back(v);
    return static_cast<std::uint32_t>(vertices.size() - 1);
  };
  const std::uint32_t point = add(near);
  triangles.insert(triangles.begin(), TriangleIndices{point, point, point});  // id 0: a point
  const std::uint32_t a = add(near + Vec3{0.1, 0.0, 0.0}), b = add(near + Vec3{0.3, 0.0, 0.0});
  const std::uint32_t c = add(near + Vec3{0.2, 0.0, 0.0});
  triangles.push_back({a, b, c});  // collinear, the middle one last
  triangles.push_back({a, a, b});  // a repeated vertex
  triangles.insert(triangles.begin() + 5, TriangleIndices{c, a, point});  // collinear
  return Mesh(std::move(vertices), std::move(triangles));
}

struct AdversarialScene {
  std::string name;
  Mesh first, second;
  bool exactTies;  ///< distances are exact in every solver: ids must match the reference's too
};

std::vector<AdversarialScene> adversarialScenes() {
  std::vector<AdversarialScene> all;
  // Exact ties: parallel grids half a unit apart, every overlapping pair at exactly 0.5; the
  // second one shuffled so the tied pairs lie in many blocks, out of id order.
  all.push_back({"parallel grids (ties)", grid(12, 0.0), shuffled(grid(16, 0.5, -2, -2), 1), true});
  all.push_back({"shuffled parallel grids (ties)", shuffled(grid(12, 0.0), 2),
                 shuffled(grid(12, 0.5, 0.5, 0.25), 3), true});
  // A box over a box: their facing faces at exactly 0.5.
  all.push_back({"box over box (ties)", primitives::box(),
                 primitives::box({1, 1, 1}, {0.25, 0.125, 1.5}), true});
  // Touching: a face on a face, a vertex on a vertex, a grid resting on a sphere's pole.
  all.push_back({"box on box, face to face", primitives::box(),
                 primitives::box({1, 1, 1}, {0.25, 0.125, 1.0}), true});
  all.push_back({"box on box, corner to corner", primitives::box(),
                 primitives::box({1, 1, 1}, {1, 1, 1}), true});
  all.push_back({"grid touching a sphere", primitives::icosphere(3),
                 shuffled(grid(8, 1.0, -4, -4), 4), true});
  // Intersecting: every intersecting pair is exactly 0 apart; the smallest ids win.
  Mesh sphere = primitives::icosphere(2);
  Mesh other = primitives::icosphere(2, 1.0, {0.5, 0.25, 0.125});
  all.push_back({"interpenetrating spheres", sphere, shuffled(other, 5), true});
  Mesh g1 = primitives::granulate(7, {1, 0.7, 0.5}, 200);
  Mesh g2 = primitives::granulate(8, {0.8, 0.8, 0.6}, 200);
  g2.rotate({1, 1, 0}, 0.4).translate({1.2, 0.3, 0.1});
  all.push_back({"granulates cutting each other", g1, g2, true});
  // Apart, far from the origin: rounding at 1e6 must not make the bounds drop the answer.
  Mesh g3 = primitives::granulate(9, {1, 0.8, 0.6}, 150);
  Mesh g4 = primitives::granulate(10, {0.9, 0.9, 0.7}, 150);
  g4.rotate({0, 1, 1}, 1.1).translate({2.01, 0.2, -0.1});
  g3.translate({1e6, -1e6, 1e6});
  g4.translate({1e6, -1e6, 1e6});
  all.push_back({"granulates at 1e6", g3, g4, false});
  all.push_back({"grids at 1e6 (ties)", grid(10, 1e6, 1e6, 1e6),
                 shuffled(grid(10, 1e6 + 0.25, 1e6 + 0.5, 1e6), 6), true});
  // A tiny mesh beside a big one, both ways round.
  Mesh big = primitives::icosphere(3, 10.0);
  Mesh tiny = primitives::icosphere(1, 1e-3, {10.002, 0.001, -0.003});
  all.push_back({"tiny sphere beside a big one", tiny, big, false});
  all.push_back({"big sphere beside a tiny one", big, tiny, false});
  // Zero-area triangles on both sides, closest to each other.
  Mesh d1 = withDegenerateTriangles(primitives::granulate(11), {1.1, 0.0, 0.0});
  Mesh d2 = withDegenerateTriangles(primitives::granulate(12), {-1.05, 0.01, 0.02});
  d2.translate({2.6, 0, 0});
  all.push_back({"zero-area triangles", d1, d2, false});
  return all;
}

TEST(MinimumDistance, PrunedSearchMatchesEveryPairOnAdversarialScenes) {
  for (const AdversarialScene& scene : adversarialScenes()) {
    const MinimumDistance expected = smallestPairByBruteForce(scene.first, scene.second);
    const double size = scene.first.bounds().diagonal() + scene.second.bounds().diagonal();
    const double tolerance = 1e-12 * (size + maxAbs(scene.first.bounds().upper));
    const TriangleSoA first = flatten(scene.first), second = flatten(scene.second);
    const QueryMesh preparedFirst(scene.first), preparedSecond(scene.second);
    for (kernels::Solver solver : {kernels::Solver::Hybrid, kernels::Solver::BruteForce})
      for (bool prepared : {false, true}) {  // flattened blocks, and the QueryMesh trees
        const std::string label =
            scene.name + ", " + kernels::name(solver) + (prepared ? ", QueryMesh" : "");
        const MinimumDistance actual = prepared
                                           ? minimumDistance(preparedFirst, preparedSecond, solver)
                                           : minimumDistance(first, second, solver);
        EXPECT_NEAR(actual.distance, expected.distance, tolerance) << label;
        EXPECT_EQ(actual.intersect, expected.intersect) << label;
        const auto check = kernels::triangleDistanceBruteForce(
            scene.first.triangle(actual.first), scene.second.triangle(actual.second));
        EXPECT_NEAR(std::sqrt(check.distanceSquared), expected.distance, tolerance) << label;
        EXPECT_NEAR(distance(actual.p, actual.q), actual.distance, tolerance) << label;
        if (solver == kernels::Solver::BruteForce) {
          // every pair computed by the same scalar code: the reference to the bit
          EXPECT_EQ(std::bit_cast<std::uint64_t>(actual.distance),
                    std::bit_cast<std::uint64_t>(expected.distance))
              << label << ": " << actual.distance << " vs " << expected.distance;
          EXPECT_EQ(actual.p, expected.p) << label;
          EXPECT_EQ(actual.q, expected.q) << label;
        }
        if (solver == kernels::Solver::BruteForce || scene.exactTies || expected.intersect) {
          EXPECT_EQ(actual.first, expected.first) << label;
          EXPECT_EQ(actual.second, expected.second) << label;
        }
        // the same distance with the meshes swapped
        const MinimumDistance swapped = prepared
                                            ? minimumDistance(preparedSecond, preparedFirst, solver)
                                            : minimumDistance(second, first, solver);
        EXPECT_NEAR(swapped.distance, expected.distance, tolerance) << label << ", swapped";
      }
  }
}

TEST(MinimumDistance, PenaltyAnswerIsTheAllPairsPenaltyAnswer) {
  // The penalty's closest points lie on the triangles, so its distances are never below the
  // true ones and the box bounds hold for it too: the pruned search must give the answer of
  // every pair by the penalty solver (whose lanes do not depend on their neighbours), bit for
  // bit, even where that answer is approximate.
  kernels::PairResults results(256);
  for (const AdversarialScene& scene : adversarialScenes()) {
    const TriangleSoA first = flatten(scene.first), second = flatten(scene.second);
    MinimumDistance expected;
    double expectedSquared = INFINITY;
    for (std::uint32_t i = 0; i < first.size(); ++i)
      for (std::size_t begin = 0; begin < second.size(); begin += 256) {
        kernels::distances(kernels::Solver::Penalty, first.triangle(i), second, begin, begin + 256,
                           results);
        for (std::size_t k = 0; k < results.size(); ++k)
          if (results.distanceSquared(k) < expectedSquared) {
            expectedSquared = results.distanceSquared(k);
            expected = {results.distance(k),
                        i,
                        static_cast<std::uint32_t>(begin + k),
                        results.p(k),
                        results.q(k),
                        results.intersect(k)};
          }
      }
    const MinimumDistance actual = minimumDistance(first, second, kernels::Solver::Penalty);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(actual.distance),
              std::bit_cast<std::uint64_t>(expected.distance))
        << scene.name << ": " << actual.distance << " vs " << expected.distance;
    EXPECT_EQ(actual.first, expected.first) << scene.name;
    EXPECT_EQ(actual.second, expected.second) << scene.name;
    EXPECT_EQ(actual.p, expected.p) << scene.name;
    EXPECT_EQ(actual.q, expected.q) << scene.name;
    EXPECT_EQ(actual.intersect, expected.intersect) << scene.name;
  }
}

TEST(MinimumDistance, TiesInEveryBlockGoToTheSmallestIds) {
  // One big triangle under a shuffled grid: each of its 800 triangles is exactly 0.5 away, in
  // every block of the search; the answer is the smallest id, here and with the roles swapped.
  const Mesh floor({{-10, -10, 0}, {60, -10, 0}, {-10, 60, 0}}, {{{0, 1, 2}}});
  const Mesh tiles = shuffled(grid(20, 0.5), 7);
  for (kernels::Solver solver : {kernels::Solver::Hybrid, kernels::Solver::BruteForce}) {
    const MinimumDistance down = minimumDistance(flatten(tiles), flatten(floor), solver);
    EXPECT_EQ(down.distance, 0.5) << kernels::name(solver);
    EXPECT_EQ(down.first, 0u) << kernels::name(solver);
    EXPECT_EQ(down.second, 0u) << kernels::name(solver);
    const MinimumDistance up = minimumDistance(flatten(floor), flatten(tiles), solver);
    EXPECT_EQ(up.distance, 0.5) << kernels::name(solver);
    EXPECT_EQ(up.first, 0u) << kernels::name(solver);
    EXPECT_EQ(up.second, 0u) << kernels::name(solver);
  }
}

TEST(MinimumDistance, SameAnswerToTheBitForAnyThreadCountWithTies) {
  const Mesh first = grid(16, 0.0);
  const Mesh second = shuffled(grid(16, 0.25, 0.5, 0.5), 8);
  const TriangleSoA a = flatten(first), b = flatten(second);
  const int threads = omp_get_max_threads();
  for (kernels::Solver solver : {kernels::Solver::Hybrid, kernels::Solver::BruteForce}) {
    omp_set_num_threads(1);
    const MinimumDistance serial = minimumDistance(a, b, solver);
    omp_set_num_threads(2);
    const MinimumDistance parallel = minimumDistance(a, b, solver);
    omp_set_num_threads(threads);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(parallel.distance),
              std::bit_cast<std::uint64_t>(serial.distance));
    EXPECT_EQ(parallel.first, serial.first);
    EXPECT_EQ(parallel.second, serial.second);
    EXPECT_EQ(parallel.p, serial.p);
    EXPECT_EQ(parallel.q, serial.q);
    EXPECT_EQ(parallel.intersect, serial.intersect);
    const MinimumDistance expected = smallestPairByBruteForce(first, second);
    EXPECT_EQ(serial.first, expected.first);
    EXPECT_EQ(serial.second, expected.second);
  }
}

TEST(MinimumDistance, RejectsAnEmptyMesh) {
  EXPECT_THROW(minimumDistance(TriangleSoA(), flatten(primitives::box())), Error);
  EXPECT_THROW(minimumDistance(flatten(primitives::box()), TriangleSoA()), Error);
}

}  // namespace
}  // namespace delta::contactdetection
