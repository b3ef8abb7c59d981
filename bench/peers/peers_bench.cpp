// Δ side by side with its peers (issue 5): Embree 3 and CGAL's AABB tree for points–mesh
// distances, FCL for mesh–mesh distance and collision, on the same meshes, points and threads.
//   build/bench/delta_bench_peers [--mesh PATH]... [--points N] [--threads 1,2]
//                                 [--workloads W1,W2,W3,W4,W5] [--levels L] [--moves T] [--json]
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
//                    signed distance too (a second Δ row) when the mesh is closed. Not in the
//                    default list: run it with --workloads W5. Its own table, per thread count:
//                    the grid's build (signed when the mesh is closed; seconds, vertices, queries,
//                    queries per second inside Δ's distance queries and their share of the build)
//                    and T moves (default 10) of the boundary, each turned about its box centre
//                    and moved so that its furthest vertex moves 0.2 h, h the finest cell's
//                    diagonal (bench/boundary_step.h): the same figures per move, averaged. The
//                    grid's distances must equal a direct signed query at its vertices, and its
//                    vertices and distances must not depend on the thread count.
//
// Per workload, library and thread count: build seconds (the library's structure), query
// seconds (when a run takes under 2 s, the median of 5 samples after a warm-up, a sample
// repeating a short query for 50 ms, per run; else one run), the ratios peer/Δ of query and of
// build + query time, bytes per triangle, and the agreement check: every peer answer against Δ's
// within 10⁻⁹ D (W1, W3, W5; W2: the same points within ε, except points whose distance is within
// 10⁻⁹ D of ε; W4b: the same intersecting triangle pairs). A disagreement is settled by brute force
// over all triangles with an exact oracle (CGAL, the first 3 of each row) and printed under the
// mesh's table ("disagreements" in the JSON). Any disagreement, and Δ answering differently on
// another thread count, makes the exit code 1 (2: bad options).
#include <omp.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <functional>
#include <iterator>
#include <limits>
#include <numeric>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/version.h"
#include "delta/ib/adaptive_grid.h"
#include "delta/io/mesh_io.h"
#include "delta/kernels/point_triangle.h"
#include "delta/query/contacts.h"
#include "delta/query/minimum_distance.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"

#include "boundary_step.h"
#include "peers.h"
#include "report.h"

namespace {

using delta::Mesh;
using delta::QueryMesh;
using delta::RigidTransform;
using delta::Triangle;
using delta::Vec3;
namespace cd = delta::contactdetection;
namespace bench = delta::bench;
using bench::makeRow;
using bench::MeshReport;
using bench::Row;
using bench::setRatios;
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
constexpr double kRepeatBelowSeconds = 2.0;
constexpr double kSampleSeconds = 0.05;  // a sample of a short query repeats it this long
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
  bool json = false;
};

constexpr const char* kUsage =
    "usage: delta_bench_peers [--mesh PATH]... [--points N] [--threads LIST] "
    "[--workloads W1,W2,W3,W4,W5] [--levels L] [--moves T] [--json]\n"
    "  --mesh PATH      a mesh file (repeatable; default CGAL's armadillo, bunny00 and\n"
    "                   refined_elephant from " DELTA_DATA_DIR
    "/meshes)\n"
    "  --points N       query points for W1-W3 (default 1000000)\n"
    "  --threads LIST   thread counts, comma-separated (default 1,2)\n"
    "  --workloads LIST any of W1,W2,W3,W4,W5 (default W1,W2,W3,W4)\n"
    "  --levels L       W5: the grid's finest level, 1 to 20 (default 7)\n"
    "  --moves T        W5: moves of the boundary (default 10)\n"
    "  --json           print one JSON object on stdout instead of the tables\n";

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

