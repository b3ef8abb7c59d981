// Δ side by side with its peers (issue 5): Embree 3 and CGAL's AABB tree for points–mesh
// distances, FCL for mesh–mesh distance and collision, on the same meshes, points and threads.
//   build/bench/delta_bench_peers [--mesh PATH]... [--points N] [--threads 1,2]
//       [--workloads W1,W2,W3,W4,W5] [--levels L] [--moves T] [Google Benchmark's flags]
//   build/bench/delta_bench_peers --mesh data/meshes/armadillo.off --benchmark_repetitions=3
//   build/bench/delta_bench_peers --benchmark_filter='^W1/' --benchmark_format=json
//
// Workloads (ε and the bands are fractions of the mesh's bounding-box diagonal D):
//   W1 distance      N points uniform in the box grown by 10% per side (the same points as
//                    `delta distance --points builtin:uniform:N`): the exact unsigned distance.
//   W2 contacts      the same points, only those closer than ε = 1% of D.
//   W3 near surface  N points within ±1% of D of the surface (area-weighted random triangle,
//                    random barycentric point, moved along the face normal): exact distance.
//   W4a min distance the mesh against a copy turned 0.6 rad about (1,2,3) around the box centre
//                    and moved along a fixed direction until the gap is 0.1% of D (bisection on
//                    Δ's minimumDistance): the minimum distance.
//   W4b contacts     the same copy moved 5% of D further in: Δ's contacts closer than 2ε,
//                    ε = 10⁻⁶ D, against FCL's intersecting triangle pairs.
//   W5 grid vertices the vertices of an immersed-boundary grid (ib::AdaptiveGrid, levels L,
//                    default 7) refined around the mesh: the exact unsigned distance, and Δ's
//                    signed distance too (Delta-signed) when the mesh is closed. Not in the
//                    default list: run it with --workloads W5. Δ alone also times the grid
//                    itself, per thread count: W5-build, an iteration the grid's build (signed
//                    when the mesh is closed), and W5-moves, T moves (default 10) of the boundary,
//                    an iteration each, every move turning it about its box centre and moving it
//                    so that its furthest vertex moves 0.2 h, h the finest cell's diagonal
//                    (bench/boundary_step.h; the motion is computed outside the timing), from the
//                    built grid. Their counters: vertices, leaves, queries (per build or move),
//                    queries_per_s_in_delta and share_in_delta (the time inside Δ's distance
//                    queries, GridStatistics::querySeconds, and its share). The grid's distances
//                    must equal a direct signed query at its vertices, and its vertices and
//                    distances, built and moved, must not depend on the thread count.
//
// Timing: Google Benchmark. Every mesh, workload, library and thread count is a benchmark named
// W1/armadillo/Embree/threads:2 (libraries Delta, Delta-signed, Embree, CGAL, and FCL on one
// thread: it has no parallel traversal), timed in real time: an iteration is one query, the same
// call into an output buffer made beforehand, and Google Benchmark repeats it until
// --benchmark_min_time (0.5 s) has passed; --benchmark_repetitions=N reports the mean, median and
// spread of N such runs, and --benchmark_min_warmup_time=T runs it untimed first. What a query
// needs (the points, Δ's QueryMesh and each peer's structure per thread count — CGAL's once, its
// build is serial —, W4's scene and models, W5's grid) is made when a benchmark first needs it,
// outside the timing, and kept until the benchmarks move on to the next mesh. Counters:
// build_s and bytes_per_triangle of the structure queried (the label says how the bytes were
// counted), points and queries_per_s, within_eps (W2), inside (Delta-signed), max_diff_over_D (a
// peer's largest |peer − Δ| / D), and W4's counts. After Google Benchmark's output comes a table
// of peer/Δ query times per workload and thread count (the medians with repetitions): on stdout
// with the console table, on stderr with --benchmark_format=json or csv, so that stdout holds
// Google Benchmark's report alone (--benchmark_format=json replaces the former --json).
//
// Agreement, checked after each benchmark's timed loop on its last answers: every peer answer
// against Δ's on the first thread count of --threads within 10⁻⁹ D (W1, W3, W5; W2: the same
// points within ε, except points whose distance is within 10⁻⁹ D of ε; W4a: the minimum distance;
// W4b: the same intersecting triangle pairs), and Δ's answers on every thread count against the
// first's, bit for bit (signed: |d| equal to the unsigned distance too). A disagreement stops the
// benchmark with an error in its row; it is settled by brute force over all triangles with an
// exact oracle (CGAL; the first 3 of each benchmark) on stderr, and makes the exit code 1 (2: bad
// options, an unreadable mesh, or a benchmark that stopped on an exception).
#include <benchmark/benchmark.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "delta/ib/adaptive_grid.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/topology.h"
#include "delta/query/contacts.h"
#include "delta/query/minimum_distance.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"

#include "bench_main.h"
#include "boundary_step.h"
#include "omp_threads.h"
#include "peers.h"
#include "report.h"

