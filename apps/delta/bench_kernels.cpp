// `delta bench kernels`: every triangle–triangle solver timed side by side on the same generated
// pairs, like `openssl speed`, so a user sees which is fastest on their machine.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/version.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/triangle_batch.h"
#include "delta/mesh/mesh.h"
#include "delta/mesh/triangle_soa.h"

#include "commands.h"
#include "json.h"
#include "stopwatch.h"

namespace delta::cli {
namespace {

constexpr std::size_t kMaxPairs = 2'000'000;  // about 600 MB of triangles and results
constexpr double kSecondsPerSolver = 0.3;     // each solver repeats the batch at least this long

struct BenchOptions {
  std::size_t pairs = 100'000;
  std::string isa;
  bool json = false;
};

/// DEM-like pairs, the same for every run: triangles of size about 1 around the origin; 3 in 4
/// near contacts (the second moved along a random direction until a plane separates the two with
/// a gap of 0–0.2 of the size, and slid sideways), 1 in 4 far apart (3–50 sizes).
class PairGenerator {
 public:
  std::pair<Triangle, Triangle> next(bool near) {
    const Triangle a = around(0.5), b = around(0.5 * uniform(0.5, 1.5));
    const double size = longestEdge(a, b);
    const Vec3 n = unitVector();
    if (!near) {
      const Vec3 shift = n * (size * uniform(3, 50));
      return {a, {b.a + shift, b.b + shift, b.c + shift}};
    }
    const auto along = [&](const Triangle& t, bool top) {
      const double x = dot(t.a, n), y = dot(t.b, n), z = dot(t.c, n);
      return top ? std::max({x, y, z}) : std::min({x, y, z});
    };
    const Vec3 u = normalized(cross(n, std::fabs(n.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0}));
    const Vec3 v = cross(n, u);
    const double lift = along(a, true) - along(b, false) + uniform(0, 0.2) * size;
    const Vec3 shift =
        n * lift + u * (0.5 * size * uniform(-1, 1)) + v * (0.5 * size * uniform(-1, 1));
    return {a, {b.a + shift, b.b + shift, b.c + shift}};
  }