Options parseOptions(int argc, char** argv) {
  Options options;
  for (int i = 1; i < argc; ++i) {
    const std::string argument = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) usageError(argument + " needs a value");
      return argv[++i];
    };
    if (argument == "--help" || argument == "-h") {
      std::fputs(kUsage, stdout);
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
      options.json = true;
    } else {
      usageError("unknown option '" + argument + "'");
    }
  }
  if (options.meshes.empty())
    for (const char* name : {"armadillo.off", "bunny00.off", "refined_elephant.off"})
      options.meshes.push_back(std::string(DELTA_DATA_DIR) + "/meshes/" + name);
  return options;
}

// ---------------------------------------------------------------------------------------------
// Timing

double secondsOf(const std::function<void()>& run) {
  const auto start = std::chrono::steady_clock::now();
  run();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct QueryTime {
  double seconds = 0.0;
  int runs = 1;
};

/// One run; when it took under kRepeatBelowSeconds it was the warm-up, and the time is the median
/// of five samples, each of as many runs as fill kSampleSeconds (a sub-millisecond mesh–mesh
/// query is otherwise timed at the resolution of this shared machine's noise), per run. Every
/// run computes the full answer (the last one's is kept).
QueryTime timeQuery(const std::function<void()>& run) {
  const double first = secondsOf(run);
  if (first >= kRepeatBelowSeconds) return {first, 1};
  const int perSample =
      static_cast<int>(std::clamp(std::ceil(kSampleSeconds / std::max(first, 1e-9)), 1.0, 1e6));
  std::array<double, 5> times{};
  for (double& t : times)
    t = secondsOf([&] {
          for (int r = 0; r < perSample; ++r)
            run();
        }) /
        perSample;
  std::sort(times.begin(), times.end());
  return {times[2], static_cast<int>(times.size()) * perSample};
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

void setAgreement(Row& row, const Comparison& comparison, double diagonal) {
  row.agreed = comparison.disagreements == 0;
  row.maxDifference = comparison.maxDifference / diagonal;
  row.agreement = row.agreed ? "yes" : "NO (" + withCommas(comparison.disagreements) + ")";
}

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

// ---------------------------------------------------------------------------------------------
// W1–W3

struct PointWorkload {
  std::string name;
  const std::vector<Vec3>* points;
  double radius;            // +∞ or ε
  bool alsoSigned = false;  // a second Δ row: signed distances (a closed mesh)
};

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

/// Δ's signed distances for `workload`: timed as the unsigned ones, and checked against them (the
/// same |distance|, bit for bit) and against the first thread count's (`firstSigned`, set when
/// empty).
Row signedRow(const QueryMesh& queryMesh, const PointWorkload& workload, int threads,
              double buildSeconds, double unsignedSeconds,
              const std::vector<double>& unsignedAnswers, std::vector<double>& firstSigned) {
  std::vector<cd::PointDistance> answers(workload.points->size());
  const QueryTime time = timeQuery([&] {
    cd::distances(queryMesh, *workload.points, {.epsilon = workload.radius, .signedDistance = true},
                  answers);
  });
  std::vector<double> signedDistances(answers.size());
  std::size_t inside = 0, differing = 0;
  for (std::size_t i = 0; i < answers.size(); ++i) {
    signedDistances[i] = answers[i].signedDistance();
    inside += answers[i].inside ? 1 : 0;
    differing += answers[i].distance != unsignedAnswers[i] ? 1 : 0;
  }
  Row row = makeRow(workload.name, "Δ signed", threads);
  row.buildSeconds = buildSeconds;
  row.querySeconds = time.seconds;
  row.queryRuns = time.runs;
  row.bytesPerTriangle =
      static_cast<double>(queryMesh.memoryBytes()) / static_cast<double>(queryMesh.size());
  row.memoryMethod = "QueryMesh::memoryBytes()";
  row.agreed = differing == 0;
  row.agreement =
      row.agreed ? "|d| = unsigned" : "NO: " + withCommas(differing) + " |d| != unsigned";
  if (firstSigned.empty()) {
    firstSigned = signedDistances;
  } else if (firstSigned != signedDistances) {
    row.agreed = false;
    row.agreement += ", NO: differs from the first thread count";
  } else {
    row.agreement += ", = 1st thread count";
  }
  char note[96];
  std::snprintf(note, sizeof note, "inside: %s; %.2f× the unsigned query",
                withCommas(inside).c_str(), time.seconds / unsignedSeconds);
  row.note = note;
  return row;
}

void runPointWorkloads(const Mesh& mesh, const std::vector<PointWorkload>& workloads,
                       const Options& options, MeshReport& report) {
  const double diagonal = report.diagonal, tolerance = kAgreementFraction * diagonal;
  const double triangles = static_cast<double>(mesh.triangleCount());
  // Δ's answers on the first thread count: the others must match them bit for bit.
  std::vector<std::vector<double>> firstAnswers(workloads.size()), firstSigned(workloads.size());

  for (const int threads : options.threads) {
    omp_set_num_threads(threads);
    std::vector<std::vector<double>> deltaAnswers(workloads.size());

    // Δ
    std::optional<QueryMesh> queryMesh;
    const double deltaBuild = secondsOf([&] { queryMesh.emplace(mesh); });
    for (std::size_t w = 0; w < workloads.size(); ++w) {
      const PointWorkload& workload = workloads[w];
      // Into a buffer made before the clock starts, as every peer's answers are.
      std::vector<cd::PointDistance> answers(workload.points->size());
      const QueryTime time = timeQuery([&] {
        cd::distances(*queryMesh, *workload.points, {.epsilon = workload.radius}, answers);
      });
      deltaAnswers[w] = distancesOf(answers);
      Row row = makeRow(workload.name, "Δ", threads);
      row.buildSeconds = deltaBuild;
      row.querySeconds = time.seconds;
      row.queryRuns = time.runs;
      row.bytesPerTriangle = static_cast<double>(queryMesh->memoryBytes()) / triangles;
      row.memoryMethod = "QueryMesh::memoryBytes()";
      if (firstAnswers[w].empty()) {
        firstAnswers[w] = deltaAnswers[w];
        row.agreement = "reference";
      } else {
        row.agreed = firstAnswers[w] == deltaAnswers[w];
        row.agreement = row.agreed ? "reference (= first thread count)"
                                   : "NO: differs from the first thread count";
      }
      if (std::isfinite(workload.radius))
        row.note = "within ε: " + withCommas(countFinite(deltaAnswers[w]));
      else if (workload.points->size() != options.points)
        row.note = withCommas(workload.points->size()) + " points";
      report.rows.push_back(row);
      if (workload.alsoSigned)
        report.rows.push_back(signedRow(*queryMesh, workload, threads, deltaBuild, row.querySeconds,
                                        deltaAnswers[w], firstSigned[w]));
    }

    // The peers
    struct PeerMaker {
      std::string name;
      std::function<std::unique_ptr<bench::PointDistancePeer>()> make;
    };
    std::vector<PeerMaker> peers;
#if defined(DELTA_HAVE_EMBREE)
    peers.push_back({"Embree", [&] { return bench::makeEmbreePeer(mesh, threads); }});
#endif
#if defined(DELTA_HAVE_CGAL)
    peers.push_back({"CGAL", [&] { return bench::makeCgalPeer(mesh); }});
#endif
    for (const PeerMaker& maker : peers) {
      const std::unique_ptr<bench::PointDistancePeer> peer = maker.make();
      for (std::size_t w = 0; w < workloads.size(); ++w) {
        const PointWorkload& workload = workloads[w];
        std::vector<double> answers(workload.points->size());
        const QueryTime time =
            timeQuery([&] { peer->distances(*workload.points, workload.radius, answers); });
        Row row = makeRow(workload.name, maker.name, threads);
        row.buildSeconds = peer->buildSeconds();
        row.querySeconds = time.seconds;
        row.queryRuns = time.runs;
        row.bytesPerTriangle = static_cast<double>(peer->memoryBytes()) / triangles;
        row.memoryMethod = peer->memoryMethod();
        const std::vector<double>& reference = deltaAnswers[w];
        const Comparison comparison = std::isfinite(workload.radius)
                                          ? compareWithin(*queryMesh, *workload.points, reference,
                                                          answers, workload.radius, tolerance)
                                          : compareDistances(reference, answers, tolerance);
        setAgreement(row, comparison, diagonal);
        if (std::isfinite(workload.radius))
          row.note = "within ε: " + withCommas(countFinite(answers));
        for (const std::size_t i : comparison.examples) {
          const Vec3& p = (*workload.points)[i];
          report.disputes.push_back(workload.name + ", " + maker.name + ", point " +
                                    std::to_string(i) + ": " +
                                    settlePoint(mesh, p, workload.radius, reference[i], answers[i],
                                                maker.name, tolerance, diagonal));
        }
        setRatios(row, report.rows);
        report.rows.push_back(row);
      }
    }
  }
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

/// Δ's W4 answers at the first thread count, which the other thread counts and the peers are
/// compared with.
struct MeshMeshReference {
  cd::MinimumDistance minimum;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> contacts;      ///< (first, second) ids
  std::vector<std::pair<std::uint32_t, std::uint32_t>> intersecting;  ///< at distance 0
  bool made = false;
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

/// A row of Δ's W4: both meshes prepared (timed) and the copy moved rigidly by `motion`, as
/// FCL's models are (the DEM case), then `query(first, copy)` timed.
template <class Query>
Row deltaMeshMeshRow(const MeshMeshScene& scene, const std::string& name,
                     const RigidTransform& motion, int threads, const Query& query) {
  std::optional<QueryMesh> a, b;
  const double build = secondsOf([&] {
    a.emplace(scene.mesh);
    b.emplace(scene.mesh);
  });
  b->transform(motion);
  const QueryTime time = timeQuery([&] { query(*a, *b); });
  Row row = makeRow(name, "Δ", threads);
  row.buildSeconds = build;
  row.querySeconds = time.seconds;
  row.queryRuns = time.runs;
  row.bytesPerTriangle = static_cast<double>(a->memoryBytes() + b->memoryBytes()) / scene.triangles;
  row.memoryMethod = "QueryMesh::memoryBytes(), both meshes";
  row.agreement = "reference";
  return row;
}

/// A later thread count's row: whether it answered as the first did.
void compareWithFirst(Row& row, bool same) {
  row.agreed = same;
  row.agreement =
      same ? "reference (= first thread count)" : "NO: differs from the first thread count";
}

/// W4a by Δ on `threads` threads.
Row deltaMinimumDistance(const MeshMeshScene& scene, int threads, MeshMeshReference& reference) {
  cd::MinimumDistance minimum;
  Row row = deltaMeshMeshRow(
      scene, scene.gapName, scene.gapMotion, threads,
      [&](const QueryMesh& a, const QueryMesh& b) { minimum = cd::minimumDistance(a, b); });
  row.note = pairNote(minimum.distance, minimum.first, minimum.second);
  if (reference.made)
    compareWithFirst(row, minimum.distance == reference.minimum.distance);
  else
    reference.minimum = minimum;
  return row;
}

/// W4b by Δ on `threads` threads.
Row deltaContacts(const MeshMeshScene& scene, int threads, MeshMeshReference& reference) {
  std::vector<delta::ContactPoint> contacts;
  Row row = deltaMeshMeshRow(scene, scene.contactName, scene.overlapMotion, threads,
                             [&](const QueryMesh& a, const QueryMesh& b) {
                               contacts = cd::contacts(a, b, scene.epsilon);
                             });
  std::vector<std::pair<std::uint32_t, std::uint32_t>> all, intersecting;
  std::size_t overlapping = 0;
  for (const delta::ContactPoint& contact : contacts) {
    all.emplace_back(contact.first, contact.second);
    overlapping += contact.overlap ? 1 : 0;
    if (contact.distance == 0.0) intersecting.emplace_back(contact.first, contact.second);
  }
  row.note = "contacts " + withCommas(contacts.size()) + ", overlapping " +
             withCommas(overlapping) + ", intersecting pairs " + withCommas(intersecting.size());
  if (reference.made)
    compareWithFirst(row, all == reference.contacts);
  else
    reference.contacts = std::move(all);
  reference.intersecting = std::move(intersecting);
  return row;
}

#if defined(DELTA_HAVE_FCL)
/// A row of FCL's (one thread: it has no parallel traversal): its build, query and memory.
Row fclRow(const MeshMeshScene& scene, const std::string& name, const bench::FclMeshPair& fcl,
           double build, const QueryTime& time) {
  Row row = makeRow(name, "FCL", 1);
  row.buildSeconds = build;
  row.querySeconds = time.seconds;
  row.queryRuns = time.runs;
  row.bytesPerTriangle = static_cast<double>(fcl.memoryBytes()) / scene.triangles;
  row.memoryMethod = "heap growth over the build, both models";
  return row;
}

/// W4a by FCL, against Δ's answer; a disagreement is settled on both pairs exactly.
Row fclMinimumDistance(const MeshMeshScene& scene, bench::FclMeshPair& fcl, double build,
                       const MeshMeshReference& reference, MeshReport& report) {
  const cd::MinimumDistance& delta = reference.minimum;
  bench::FclMeshPair::Distance answer;
  Row row = fclRow(scene, scene.gapName, fcl, build,
                   timeQuery([&] { answer = fcl.minimumDistance(scene.gapMotion); }));
  row.note = pairNote(answer.distance, answer.first, answer.second);
  const double difference = std::abs(answer.distance - delta.distance);
  row.agreed = difference <= scene.tolerance;
  row.maxDifference = difference / scene.diagonal;
  row.agreement = row.agreed ? "yes" : "NO";
  if (!row.agreed) {
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
    report.disputes.push_back(text);
  }
  return row;
}

/// W4b by FCL: its intersecting pairs against Δ's (contacts at distance 0); each disagreement
/// (a few shown) settled exactly.
Row fclContacts(const MeshMeshScene& scene, bench::FclMeshPair& fcl, double build,
                const MeshMeshReference& reference, MeshReport& report) {
  const auto& intersecting = reference.intersecting;
  bench::FclMeshPair::Collision collision;
  Row row =
      fclRow(scene, scene.contactName, fcl, build,
             timeQuery([&] { collision = fcl.collide(scene.overlapMotion, kFclMaxContacts); }));
  std::vector<std::pair<std::uint32_t, std::uint32_t>> onlyFcl, onlyDelta;
  std::set_difference(collision.pairs.begin(), collision.pairs.end(), intersecting.begin(),
                      intersecting.end(), std::back_inserter(onlyFcl));
  std::set_difference(intersecting.begin(), intersecting.end(), collision.pairs.begin(),
                      collision.pairs.end(), std::back_inserter(onlyDelta));
  std::size_t fclOutsideContacts = 0;  // FCL pairs Δ does not even report closer than 2ε
  for (const auto& pair : onlyFcl)
    if (!std::binary_search(reference.contacts.begin(), reference.contacts.end(), pair))
      ++fclOutsideContacts;
  row.note = "contacts " + withCommas(collision.contacts) + ", intersecting pairs " +
             withCommas(collision.pairs.size()) + " (only FCL " + withCommas(onlyFcl.size()) +
             ", only Δ " + withCommas(onlyDelta.size()) + ")";
  row.agreed = onlyFcl.empty() && onlyDelta.empty();
  row.agreement =
      row.agreed ? "yes" : "NO (" + withCommas(onlyFcl.size() + onlyDelta.size()) + " pairs)";
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
    report.disputes.push_back(text);
  };
  for (std::size_t k = 0; k < onlyFcl.size() && k < kDisputesShown; ++k)
    settle(onlyFcl[k], true);
  for (std::size_t k = 0; k < onlyDelta.size() && k < kDisputesShown; ++k)
    settle(onlyDelta[k], false);
  if (fclOutsideContacts > 0)
    row.note += ", " + withCommas(fclOutsideContacts) + " FCL pairs not among Δ's contacts";
  return row;
}
#endif

void runMeshMeshWorkloads(const Mesh& mesh, const Options& options, MeshReport& report) {
  omp_set_num_threads(*std::max_element(options.threads.begin(), options.threads.end()));
  const MeshMeshScene scene = meshMeshScene(mesh, report.diagonal);
  MeshMeshReference reference;
  for (const int threads : options.threads) {
    omp_set_num_threads(threads);
    report.rows.push_back(deltaMinimumDistance(scene, threads, reference));
    report.rows.push_back(deltaContacts(scene, threads, reference));
    reference.made = true;
  }
#if defined(DELTA_HAVE_FCL)
  // FCL is single-threaded: its ratios are against Δ on one thread.
  omp_set_num_threads(1);
  std::unique_ptr<bench::FclMeshPair> fcl;
  const double build = secondsOf([&] { fcl = bench::makeFclPair(mesh, mesh); });
  for (Row row : {fclMinimumDistance(scene, *fcl, build, reference, report),
                  fclContacts(scene, *fcl, build, reference, report)}) {
    setRatios(row, report.rows);
    report.rows.push_back(row);
  }
#endif
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

/// W5's grid at every thread count (report.grid): its build (the median of three after a warm-up
/// when it takes under kRepeatBelowSeconds), then options.moves moves of the boundary. The first
/// thread count's grid is checked against a direct query at its vertices, the others against
/// it, before and after the moves. Returns the vertices of the built grid.
std::vector<Vec3> runGridPhases(const Mesh& mesh, const Options& options, MeshReport& report) {
  const QueryMesh boundary(mesh);
  bench::GridReport& grid = report.grid;
  grid.levels = options.levels;
  grid.signedDistance = boundary.closed();
  grid.moves = options.moves;
  const delta::ib::GridOptions gridOptions{.levels = options.levels,
                                           .signedDistance = grid.signedDistance};
  std::optional<GridField> firstBuilt, firstMoved;
  for (const int threads : options.threads) {
    omp_set_num_threads(threads);
    std::optional<delta::ib::AdaptiveGrid> built;
    std::vector<delta::ib::GridStatistics> runs;
    const auto build = [&] {
      built.emplace(boundary, gridOptions);
      runs.push_back(built->statistics());
    };
    build();
    if (runs.front().seconds < kRepeatBelowSeconds) {
      runs.clear();
      for (int run = 0; run < 3; ++run)
        build();
      std::sort(runs.begin(), runs.end(),
                [](const auto& a, const auto& b) { return a.seconds < b.seconds; });
    }
    const delta::ib::GridStatistics& median = runs[runs.size() / 2];
    delta::ib::AdaptiveGrid& adaptive = *built;
    bench::GridPhases phases;
    phases.threads = threads;
    phases.vertices = adaptive.vertexCount();
    phases.leaves = adaptive.leafCount();
    phases.buildSeconds = median.seconds;
    phases.buildRuns = static_cast<int>(runs.size());
    phases.buildQueries = median.queries;
    phases.buildQuerySeconds = median.querySeconds;

    const GridField field(adaptive);
    if (!firstBuilt) {
      const std::vector<cd::PointDistance> direct =
          cd::distances(boundary, field.positions, {.signedDistance = grid.signedDistance});
      std::size_t differing = 0;
      for (std::size_t v = 0; v < direct.size(); ++v) {
        const double expected =
            grid.signedDistance ? direct[v].signedDistance() : direct[v].distance;
        differing += expected != field.distances[v] ? 1 : 0;
      }
      phases.agreed = differing == 0;
      phases.agreement = phases.agreed
                             ? "built = direct queries"
                             : "NO: " + withCommas(differing) + " differ from direct queries";
      firstBuilt = field;
    } else {
      phases.agreed = field == *firstBuilt;
      phases.agreement = phases.agreed ? "built = first thread count"
                                       : "NO: built differs from the first thread count";
    }

    grid.cellDiagonal = adaptive.cellDiagonal(options.levels);
    grid.step = kStepInCells * grid.cellDiagonal;
    delta::ib::GridStatistics moves;
    for (int move = 0; move < options.moves; ++move)
      moves += adaptive.moveBoundary(bench::boundaryStep(adaptive.boundary(), grid.step));
    phases.moveSeconds = moves.seconds / options.moves;
    phases.moveQueries = static_cast<double>(moves.queries) / options.moves;
    phases.moveQuerySeconds = moves.querySeconds / options.moves;
    const GridField moved(adaptive);
    if (!firstMoved) {
      firstMoved = moved;
    } else if (moved == *firstMoved) {
      phases.agreement += ", moved = first thread count";
    } else {
      phases.agreed = false;
      phases.agreement += ", NO: moved differs from the first thread count";
    }
    grid.rows.push_back(phases);
  }
  return firstBuilt->positions;
}

int run(const Options& options) {
  if (!options.json)
    std::printf("Δ %s (%s) against its peers%s; %d hardware threads\n", delta::version(),
                delta::gitCommit(), bench::peerVersions().c_str(), omp_get_num_procs());
  std::vector<MeshReport> reports;
  bool agreed = true;
  for (const std::string& path : options.meshes) {
    const Mesh mesh = delta::io::load(path);
    MeshReport report;
    report.path = path;
    report.triangles = mesh.triangleCount();
    report.vertices = mesh.vertexCount();
    report.diagonal = mesh.bounds().diagonal();
    report.points = options.points;
    const std::vector<Vec3> uniform = uniformPoints(mesh.bounds(), options.points, kUniformSeed);
    std::vector<Vec3> nearSurface, gridVertices;
    std::vector<PointWorkload> workloads;
    if (options.workloads[0]) workloads.push_back({"W1 distance", &uniform, kInfinity});
    if (options.workloads[1])
      workloads.push_back({"W2 contacts", &uniform, kContactFraction * report.diagonal});
    if (options.workloads[2]) {
      nearSurface = nearSurfacePoints(mesh, kContactFraction * report.diagonal, options.points,
                                      kNearSurfaceSeed);
      workloads.push_back({"W3 near surface", &nearSurface, kInfinity});
    }
    if (options.workloads[4]) {
      gridVertices = runGridPhases(mesh, options, report);
      workloads.push_back(
          {"W5 grid vertices", &gridVertices, kInfinity, report.grid.signedDistance});
    }
    if (!workloads.empty()) runPointWorkloads(mesh, workloads, options, report);
    if (options.workloads[3]) runMeshMeshWorkloads(mesh, options, report);
    for (const Row& row : report.rows)
      agreed = agreed && row.agreed;
    for (const bench::GridPhases& phases : report.grid.rows)
      agreed = agreed && phases.agreed;
    if (!options.json) {
      bench::printTable(report);
      std::fflush(stdout);
    }
    reports.push_back(std::move(report));
  }
  if (options.json)
    printJson(options.points, reports, agreed);
  else
    std::printf("\nagreement: %s\n", agreed ? "every check passed" : "FAILED (see above)");
  return agreed ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const Options options = parseOptions(argc, argv);
  try {
    return run(options);
  } catch (const std::exception& error) {
    std::fprintf(stderr, "delta_bench_peers: %s\n", error.what());
    return 2;
  }
}