namespace {

using delta::Mesh;
using delta::QueryMesh;
using delta::RigidTransform;
using delta::Triangle;
using delta::Vec3;
namespace cd = delta::contactdetection;
namespace ib = delta::ib;
namespace bench = delta::bench;
using bench::OmpThreads;
using bench::withCommas;

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

constexpr double kAgreementFraction = 1e-9;    // of the diagonal
constexpr double kContactFraction = 0.01;      // W2's ε and W3's band
constexpr double kGapFraction = 1e-3;          // W4a's gap
constexpr double kOverlapFraction = 0.05;      // W4b's overlap
constexpr double kMeshEpsilonFraction = 1e-6;  // W4b's ε
constexpr double kStepInCells = 0.2;           // W5's motion a move, in finest-cell diagonals
constexpr int kMaxLevels = 20;                 // ib::GridOptions::levels
constexpr std::size_t kFclMaxContacts = 100'000'000;
constexpr std::size_t kDisputesShown = 3;  // disagreements settled by brute force, each
constexpr std::uint64_t kUniformSeed = 1;  // as `delta distance --points builtin:uniform:N`
constexpr std::uint64_t kNearSurfaceSeed = 3;
constexpr double kRotationRadians = 0.6;
const Vec3 kRotationAxis{1, 2, 3};
const Vec3 kApproach = delta::normalized(Vec3{1, 0.5, 0.25});  // the copy moves along this

// ---------------------------------------------------------------------------------------------
// Options

struct Options {
  std::vector<std::string> meshes;
  std::size_t points = 1'000'000;
  std::vector<int> threads{1, 2};
  std::array<bool, 5> workloads{true, true, true, true, false};
  int levels = 7;  // W5
  int moves = 10;  // W5
};

constexpr const char* kUsage =
    "usage: delta_bench_peers [--mesh PATH]... [--points N] [--threads LIST] "
    "[--workloads W1,W2,W3,W4,W5] [--levels L] [--moves T] [Google Benchmark's flags]\n"
    "  --mesh PATH      a mesh file (repeatable; default CGAL's armadillo, bunny00 and\n"
    "                   refined_elephant from " DELTA_DATA_DIR
    "/meshes)\n"
    "  --points N       query points for W1-W3 (default 1000000)\n"
    "  --threads LIST   thread counts, comma-separated (default 1,2)\n"
    "  --workloads LIST any of W1,W2,W3,W4,W5 (default W1,W2,W3,W4)\n"
    "  --levels L       W5: the grid's finest level, 1 to 20 (default 7)\n"
    "  --moves T        W5: moves of the boundary (default 10)\n"
    "Every other argument goes to Google Benchmark (listed below), which refuses what it does\n"
    "not know: --benchmark_filter=REGEX (benchmarks are named W1/armadillo/Embree/threads:2),\n"
    "--benchmark_repetitions=N, --benchmark_out=FILE, and --benchmark_format=json, which\n"
    "replaces the former --json (the table of peer/Δ ratios then goes to stderr).\n";

[[noreturn]] void usageError(const std::string& message) {
  std::fprintf(stderr, "delta_bench_peers: %s\n%s", message.c_str(), kUsage);
  std::exit(2);
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream stream(text);
  for (std::string item; std::getline(stream, item, ',');)
    if (!item.empty()) items.push_back(item);
  return items;
}

long long positiveInteger(const std::string& text, const char* option) {
  std::size_t used = 0;
  long long value = 0;
  try {
    value = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || value <= 0)
    usageError(std::string(option) + " wants a positive integer, not '" + text + "'");
  return value;
}

/// The program's own options, from argv; the other arguments (Google Benchmark's flags, and
/// anything else, for benchmark::Initialize to refuse) go to `rest`, after argv[0].
Options parseOptions(int argc, char** argv, std::vector<char*>& rest) {
  Options options;
  rest.assign(argv, argv + 1);
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) usageError(argument + " needs a value");
      return argv[++i];
    };
    if (argument == "--help" || argument == "-h") {
      std::fputs(kUsage, stdout);
      benchmark::PrintDefaultHelp();
      std::exit(0);
    } else if (argument == "--mesh") {
      options.meshes.push_back(value());
    } else if (argument == "--points") {
      options.points = static_cast<std::size_t>(positiveInteger(value(), "--points"));
    } else if (argument == "--threads") {
      options.threads.clear();
      for (const std::string& item : splitList(value()))
        options.threads.push_back(static_cast<int>(positiveInteger(item, "--threads")));
      if (options.threads.empty()) usageError("--threads wants a list such as 1,2");
    } else if (argument == "--workloads") {
      options.workloads = {false, false, false, false, false};
      for (const std::string& item : splitList(value())) {
        if (item.size() != 2 || (item[0] != 'W' && item[0] != 'w') || item[1] < '1' ||
            item[1] > '5')
          usageError("unknown workload '" + item + "' (W1, W2, W3, W4 or W5)");
        options.workloads[static_cast<std::size_t>(item[1] - '1')] = true;
      }
    } else if (argument == "--levels") {
      const long long levels = positiveInteger(value(), "--levels");
      if (levels > kMaxLevels) usageError("--levels wants 1 to " + std::to_string(kMaxLevels));
      options.levels = static_cast<int>(levels);
    } else if (argument == "--moves") {
      options.moves = static_cast<int>(positiveInteger(value(), "--moves"));
    } else if (argument == "--json") {
      usageError("--json is gone: Google Benchmark's --benchmark_format=json replaces it");
    } else {
      rest.push_back(argv[i]);
    }
  }
  if (options.meshes.empty())
    for (const char* name : {"armadillo.off", "bunny00.off", "refined_elephant.off"})
      options.meshes.push_back(std::string(DELTA_DATA_DIR) + "/meshes/" + name);
  return options;
}

/// The seconds `run` took (a structure's build; queries are timed by Google Benchmark).
double secondsOf(const std::function<void()>& run) {
  const auto start = std::chrono::steady_clock::now();
  run();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// ---------------------------------------------------------------------------------------------
// Query points

double unit(std::mt19937_64& random) {
  return static_cast<double>(random() >> 11) * 0x1p-53;
}

/// Uniform in the box grown by 10% per side: apps/delta/point_source.cpp's builtin:uniform.
std::vector<Vec3> uniformPoints(const delta::Aabb& box, std::size_t count, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  const Vec3 lower = box.lower - box.extent() * 0.1, size = box.extent() * 1.2;
  std::vector<Vec3> points(count);
  for (Vec3& p : points) {
    const double x = unit(random), y = unit(random), z = unit(random);
    p = {lower.x + size.x * x, lower.y + size.y * y, lower.z + size.z * z};
  }
  return points;
}

/// Within ±band of the surface: a triangle drawn by area, a uniform point on it, moved along the
/// unit face normal by a uniform offset in [−band, band].
std::vector<Vec3> nearSurfacePoints(const Mesh& mesh, double band, std::size_t count,
                                    std::uint64_t seed) {
  std::vector<double> cumulativeArea(mesh.triangleCount());
  double total = 0.0;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t)
    cumulativeArea[t] = total += mesh.triangle(t).area();
  std::mt19937_64 random(seed);
  std::vector<Vec3> points(count);
  for (Vec3& p : points) {
    const double pick = unit(random) * total;
    const auto found = std::upper_bound(cumulativeArea.begin(), cumulativeArea.end(), pick);
    const std::size_t t = std::min(static_cast<std::size_t>(found - cumulativeArea.begin()),
                                   mesh.triangleCount() - 1);
    const Triangle triangle = mesh.triangle(t);
    double u = unit(random), v = unit(random);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    const double offset = (2.0 * unit(random) - 1.0) * band;
    p = triangle.a + (triangle.b - triangle.a) * u + (triangle.c - triangle.a) * v +
        delta::normalized(triangle.areaVector()) * offset;
  }
  return points;
}

// ---------------------------------------------------------------------------------------------
// Agreement

struct Comparison {
  std::size_t disagreements = 0;
  double maxDifference = 0.0;  // over the points both answered
  std::vector<std::size_t> examples;
};

/// Every distance within `tolerance` of Δ's.
Comparison compareDistances(const std::vector<double>& reference, const std::vector<double>& peer,
                            double tolerance) {
  Comparison comparison;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const double difference = std::abs(peer[i] - reference[i]);
    if (std::isfinite(difference))
      comparison.maxDifference = std::max(comparison.maxDifference, difference);
    if (difference <= tolerance) continue;
    ++comparison.disagreements;  // NaN and ∞ land here too
    if (comparison.examples.size() < kDisputesShown) comparison.examples.push_back(i);
  }
  return comparison;
}

/// The same points within ε (+∞ marks "not within"), except where Δ's unbounded distance is
/// within `tolerance` of ε, and the same distances for the points both found.
Comparison compareWithin(const QueryMesh& mesh, std::span<const Vec3> points,
                         const std::vector<double>& reference, const std::vector<double>& peer,
                         double epsilon, double tolerance) {
  Comparison comparison;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    const bool inReference = std::isfinite(reference[i]), inPeer = std::isfinite(peer[i]);
    if (inReference && inPeer) {
      const double difference = std::abs(peer[i] - reference[i]);
      comparison.maxDifference = std::max(comparison.maxDifference, difference);
      if (difference <= tolerance) continue;
    } else if (inReference == inPeer) {
      continue;
    } else if (std::abs(cd::distance(mesh, points[i]).distance - epsilon) <= tolerance) {
      continue;  // on the boundary of the ε-ball: either answer is right
    }
    ++comparison.disagreements;
    if (comparison.examples.size() < kDisputesShown) comparison.examples.push_back(i);
  }
  return comparison;
}

std::string fullPrecision(const Vec3& p) {
  char text[128];
  std::snprintf(text, sizeof text, "{%.17g, %.17g, %.17g}", p.x, p.y, p.z);
  return text;
}