 private:
  double uniform(double low, double high) {
    return low + (high - low) * static_cast<double>(engine_() >> 11) * 0x1.0p-53;
  }
  Vec3 unitVector() {
    for (;;) {
      const Vec3 v{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
      const double n2 = lengthSquared(v);
      if (n2 > 1e-4 && n2 <= 1.0) return v / std::sqrt(n2);
    }
  }
  Triangle around(double radius) {
    const auto vertex = [&] { return unitVector() * (radius * uniform(0.3, 1.0)); };
    const Vec3 a = vertex(), b = vertex(), c = vertex();
    return {a, b, c};
  }
  static double longestEdge(const Triangle& a, const Triangle& b) {
    return std::max({distance(a.a, a.b), distance(a.b, a.c), distance(a.c, a.a), distance(b.a, b.b),
                     distance(b.b, b.c), distance(b.c, b.a)});
  }

  std::mt19937_64 engine_{20240611};
};

TriangleSoA flattenTriangles(const std::vector<Triangle>& triangles) {
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> indices;
  vertices.reserve(3 * triangles.size());
  indices.reserve(triangles.size());
  for (const Triangle& t : triangles) {
    const auto base = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), {t.a, t.b, t.c});
    indices.push_back({base, base + 1, base + 2});
  }
  return TriangleSoA(Mesh(std::move(vertices), std::move(indices)));
}

struct SolverReport {
  kernels::Solver solver = kernels::Solver::BruteForce;
  double pairsPerSecond = 0.0;
  double maxRelativeError = 0.0;
  double maxRelativeErrorConverged = 0.0;  ///< over the pairs flagged converged
  kernels::BatchStatistics statistics;
};

void run(const BenchOptions& options) {
  kernels::Isa isa = kernels::defaultIsa();
  if (!options.isa.empty()) {
    const std::optional<kernels::Isa> named = kernels::parseIsa(options.isa);
    if (!named)
      throw Error("--isa: unknown instruction set '" + options.isa +
                  "' (scalar, sse2, avx2, avx512, neon, sve)");
    if (!kernels::isSupported(*named))
      throw Error("--isa: this CPU (or build) cannot run " + options.isa);
    isa = *named;
  }
  const std::size_t count = options.pairs;
  std::vector<Triangle> first(count), second(count);
  PairGenerator generator;
  for (std::size_t i = 0; i < count; ++i)
    std::tie(first[i], second[i]) = generator.next(i % 4 != 3);
  const TriangleSoA firstSoa = flattenTriangles(first), secondSoa = flattenTriangles(second);
  std::vector<double> size(count), reference(count);
  for (std::size_t i = 0; i < count; ++i)
    size[i] = std::max({distance(first[i].a, first[i].b), distance(first[i].b, first[i].c),
                        distance(first[i].c, first[i].a), distance(second[i].a, second[i].b),
                        distance(second[i].b, second[i].c), distance(second[i].c, second[i].a)});

  kernels::PairResults results(count);
  std::vector<SolverReport> reports;
  for (kernels::Solver solver :
       {kernels::Solver::BruteForce, kernels::Solver::Penalty, kernels::Solver::Hybrid}) {
    SolverReport report;
    report.solver = solver;
    std::size_t runs = 0;
    Stopwatch clock;
    do {
      report.statistics = kernels::distances(solver, firstSoa, secondSoa, results, isa);
      ++runs;
    } while (clock.seconds() < kSecondsPerSolver);
    report.pairsPerSecond = static_cast<double>(runs * count) / clock.seconds();
    for (std::size_t i = 0; i < count; ++i) {
      if (solver == kernels::Solver::BruteForce) reference[i] = results.distance(i);
      const double error = std::fabs(results.distance(i) - reference[i]) / size[i];
      report.maxRelativeError = std::max(report.maxRelativeError, error);
      if (results.converged(i))
        report.maxRelativeErrorConverged = std::max(report.maxRelativeErrorConverged, error);
    }
    reports.push_back(report);
  }

  const auto rate = [&](std::size_t part) {
    return static_cast<double>(part) / static_cast<double>(count);
  };
  if (options.json) {
    JsonWriter json;
    json.beginObject()
        .value("pairs", count)
        .value("isa", kernels::name(isa))
        .value("threads", 1)
        .beginObject("solvers");
    for (const SolverReport& r : reports) {
      json.beginObject(kernels::name(r.solver))
          .value("pairs_per_s", r.pairsPerSecond)
          .value("max_rel_error", r.maxRelativeError);
      if (r.solver == kernels::Solver::Penalty)
        json.value("unconverged_rate", rate(r.statistics.unconverged))
            .value("max_rel_error_converged", r.maxRelativeErrorConverged);
      if (r.solver == kernels::Solver::Hybrid)
        json.value("fallback_rate", rate(r.statistics.fallbacks))
            .value("recheck_rate", rate(r.statistics.rechecked));
      json.endObject();
    }
    json.endObject().value("version", version()).value("git_commit", gitCommit()).endObject();
    std::printf("%s\n", json.str().c_str());
    return;
  }
  std::printf(
      "delta %s (git %s): %zu triangle pairs (3 in 4 near contacts, 1 in 4 far), "
      "ISA %s, 1 thread\n",
      version(), gitCommit(), count, kernels::name(isa));
  std::printf("%-12s %14s %16s  %s\n", "solver", "pairs/s", "max rel. error", "");
  for (const SolverReport& r : reports) {
    std::string note;
    char buffer[128];
    if (r.solver == kernels::Solver::BruteForce) note = "the reference";
    if (r.solver == kernels::Solver::Penalty) {
      std::snprintf(buffer, sizeof buffer, "unconverged %.2f%% (converged: error ≤ %.2g)",
                    100 * rate(r.statistics.unconverged), r.maxRelativeErrorConverged);
      note = buffer;
    }
    if (r.solver == kernels::Solver::Hybrid) {
      std::snprintf(buffer, sizeof buffer, "rechecked %.2f%%, brute-force fallback %.3f%%",
                    100 * rate(r.statistics.rechecked), 100 * rate(r.statistics.fallbacks));
      note = buffer;
    }
    std::printf("%-12s %12.3f M %16.3g  %s\n", kernels::name(r.solver), r.pairsPerSecond / 1e6,
                r.maxRelativeError, note.c_str());
  }
  std::printf("(max rel. error: |distance − brute force| / longest edge of the pair)\n");
}

}  // namespace

void addBenchCommand(CLI::App& app) {
  CLI::App* bench = app.add_subcommand("bench", "Time Δ's kernels on generated input");
  // A misspelt benchmark is named in the error (CLI11 would only say a subcommand is required).
  auto unknown = std::make_shared<std::string>();
  bench->add_option("BENCHMARK", *unknown, "The benchmark: kernels");
  bench->require_subcommand(0, 1);
  bench->callback([bench, unknown] {
    if (!unknown->empty())
      throw Error("bench: unknown benchmark '" + *unknown + "' (benchmarks: kernels)");
    if (bench->get_subcommands().empty()) throw Error("bench: name a benchmark (kernels)");
  });
  auto options = std::make_shared<BenchOptions>();
  CLI::App* kernels = bench->add_subcommand(
      "kernels", "Time every triangle–triangle solver side by side on the same pairs");
  kernels
      ->add_option("--pairs", options->pairs,
                   "Triangle pairs to generate (1 to " + std::to_string(kMaxPairs) + ")")
      ->check(CLI::Range(std::size_t{1}, kMaxPairs));
  kernels->add_option("--isa", options->isa,
                      "Instruction set for the SIMD solvers: scalar, sse2, avx2, avx512 (x86-64), "
                      "neon, sve (AArch64) "
                      "(default: the widest this CPU runs)");
  kernels->add_flag("--json", options->json, "Print one JSON object instead of a table");
  // A stray word after `kernels` falls through to BENCHMARK, whose check runs after this
  // callback: checked here first, so that nothing runs for a command line that is refused.
  kernels->callback([options, unknown] {
    if (!unknown->empty())
      throw Error("bench kernels: unexpected argument '" + *unknown +
                  "' (see delta bench kernels --help)");
    run(*options);
  });
}

}  // namespace delta::cli