/// Settles a distance disagreement at one point by brute force: Δ's point–triangle kernel over
/// every triangle, then, where CGAL is available, the exact oracle on every triangle within
/// 10⁻⁶ D of that minimum. The answers are those of a query bounded by `radius` (+∞ where the
/// point is not closer than it); says which of them the truth is within the tolerance of.
std::string settlePoint(const Mesh& mesh, const Vec3& p, double radius, double deltaDistance,
                        double peerDistance, const std::string& peer, double tolerance,
                        double diagonal) {
  double bruteForce = kInfinity;
  std::size_t closest = 0;
  std::vector<double> distances(mesh.triangleCount());
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    distances[t] =
        std::sqrt(delta::kernels::closestPointOnTriangle(p, mesh.triangle(t)).distanceSquared);
    if (distances[t] < bruteForce) bruteForce = distances[t], closest = t;
  }
  double truth = bruteForce;
  std::string how = "brute force (Δ's kernel, every triangle)";
#if defined(DELTA_HAVE_CGAL)
  truth = kInfinity;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t)
    if (distances[t] <= bruteForce + 1e-6 * diagonal) {
      const double exact = bench::exactDistance(p, mesh.triangle(t));
      if (exact < truth) truth = exact, closest = t;
    }
  how = "brute force + exact CGAL oracle";
#else
  (void)diagonal;
#endif
  const auto right = [&](double answer) {
    if (std::abs(truth - radius) <= tolerance) return true;  // either side of the ε-sphere
    if (!(truth < radius)) return std::isinf(answer);
    return std::abs(answer - truth) <= tolerance;
  };
  const bool deltaRight = right(deltaDistance), peerRight = right(peerDistance);
  char text[512];
  std::snprintf(text, sizeof text,
                "point %s: Δ %.17g, %s %.17g; %s: %.17g (triangle %zu, brute force %.17g) -> %s",
                fullPrecision(p).c_str(), deltaDistance, peer.c_str(), peerDistance, how.c_str(),
                truth, closest, bruteForce,
                deltaRight && peerRight ? "both right"
                : deltaRight            ? (peer + " is wrong").c_str()
                : peerRight             ? "Δ is wrong"
                                        : "both wrong");
  return text;
}

std::vector<double> distancesOf(const std::vector<cd::PointDistance>& answers) {
  std::vector<double> out(answers.size());
  for (std::size_t i = 0; i < answers.size(); ++i)
    out[i] = answers[i].distance;
  return out;
}

std::size_t countFinite(const std::vector<double>& distances) {
  return static_cast<std::size_t>(
      std::count_if(distances.begin(), distances.end(), [](double d) { return std::isfinite(d); }));
}

/// How many distances differ from the reference's, bit for bit.
std::size_t countDiffering(const std::vector<double>& distances,
                           const std::vector<double>& reference) {
  std::size_t differing = 0;
  for (std::size_t i = 0; i < distances.size(); ++i)
    differing += distances[i] != reference[i] ? 1 : 0;
  return differing;
}

// ---------------------------------------------------------------------------------------------
// W4

Mesh moved(const Mesh& mesh, const RigidTransform& motion) {
  Mesh copy = mesh;
  copy.transform(motion);
  return copy;
}

/// The copy's motion: turned about the box centre, then moved `shift` along kApproach.
RigidTransform copyMotion(const Mesh& mesh, double shift) {
  const RigidTransform turn = RigidTransform::rotationAbout(
      delta::Quaternion::fromAxisAngle(kRotationAxis, kRotationRadians), mesh.bounds().center());
  return RigidTransform::translationBy(kApproach * shift) * turn;
}

/// The shift along kApproach that leaves a gap of `gap` (to 1%) between the mesh and its turned
/// copy: bisection on Δ's minimum distance, from the turned copy in place (overlapping) to 2 D
/// away (clear of it).
double shiftForGap(const Mesh& mesh, double gap, double diagonal) {
  const delta::TriangleSoA fixed = delta::flatten(mesh);
  const auto gapAt = [&](double shift) {
    return cd::minimumDistance(fixed, delta::flatten(moved(mesh, copyMotion(mesh, shift))))
        .distance;
  };
  double low = 0.0, high = 2.0 * diagonal;
  if (gapAt(low) >= gap || gapAt(high) <= gap)
    throw std::runtime_error("W4: the turned copy does not cross the gap between 0 and 2 D");
  for (int step = 0; step < 200; ++step) {
    const double middle = 0.5 * (low + high), at = gapAt(middle);
    if (std::abs(at - gap) <= 0.01 * gap) return middle;
    (at < gap ? low : high) = middle;
  }
  return 0.5 * (low + high);
}

std::string pairNote(double distance, std::uint32_t first, std::uint32_t second) {
  char text[128];
  std::snprintf(text, sizeof text, "d = %.10g (triangles %u, %u)", distance, first, second);
  return text;
}

/// W4's scene: the mesh and its turned copy, moved to a small gap (W4a) and into a small
/// overlap (W4b).
struct MeshMeshScene {
  const Mesh& mesh;
  double diagonal, tolerance, triangles, epsilon;
  RigidTransform gapMotion, overlapMotion;
  Mesh gapCopy, overlapCopy;
  std::string gapName = "W4a min distance", contactName = "W4b contacts";
};

MeshMeshScene meshMeshScene(const Mesh& mesh, double diagonal) {
  const double gapShift = shiftForGap(mesh, kGapFraction * diagonal, diagonal);
  const double overlapShift = gapShift - kOverlapFraction * diagonal;
  const RigidTransform gapMotion = copyMotion(mesh, gapShift);
  const RigidTransform overlapMotion = copyMotion(mesh, overlapShift);
  return {mesh,
          diagonal,
          kAgreementFraction * diagonal,
          2.0 * static_cast<double>(mesh.triangleCount()),
          kMeshEpsilonFraction * diagonal,
          gapMotion,
          overlapMotion,
          moved(mesh, gapMotion),
          moved(mesh, overlapMotion)};
}

/// Δ's W4b answer as triangle pairs: the (first, second) ids of every contact, in Δ's order,
/// and of those at distance 0 (intersecting).
struct ContactPairs {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> all, intersecting;
  std::size_t overlapping = 0;
};

ContactPairs contactPairs(const std::vector<delta::ContactPoint>& contacts) {
  ContactPairs pairs;
  for (const delta::ContactPoint& contact : contacts) {
    pairs.all.emplace_back(contact.first, contact.second);
    pairs.overlapping += contact.overlap ? 1 : 0;
    if (contact.distance == 0.0) pairs.intersecting.emplace_back(contact.first, contact.second);
  }
  return pairs;
}

// ---------------------------------------------------------------------------------------------
// W5

/// Where `grid`'s vertices are and the distances it holds, to compare grids.
struct GridField {
  std::vector<Vec3> positions;
  std::vector<double> distances;

  explicit GridField(const delta::ib::AdaptiveGrid& grid)
      : positions(grid.positions()), distances(grid.distances().begin(), grid.distances().end()) {}
  bool operator==(const GridField&) const = default;
};

// ---------------------------------------------------------------------------------------------
// What the benchmarks share

enum class Workload { W1, W2, W3, W4a, W4b, W5, W5Build, W5Moves };
enum class Library { Delta, DeltaSigned, Embree, Cgal, Fcl };

const char* nameOf(Workload workload) {
  constexpr std::array<const char*, 8> names{"W1",  "W2", "W3",       "W4a",
                                             "W4b", "W5", "W5-build", "W5-moves"};
  return names[static_cast<std::size_t>(workload)];
}

const char* nameOf(Library library) {
  constexpr std::array<const char*, 5> names{"Delta", "Delta-signed", "Embree", "CGAL", "FCL"};
  return names[static_cast<std::size_t>(library)];
}

/// A mesh of --mesh, loaded before any benchmark is registered, and the name its benchmarks
/// carry (the file's stem, with -2, -3, … where two files share one).
struct LoadedMesh {
  std::string path, name;
  Mesh mesh;
  double diagonal = 0.0;
  bool closed = false;  // closed and consistently oriented: QueryMesh::closed()
};

/// Δ's prepared mesh on one thread count, and the seconds its build took.
struct DeltaMesh {
  std::optional<QueryMesh> mesh;
  double buildSeconds = 0.0;
};

/// W4's two prepared meshes, the copy moved rigidly to its place as FCL's models are (the DEM
/// case), and the seconds both builds took.
struct DeltaPair {
  std::optional<QueryMesh> first, second;
  double buildSeconds = 0.0;
};

#if defined(DELTA_HAVE_FCL)
/// FCL's two models, and the seconds their build took.
struct FclPair {
  std::unique_ptr<bench::FclMeshPair> models;
  double buildSeconds = 0.0;
};
#endif

/// W5's grid built on the first thread count, which every thread count's grid must equal.
struct GridReference {
  std::optional<QueryMesh> boundary;  // its own, so that the grid's data is not counted in the
                                      // memoryBytes() of the QueryMesh the W5 queries use
  ib::GridOptions options;
  double cellDiagonal = 0.0;  // of a finest cell, h
  double step = 0.0;          // how far the furthest vertex moves in one move
  std::optional<ib::AdaptiveGrid> built;
  std::optional<GridField> builtField;
  std::size_t differingFromDirect = 0;  // vertices whose distance is not a direct query's
};

/// What the benchmarks of one mesh share, each part made the first time a benchmark needs it
/// (before its timed loop), then kept. Δ's reference answers are its answers on the first
/// thread count of --threads, made there whichever benchmarks a filter leaves.
///
/// Threading: one benchmark at a time; every part is made on the thread count it belongs to.
class MeshState {
 public:
  MeshState(const LoadedMesh& loaded, const Options& options)
      : loaded_(loaded), options_(options) {}

  const LoadedMesh& loaded() const noexcept { return loaded_; }
  const Mesh& mesh() const noexcept { return loaded_.mesh; }
  double diagonal() const noexcept { return loaded_.diagonal; }
  double tolerance() const noexcept { return kAgreementFraction * loaded_.diagonal; }
  int firstThreads() const noexcept { return options_.threads.front(); }
  double triangles() const noexcept { return static_cast<double>(mesh().triangleCount()); }

  /// The query points: W1 and W2 the uniform points, W3 those near the surface, W5 the grid's
  /// vertices.
  const std::vector<Vec3>& points(Workload workload) {
    switch (workload) {
      case Workload::W3:
        if (!nearSurface_)
          nearSurface_ = nearSurfacePoints(mesh(), kContactFraction * diagonal(), options_.points,
                                           kNearSurfaceSeed);
        return *nearSurface_;
      case Workload::W5:
        return grid().builtField->positions;
      default:
        if (!uniform_) uniform_ = uniformPoints(mesh().bounds(), options_.points, kUniformSeed);
        return *uniform_;
    }
  }

  /// The query's radius: W2's ε, +∞ (unbounded) for the others.
  double radius(Workload workload) const {
    return workload == Workload::W2 ? kContactFraction * diagonal() : kInfinity;
  }

  const DeltaMesh& deltaMesh(int threads) {
    DeltaMesh& built = deltaMeshes_[threads];
    if (!built.mesh) {
      const OmpThreads omp(threads);
      built.buildSeconds = secondsOf([&] { built.mesh.emplace(mesh()); });
    }
    return built;
  }

  /// Embree's scene for `threads` (its device has that many), or CGAL's tree (one for every
  /// thread count: its build is serial).
  const bench::PointDistancePeer& peer(Library library, int threads) {
    std::unique_ptr<bench::PointDistancePeer>& peer =
        peers_[{library, library == Library::Cgal ? 0 : threads}];
    if (!peer) {
      const OmpThreads omp(threads);
#if defined(DELTA_HAVE_EMBREE)
      if (library == Library::Embree) peer = bench::makeEmbreePeer(mesh(), threads);
#endif
#if defined(DELTA_HAVE_CGAL)
      if (library == Library::Cgal) peer = bench::makeCgalPeer(mesh());
#endif
      if (!peer) throw std::logic_error(std::string("no points–mesh peer ") + nameOf(library));
    }
    return *peer;
  }

  /// Δ's unsigned distances (+∞ beyond the radius) on the first thread count.
  const std::vector<double>& reference(Workload workload) {
    const auto found = references_.find(workload);
    if (found != references_.end()) return found->second;
    const std::vector<cd::PointDistance> answers = firstAnswers(workload, false);
    return references_.emplace(workload, distancesOf(answers)).first->second;
  }

  /// Δ's signed distances on the first thread count.
  const std::vector<double>& signedReference(Workload workload) {
    const auto found = signedReferences_.find(workload);
    if (found != signedReferences_.end()) return found->second;
    const std::vector<cd::PointDistance> answers = firstAnswers(workload, true);
    std::vector<double> distances(answers.size());
    for (std::size_t i = 0; i < answers.size(); ++i)
      distances[i] = answers[i].signedDistance();
    return signedReferences_.emplace(workload, std::move(distances)).first->second;
  }

  /// W4's scene, found on the largest thread count.
  const MeshMeshScene& scene() {
    if (!scene_) {
      const OmpThreads omp(*std::max_element(options_.threads.begin(), options_.threads.end()));
      scene_.emplace(meshMeshScene(mesh(), diagonal()));
    }
    return *scene_;
  }

  /// Δ's two meshes of W4a (the copy at the gap) or W4b (the copy overlapping).
  const DeltaPair& deltaPair(Workload workload, int threads) {
    DeltaPair& pair = deltaPairs_[{workload, threads}];
    if (!pair.first) {
      const RigidTransform& motion =
          workload == Workload::W4a ? scene().gapMotion : scene().overlapMotion;
      const OmpThreads omp(threads);
      pair.buildSeconds = secondsOf([&] {
        pair.first.emplace(mesh());
        pair.second.emplace(mesh());
      });
      pair.second->transform(motion);
    }
    return pair;
  }

  /// Δ's W4a answer on the first thread count.
  const cd::MinimumDistance& minimumReference() {
    if (!minimum_) {
      const DeltaPair& pair = deltaPair(Workload::W4a, firstThreads());
      const OmpThreads omp(firstThreads());
      minimum_ = cd::minimumDistance(*pair.first, *pair.second);
    }
    return *minimum_;
  }

  /// Δ's W4b answer on the first thread count.
  const ContactPairs& contactsReference() {
    if (!contacts_) {
      const DeltaPair& pair = deltaPair(Workload::W4b, firstThreads());
      const double epsilon = scene().epsilon;
      const OmpThreads omp(firstThreads());
      contacts_ = contactPairs(cd::contacts(*pair.first, *pair.second, epsilon));
    }
    return *contacts_;
  }

#if defined(DELTA_HAVE_FCL)
  const FclPair& fcl() {
    if (!fcl_) {
      FclPair built;
      built.buildSeconds = secondsOf([&] { built.models = bench::makeFclPair(mesh(), mesh()); });
      fcl_ = std::move(built);
    }
    return *fcl_;
  }
#endif

  /// W5's grid, built on the first thread count (signed where the mesh is closed), and checked
  /// against direct queries at its vertices.
  const GridReference& grid() {
    if (grid_) return *grid_;
    const OmpThreads omp(firstThreads());
    GridReference grid;
    const QueryMesh& boundary = grid.boundary.emplace(mesh());
    grid.options = {.levels = options_.levels, .signedDistance = boundary.closed()};
    grid.built.emplace(boundary, grid.options);
    grid.builtField.emplace(*grid.built);
    const std::vector<Vec3>& positions = grid.builtField->positions;
    const std::vector<cd::PointDistance> direct =
        cd::distances(boundary, positions, {.signedDistance = grid.options.signedDistance});
    for (std::size_t v = 0; v < direct.size(); ++v) {
      const double expected =
          grid.options.signedDistance ? direct[v].signedDistance() : direct[v].distance;
      grid.differingFromDirect += expected != grid.builtField->distances[v] ? 1 : 0;
    }
    grid.cellDiagonal = grid.built->cellDiagonal(options_.levels);
    grid.step = kStepInCells * grid.cellDiagonal;
    return grid_.emplace(std::move(grid));
  }

  /// W5's grid after --moves moves from where it was built, on the first thread count.
  const GridField& movedGrid() {
    if (!moved_) {
      const GridReference& reference = grid();
      const OmpThreads omp(firstThreads());
      ib::AdaptiveGrid moving = *reference.built;
      for (int move = 0; move < options_.moves; ++move)
        moving.moveBoundary(bench::boundaryStep(moving.boundary(), reference.step));
      moved_.emplace(moving);
    }
    return *moved_;
  }

 private:
  std::vector<cd::PointDistance> firstAnswers(Workload workload, bool signedDistance) {
    const std::vector<Vec3>& query = points(workload);
    const QueryMesh& queryMesh = *deltaMesh(firstThreads()).mesh;
    const OmpThreads omp(firstThreads());
    std::vector<cd::PointDistance> answers(query.size());
    cd::distances(queryMesh, query, {.epsilon = radius(workload), .signedDistance = signedDistance},
                  answers);
    return answers;
  }

  const LoadedMesh& loaded_;
  const Options& options_;
  std::optional<std::vector<Vec3>> uniform_, nearSurface_;
  std::map<int, DeltaMesh> deltaMeshes_;
  std::map<std::pair<Library, int>, std::unique_ptr<bench::PointDistancePeer>> peers_;
  std::map<Workload, std::vector<double>> references_, signedReferences_;
  std::optional<MeshMeshScene> scene_;
  std::map<std::pair<Workload, int>, DeltaPair> deltaPairs_;
  std::optional<cd::MinimumDistance> minimum_;
  std::optional<ContactPairs> contacts_;
#if defined(DELTA_HAVE_FCL)
  std::optional<FclPair> fcl_;
#endif
  std::optional<GridReference> grid_;
  std::optional<GridField> moved_;
};

/// What every benchmark reaches: the structures of the mesh whose benchmarks run now, and what
/// the checks found. Asked for another mesh, it frees the previous one's structures first: the
/// benchmarks are registered mesh by mesh, so each is made once (unless
/// --benchmark_enable_random_interleaving mixes the meshes).
///
/// Threading: one benchmark at a time.
class Shared {
 public:
  explicit Shared(const Options& options) : options_(options) {}

  MeshState& of(const LoadedMesh& mesh) {
    if (!current_ || &current_->loaded() != &mesh) {
      current_.reset();
      current_ = std::make_unique<MeshState>(mesh, options_);
    }
    return *current_;
  }

  /// Frees the last mesh's structures (before the program's end, while the peers' libraries
  /// are still there to free them).
  void release() { current_.reset(); }

  /// A check of `benchmark` failed: its run stops with `message` as its error and the program
  /// will exit 1. The first time it fails (Google Benchmark may run it several times), the
  /// message and the brute-force verdicts settle() returns, one a line, go to stderr.
  template <class Settle>
  void disagree(benchmark::State& state, const std::string& benchmark, const std::string& message,
                const Settle& settle) {
    if (disagreeing_.insert(benchmark).second) {
      std::fprintf(stderr, "disagreement: %s: %s\n", benchmark.c_str(), message.c_str());
      for (const std::string& verdict : settle())
        std::fprintf(stderr, "  %s\n", verdict.c_str());
    }
    state.SkipWithError(message.c_str());
  }
  void disagree(benchmark::State& state, const std::string& benchmark, const std::string& message) {
    disagree(state, benchmark, message, [] { return std::vector<std::string>{}; });
  }

  /// `benchmark` stopped on an exception: its error, and exit status 2.
  void fail(benchmark::State& state, const std::string& benchmark, const std::exception& error) {
    failing_.insert(benchmark);
    state.SkipWithError(error.what());
  }

  /// "every check passed", or what failed.
  std::string verdict() const {
    if (disagreeing_.empty() && failing_.empty()) return "every check passed";
    std::string verdict = "FAILED:";
    if (!disagreeing_.empty())
      verdict += " " + std::to_string(disagreeing_.size()) + " benchmarks disagree (see stderr)";
    if (!failing_.empty())
      verdict += " " + std::to_string(failing_.size()) + " benchmarks stopped with an error";
    return verdict;
  }

  /// 0, 1 for a disagreement, 2 for a benchmark that stopped on an exception.
  int exitStatus() const { return !disagreeing_.empty() ? 1 : !failing_.empty() ? 2 : 0; }

 private:
  const Options& options_;
  std::unique_ptr<MeshState> current_;
  std::set<std::string> disagreeing_, failing_;
};

/// One benchmark: the mesh, workload, library and thread count it times, and its name.
struct Case {
  const LoadedMesh* mesh = nullptr;
  Workload workload = Workload::W1;
  Library library = Library::Delta;
  int threads = 1;
  std::string name;
};

// ---------------------------------------------------------------------------------------------
// W1–W3, W5's vertices

/// The counters of a points–mesh benchmark: its points, queries per second, and the build
/// seconds and bytes per triangle of the structure it queried; the label says how the bytes
/// were counted.
void setPointCounters(benchmark::State& state, std::size_t points, double buildSeconds,
                      double bytesPerTriangle, const std::string& memoryMethod) {
  const auto count = static_cast<double>(points);
  state.counters["points"] = count;
  state.counters["queries_per_s"] =
      benchmark::Counter(count, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["build_s"] = buildSeconds;
  state.counters["bytes_per_triangle"] = bytesPerTriangle;
  state.SetLabel(memoryMethod);
}

/// Δ's distances of `c`'s points (signed or not) timed, into a buffer made before the clock
/// starts, as every peer's answers are; the counters set.
std::vector<cd::PointDistance> timedDeltaDistances(benchmark::State& state, MeshState& mesh,
                                                   const Case& c, bool signedDistance) {
  const DeltaMesh& built = mesh.deltaMesh(c.threads);
  const std::vector<Vec3>& points = mesh.points(c.workload);
  const cd::PointQuery query{.epsilon = mesh.radius(c.workload), .signedDistance = signedDistance};
  const OmpThreads omp(c.threads);
  std::vector<cd::PointDistance> answers(points.size());
  for (auto _ : state)
    cd::distances(*built.mesh, points, query, answers);
  setPointCounters(state, points.size(), built.buildSeconds,
                   static_cast<double>(built.mesh->memoryBytes()) / mesh.triangles(),
                   "QueryMesh::memoryBytes()");
  return answers;
}

/// Δ's unsigned distances: the first thread count's, bit for bit.
void deltaPoints(benchmark::State& state, Shared& shared, const Case& c) {
  MeshState& mesh = shared.of(*c.mesh);
  const std::vector<double>& reference = mesh.reference(c.workload);
  const std::vector<double> distances = distancesOf(timedDeltaDistances(state, mesh, c, false));
  if (std::isfinite(mesh.radius(c.workload)))
    state.counters["within_eps"] = static_cast<double>(countFinite(distances));
  if (const std::size_t differing = countDiffering(distances, reference); differing > 0)
    shared.disagree(state, c.name,
                    withCommas(differing) + " distances differ from the first thread count's");
}

/// Δ's signed distances (W5, a closed mesh): |d| the unsigned distance and the signed distances
/// the first thread count's, bit for bit.
void deltaSignedPoints(benchmark::State& state, Shared& shared, const Case& c) {
  MeshState& mesh = shared.of(*c.mesh);
  const std::vector<double>& unsignedReference = mesh.reference(c.workload);
  const std::vector<double>& signedReference = mesh.signedReference(c.workload);
  const std::vector<cd::PointDistance> answers = timedDeltaDistances(state, mesh, c, true);
  std::size_t inside = 0, notUnsigned = 0, notFirst = 0;
  for (std::size_t i = 0; i < answers.size(); ++i) {
    inside += answers[i].inside ? 1 : 0;
    notUnsigned += answers[i].distance != unsignedReference[i] ? 1 : 0;
    notFirst += answers[i].signedDistance() != signedReference[i] ? 1 : 0;
  }
  state.counters["inside"] = static_cast<double>(inside);
  if (notUnsigned > 0 || notFirst > 0)
    shared.disagree(state, c.name,
                    withCommas(notUnsigned) + " |d| differ from the unsigned distance, " +
                        withCommas(notFirst) + " signed distances from the first thread count's");
}

/// A peer's distances: every answer against Δ's; the first disagreements settled by brute force.
void peerPoints(benchmark::State& state, Shared& shared, const Case& c) {
  MeshState& mesh = shared.of(*c.mesh);
  const bench::PointDistancePeer& peer = mesh.peer(c.library, c.threads);
  const std::vector<Vec3>& points = mesh.points(c.workload);
  const double radius = mesh.radius(c.workload), tolerance = mesh.tolerance();
  const std::vector<double>& reference = mesh.reference(c.workload);
  const QueryMesh& deltaMesh = *mesh.deltaMesh(mesh.firstThreads()).mesh;
  const OmpThreads omp(c.threads);
  std::vector<double> answers(points.size());
  for (auto _ : state)
    peer.distances(points, radius, answers);
  setPointCounters(state, points.size(), peer.buildSeconds(),
                   static_cast<double>(peer.memoryBytes()) / mesh.triangles(), peer.memoryMethod());
  const Comparison comparison =
      std::isfinite(radius)
          ? compareWithin(deltaMesh, points, reference, answers, radius, tolerance)
          : compareDistances(reference, answers, tolerance);
  if (std::isfinite(radius))
    state.counters["within_eps"] = static_cast<double>(countFinite(answers));
  state.counters["max_diff_over_D"] = comparison.maxDifference / mesh.diagonal();
  if (comparison.disagreements == 0) return;
  shared.disagree(
      state, c.name, withCommas(comparison.disagreements) + " answers differ from Δ's", [&] {
        std::vector<std::string> verdicts;
        for (const std::size_t i : comparison.examples)
          verdicts.push_back("point " + std::to_string(i) + ": " +
                             settlePoint(mesh.mesh(), points[i], radius, reference[i], answers[i],
                                         nameOf(c.library), tolerance, mesh.diagonal()));
        return verdicts;
      });
}

// ---------------------------------------------------------------------------------------------
// W4

/// The counters of a mesh–mesh benchmark: the build seconds and bytes per triangle (of both
/// meshes) of the structures it queried; the label says how the bytes were counted, then
/// `note` where there is one.
void setMeshMeshCounters(benchmark::State& state, double buildSeconds, double bytesPerTriangle,
                         const std::string& memoryMethod, const std::string& note = {}) {
  state.counters["build_s"] = buildSeconds;
  state.counters["bytes_per_triangle"] = bytesPerTriangle;
  state.SetLabel(note.empty() ? memoryMethod : memoryMethod + "; " + note);
}

/// W4a by Δ: the first thread count's minimum distance, bit for bit.
void deltaMinimumDistance(benchmark::State& state, Shared& shared, const Case& c) {
  MeshState& mesh = shared.of(*c.mesh);
  const DeltaPair& pair = mesh.deltaPair(Workload::W4a, c.threads);
  const cd::MinimumDistance& reference = mesh.minimumReference();
  const double triangles = mesh.scene().triangles;
  const OmpThreads omp(c.threads);
  cd::MinimumDistance minimum;
  for (auto _ : state)
    minimum = cd::minimumDistance(*pair.first, *pair.second);
  setMeshMeshCounters(
      state, pair.buildSeconds,
      static_cast<double>(pair.first->memoryBytes() + pair.second->memoryBytes()) / triangles,
      "QueryMesh::memoryBytes(), both meshes",
      pairNote(minimum.distance, minimum.first, minimum.second));
  if (minimum.distance != reference.distance) {
    char text[160];
    std::snprintf(text, sizeof text, "d = %.17g, the first thread count's %.17g", minimum.distance,
                  reference.distance);
    shared.disagree(state, c.name, text);
  }
}

/// W4b by Δ: the first thread count's contacts (their triangle pairs, in order).
void deltaContacts(benchmark::State& state, Shared& shared, const Case& c) {
  MeshState& mesh = shared.of(*c.mesh);
  const DeltaPair& pair = mesh.deltaPair(Workload::W4b, c.threads);
  const ContactPairs& reference = mesh.contactsReference();
  const double epsilon = mesh.scene().epsilon, triangles = mesh.scene().triangles;
  const OmpThreads omp(c.threads);
  std::vector<delta::ContactPoint> contacts;
  for (auto _ : state)
    contacts = cd::contacts(*pair.first, *pair.second, epsilon);
  const ContactPairs pairs = contactPairs(contacts);
  setMeshMeshCounters(
      state, pair.buildSeconds,
      static_cast<double>(pair.first->memoryBytes() + pair.second->memoryBytes()) / triangles,
      "QueryMesh::memoryBytes(), both meshes");
  state.counters["contacts"] = static_cast<double>(contacts.size());
  state.counters["overlapping"] = static_cast<double>(pairs.overlapping);
  state.counters["intersecting_pairs"] = static_cast<double>(pairs.intersecting.size());
  if (pairs.all != reference.all)
    shared.disagree(state, c.name,
                    "contacts (" + withCommas(pairs.all.size()) +
                        ") differ from the first thread count's (" +
                        withCommas(reference.all.size()) + ")");
}

#if defined(DELTA_HAVE_FCL)
/// W4a by FCL, against Δ's answer; a disagreement is settled on both pairs exactly.
void fclMinimumDistance(benchmark::State& state, Shared& shared, const Case& c) {
  MeshState& mesh = shared.of(*c.mesh);
  const MeshMeshScene& scene = mesh.scene();
  const FclPair& fcl = mesh.fcl();
  const cd::MinimumDistance& delta = mesh.minimumReference();
  const OmpThreads omp(c.threads);
  bench::FclMeshPair::Distance answer;
  for (auto _ : state)
    answer = fcl.models->minimumDistance(scene.gapMotion);
  setMeshMeshCounters(state, fcl.buildSeconds,
                      static_cast<double>(fcl.models->memoryBytes()) / scene.triangles,
                      "heap growth over the build, both models",
                      pairNote(answer.distance, answer.first, answer.second));
  const double difference = std::abs(answer.distance - delta.distance);
  state.counters["max_diff_over_D"] = difference / scene.diagonal;
  if (difference <= scene.tolerance) return;
  shared.disagree(state, c.name, "FCL's minimum distance differs from Δ's", [&] {
    // Which pair is closer? Both pairs, exactly, on Δ's coordinates of the copy.
    char text[512];
    const Triangle fclFirst = scene.mesh.triangle(answer.first),
                   fclSecond = scene.gapCopy.triangle(answer.second);
    const Triangle deltaFirst = scene.mesh.triangle(delta.first),
                   deltaSecond = scene.gapCopy.triangle(delta.second);
#if defined(DELTA_HAVE_CGAL)
    const double fclExact = bench::exactDistance(fclFirst, fclSecond),
                 deltaExact = bench::exactDistance(deltaFirst, deltaSecond);
#else
    const double fclExact = kNaN, deltaExact = kNaN;
    (void)fclFirst, (void)fclSecond, (void)deltaFirst, (void)deltaSecond;
#endif
    std::snprintf(text, sizeof text,
                  "%s, FCL: Δ %.17g (pair %u, %u: exactly %.17g), FCL %.17g (pair %u, %u: "
                  "exactly %.17g)",
                  scene.gapName.c_str(), delta.distance, delta.first, delta.second, deltaExact,
                  answer.distance, answer.first, answer.second, fclExact);
    return std::vector<std::string>{text};
  });
}

/// W4b by FCL: its intersecting pairs against Δ's (contacts at distance 0); each disagreement
/// (a few shown) settled exactly.
void fclContacts(benchmark::State& state, Shared& shared, const Case& c) {
  MeshState& mesh = shared.of(*c.mesh);
  const MeshMeshScene& scene = mesh.scene();
  const FclPair& fcl = mesh.fcl();
  const ContactPairs& reference = mesh.contactsReference();
  const auto& intersecting = reference.intersecting;
  const OmpThreads omp(c.threads);
  bench::FclMeshPair::Collision collision;
  for (auto _ : state)
    collision = fcl.models->collide(scene.overlapMotion, kFclMaxContacts);
  std::vector<std::pair<std::uint32_t, std::uint32_t>> onlyFcl, onlyDelta;
  std::set_difference(collision.pairs.begin(), collision.pairs.end(), intersecting.begin(),
                      intersecting.end(), std::back_inserter(onlyFcl));
  std::set_difference(intersecting.begin(), intersecting.end(), collision.pairs.begin(),
                      collision.pairs.end(), std::back_inserter(onlyDelta));
  std::size_t fclOutsideContacts = 0;  // FCL pairs Δ does not even report closer than 2ε
  for (const auto& pair : onlyFcl)
    if (!std::binary_search(reference.all.begin(), reference.all.end(), pair)) ++fclOutsideContacts;
  setMeshMeshCounters(state, fcl.buildSeconds,
                      static_cast<double>(fcl.models->memoryBytes()) / scene.triangles,
                      "heap growth over the build, both models");
  state.counters["contacts"] = static_cast<double>(collision.contacts);
  state.counters["intersecting_pairs"] = static_cast<double>(collision.pairs.size());
  state.counters["only_fcl"] = static_cast<double>(onlyFcl.size());
  state.counters["only_delta"] = static_cast<double>(onlyDelta.size());
  state.counters["fcl_pairs_not_in_contacts"] = static_cast<double>(fclOutsideContacts);
  if (onlyFcl.empty() && onlyDelta.empty()) return;
  const auto settle = [&](const std::pair<std::uint32_t, std::uint32_t>& pair, bool fclSaysMeet) {
    const Triangle first = scene.mesh.triangle(pair.first),
                   second = scene.overlapCopy.triangle(pair.second);
#if defined(DELTA_HAVE_CGAL)
    const bool meet = bench::exactIntersect(first, second);
    const double gap = bench::exactDistance(first, second);
    const char* verdict = meet == fclSaysMeet ? "Δ is wrong" : "FCL is wrong";
#else
    const bool meet = fclSaysMeet;
    const double gap = kNaN;
    const char* verdict = "no exact oracle (built without CGAL)";
    (void)first, (void)second;
#endif
    char text[256];
    std::snprintf(text, sizeof text,
                  "%s, FCL: pair (%u, %u) %s by FCL, %s by Δ; exact: %s, distance %.3g -> %s",
                  scene.contactName.c_str(), pair.first, pair.second,
                  fclSaysMeet ? "intersecting" : "not intersecting",
                  fclSaysMeet ? "not intersecting" : "intersecting",
                  meet ? "they meet" : "they do not meet", gap, verdict);
    return std::string(text);
  };
  shared.disagree(state, c.name,
                  withCommas(onlyFcl.size() + onlyDelta.size()) +
                      " intersecting pairs differ from Δ's (only FCL " +
                      withCommas(onlyFcl.size()) + ", only Δ " + withCommas(onlyDelta.size()) + ")",
                  [&] {
                    std::vector<std::string> verdicts;
                    for (std::size_t k = 0; k < onlyFcl.size() && k < kDisputesShown; ++k)
                      verdicts.push_back(settle(onlyFcl[k], true));
                    for (std::size_t k = 0; k < onlyDelta.size() && k < kDisputesShown; ++k)
                      verdicts.push_back(settle(onlyDelta[k], false));
                    return verdicts;
                  });
}
#endif

// ---------------------------------------------------------------------------------------------
// W5's grid

/// The counters of W5-build and W5-moves (as bench/ib_bench.cpp's): the grid's vertices and
/// leaves, queries per build or move, queries per second inside Δ's distance queries and their
/// share of the time (GridStatistics, summed over the iterations); the label: the grid.
void setGridCounters(benchmark::State& state, const ib::GridStatistics& totals,
                     const ib::AdaptiveGrid& grid, const GridReference& reference) {
  const auto queries = static_cast<double>(totals.queries);
  state.counters["vertices"] = static_cast<double>(grid.vertexCount());
  state.counters["leaves"] = static_cast<double>(grid.leafCount());
  state.counters["queries"] = queries / static_cast<double>(state.iterations());
  state.counters["queries_per_s_in_delta"] = queries / totals.querySeconds;
  state.counters["share_in_delta"] = totals.querySeconds / totals.seconds;
  char label[160];
  std::snprintf(label, sizeof label,
                "levels %d, %s distances, finest cell diagonal h = %.6g, a move %.3g h",
                reference.options.levels, reference.options.signedDistance ? "signed" : "unsigned",
                reference.cellDiagonal, reference.step / reference.cellDiagonal);
  state.SetLabel(label);
}

/// W5-build: the grid built on every thread count must be the first thread count's, which must
/// hold the distances of direct queries at its vertices.
void gridBuild(benchmark::State& state, Shared& shared, const Case& c) {
  MeshState& mesh = shared.of(*c.mesh);
  const GridReference& reference = mesh.grid();
  const OmpThreads omp(c.threads);
  std::optional<ib::AdaptiveGrid> grid;
  ib::GridStatistics totals;
  for (auto _ : state) {
    grid.emplace(*reference.boundary, reference.options);
    totals += grid->statistics();
  }
  setGridCounters(state, totals, *grid, reference);
  if (reference.differingFromDirect > 0)
    shared.disagree(state, c.name,
                    "the first thread count's grid: " + withCommas(reference.differingFromDirect) +
                        " vertices differ from direct queries");
  else if (GridField(*grid) != *reference.builtField)
    shared.disagree(state, c.name, "the grid differs from the first thread count's");
}

/// W5-moves: --moves moves (one an iteration) from the built grid, after which the grid must be
/// the first thread count's.
void gridMoves(benchmark::State& state, Shared& shared, const Case& c) {
  MeshState& mesh = shared.of(*c.mesh);
  const GridReference& reference = mesh.grid();
  const GridField& movedReference = mesh.movedGrid();
  const OmpThreads omp(c.threads);
  ib::AdaptiveGrid grid = *reference.built;
  ib::GridStatistics totals;
  for (auto _ : state) {
    state.PauseTiming();
    const RigidTransform motion = bench::boundaryStep(grid.boundary(), reference.step);
    state.ResumeTiming();
    totals += grid.moveBoundary(motion);
  }
  setGridCounters(state, totals, grid, reference);
  if (GridField(grid) != movedReference)
    shared.disagree(state, c.name,
                    "the grid after " + std::to_string(state.iterations()) +
                        " moves differs from the first thread count's");
}

// ---------------------------------------------------------------------------------------------
// The program

/// The meshes of --mesh, named by their stems.
std::vector<LoadedMesh> loadMeshes(const Options& options) {
  std::vector<LoadedMesh> meshes;
  std::set<std::string> names;
  for (const std::string& path : options.meshes) {
    const std::string stem = std::filesystem::path(path).stem().string();
    std::string name = stem;
    for (int k = 2; !names.insert(name).second; ++k)
      name = stem + "-" + std::to_string(k);
    Mesh mesh = delta::io::load(path);
    const double diagonal = mesh.bounds().diagonal();
    const delta::Topology topology = delta::analyzeTopology(mesh);
    meshes.push_back(
        {path, name, std::move(mesh), diagonal, topology.closed && topology.consistentlyOriented});
  }
  return meshes;
}

using Function = void (*)(benchmark::State&, Shared&, const Case&);

/// Registers `function` on `c`, named workload/mesh/library/threads:N, an exception becoming the
/// benchmark's error.
benchmark::internal::Benchmark* add(Shared& shared, Case c, Function function) {
  c.name = std::string(nameOf(c.workload)) + "/" + c.mesh->name + "/" + nameOf(c.library) +
           "/threads:" + std::to_string(c.threads);
  return benchmark::RegisterBenchmark(c.name.c_str(),
                                      [&shared, c, function](benchmark::State& state) {
                                        try {
                                          function(state, shared, c);
                                        } catch (const std::exception& error) {
                                          shared.fail(state, c.name, error);
                                        }
                                      })
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
}

/// Mesh by mesh, workload by workload, library by library, thread count by thread count.
void registerBenchmarks(const std::vector<LoadedMesh>& meshes, const Options& options,
                        Shared& shared) {
  std::vector<Library> peers;
#if defined(DELTA_HAVE_EMBREE)
  peers.push_back(Library::Embree);
#endif
#if defined(DELTA_HAVE_CGAL)
  peers.push_back(Library::Cgal);
#endif
  std::vector<std::pair<Library, Function>> pointLibraries{{Library::Delta, deltaPoints}};
  for (const Library peer : peers)
    pointLibraries.emplace_back(peer, peerPoints);
  for (const LoadedMesh& mesh : meshes) {
    const auto everyThreadCount = [&](Workload workload, Library library, Function function) {
      for (const int threads : options.threads)
        add(shared, {&mesh, workload, library, threads, {}}, function);
    };
    for (const Workload workload : {Workload::W1, Workload::W2, Workload::W3})
      if (options.workloads[static_cast<std::size_t>(workload)])
        for (const auto& [library, function] : pointLibraries)
          everyThreadCount(workload, library, function);
    if (options.workloads[3]) {
      everyThreadCount(Workload::W4a, Library::Delta, deltaMinimumDistance);
#if defined(DELTA_HAVE_FCL)
      add(shared, {&mesh, Workload::W4a, Library::Fcl, 1, {}}, fclMinimumDistance);
#endif
      everyThreadCount(Workload::W4b, Library::Delta, deltaContacts);
#if defined(DELTA_HAVE_FCL)
      add(shared, {&mesh, Workload::W4b, Library::Fcl, 1, {}}, fclContacts);
#endif
    }
    if (options.workloads[4]) {
      everyThreadCount(Workload::W5Build, Library::Delta, gridBuild);
      for (const int threads : options.threads)
        add(shared, {&mesh, Workload::W5Moves, Library::Delta, threads, {}}, gridMoves)
            ->Iterations(options.moves);
      for (const auto& [library, function] : pointLibraries) {
        everyThreadCount(Workload::W5, library, function);
        if (library == Library::Delta && mesh.closed)
          everyThreadCount(Workload::W5, Library::DeltaSigned, deltaSignedPoints);
      }
    }
  }
}

/// The machine, the peers, the meshes and the options, in Google Benchmark's context.
void addContext(const std::vector<LoadedMesh>& meshes, const Options& options) {
  benchmark::AddCustomContext("omp_num_procs", std::to_string(omp_get_num_procs()));
  bench::addPeersToContext();
  benchmark::AddCustomContext("points", withCommas(options.points) + " (W1-W3)");
  if (options.workloads[4])
    benchmark::AddCustomContext("w5_grid", "levels " + std::to_string(options.levels) + ", " +
                                               std::to_string(options.moves) + " moves");
  for (const LoadedMesh& mesh : meshes) {
    char text[512];
    std::snprintf(text, sizeof text, "%s: %s triangles, %s vertices, diagonal D = %.6g%s",
                  mesh.path.c_str(), withCommas(mesh.mesh.triangleCount()).c_str(),
                  withCommas(mesh.mesh.vertexCount()).c_str(), mesh.diagonal,
                  mesh.closed ? ", closed" : "");
    benchmark::AddCustomContext("mesh " + mesh.name, text);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> benchmarkArguments;
  const Options options = parseOptions(argc, argv, benchmarkArguments);
  std::vector<LoadedMesh> meshes;
  try {
    meshes = loadMeshes(options);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "delta_bench_peers: %s\n", error.what());
    return 2;
  }
  Shared shared(options);
  registerBenchmarks(meshes, options, shared);
  addContext(meshes, options);
  bench::RatioReporter reporter;
  const int benchmarkArgc = static_cast<int>(benchmarkArguments.size());
  benchmarkArguments.push_back(nullptr);
  if (const int status = bench::runBenchmarks(benchmarkArgc, benchmarkArguments.data(), &reporter))
    return status;
  shared.release();
  if (!reporter.ran()) return shared.exitStatus();
  std::FILE* out = reporter.displaysConsole() ? stdout : stderr;
  std::fflush(stdout);
  reporter.printRatios(out);
  std::fprintf(out, "\nagreement: %s\n", shared.verdict().c_str());
  return shared.exitStatus();
}
