// Winding-number signs (PointQuery::sign = Sign::winding) and self-intersections (issue 22):
//
//  - Agreement/<mesh>: 50,000 points within 1% of the diagonal of the surface (offsets from a
//    random point of a random triangle, log-uniform from 1e-4 to 1e-2 of the diagonal, in a
//    random direction); counters: `disagree` (winding sign ≠ sign of the exact winding number
//    over all triangles, at points where that is further than 1e-9 from ½), `ambiguous` (|w − ½|
//    ≤ 0.05), `pseudonormal_wrong` (the pseudonormal sign ≠ the exact winding sign: the issue's
//    reproduction on camel and bull, where Δ now refuses pseudonormals), `exact_fallbacks`.
//  - Signed/<mesh>/<sign>: 10^5 points uniform in the box grown by 10%, queries per second.
//  - SelfIntersections/<mesh>: a fresh QueryMesh's selfIntersections().
//
// Meshes: CGAL's ChineseDragon-10kv (6 boundary edges), armadillo with a cut hole, camel, bull
// (closed, crossing themselves), armadillo; icosphere(7) (327,680 triangles) for the size of a
// 345k-triangle armadillo. Run: build-r/bench/delta_bench_winding (data/meshes from
// scripts/setup.sh).

#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "delta/core/parallel.h"
#include "delta/io/mesh_io.h"
#include "delta/mesh/primitives.h"
#include "delta/query/point_distance.h"
#include "delta/query/self_intersections.h"
#include "delta/query/winding_number.h"

// The pseudonormal sign itself (which the public queries refuse on a crossing mesh), for the
// issue's reproduction only.
#include "../src/query/detail/query_mesh_data.h"
#include "bench_main.h"

namespace {

using namespace delta;
namespace fs = std::filesystem;
namespace cd = contactdetection;

const fs::path kMeshes = fs::path(DELTA_DATA_DIR) / "meshes";

/// `mesh` less its triangles whose centroid lies within `radius` of triangle `centre`'s.
Mesh cutHole(const Mesh& mesh, std::size_t centre, double radius) {
  const Vec3 at = mesh.triangle(centre).centroid();
  std::vector<TriangleIndices> kept;
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t)
    if (length(mesh.triangle(t).centroid() - at) > radius) kept.push_back(mesh.triangles()[t]);
  return Mesh({mesh.vertices().begin(), mesh.vertices().end()}, kept);
}

Mesh named(const std::string& name) {
  if (name == "icosphere7") return primitives::icosphere(7);
  if (name == "armadillo-hole") {
    const Mesh armadillo = io::load(kMeshes / "armadillo.off");
    return cutHole(armadillo, 1000, 0.03 * armadillo.bounds().diagonal());
  }
  return io::load(kMeshes / (name + ".off"));
}

std::vector<Vec3> nearSurface(const Mesh& mesh, std::size_t count, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double diagonal = mesh.bounds().diagonal();
  std::vector<Vec3> points(count);
  for (Vec3& p : points) {
    const Triangle t = mesh.triangle(random() % mesh.triangleCount());
    double u = unit(random), v = unit(random);
    if (u + v > 1.0) u = 1.0 - u, v = 1.0 - v;
    const Vec3 direction =
        normalized(Vec3{unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5});
    const double offset = diagonal * std::pow(10.0, -4.0 + 2.0 * unit(random));
    p = t.a + (t.b - t.a) * u + (t.c - t.a) * v + direction * offset;
  }
  return points;
}

void agreement(benchmark::State& state, const std::string& name) {
  if (name != "icosphere7" && !fs::exists(kMeshes / "armadillo.off")) {
    state.SkipWithError("no data/meshes (scripts/setup.sh)");
    return;
  }
  const Mesh mesh = named(name);
  const QueryMesh query(mesh);
  const TriangleSoA triangles = flatten(mesh);
  const std::vector<Vec3> points = nearSurface(mesh, 50'000, 22);
  cd::PointQuery request;
  request.signedDistance = true;
  request.sign = cd::Sign::winding;
  std::vector<cd::PointDistance> answers;
  for (auto _ : state)
    answers = cd::distances(query, points, request);
  std::vector<double> exact(points.size());
  std::vector<unsigned char> pseudonormal(points.size());
  const detail::QueryMeshData& data = query.data();
  const double orientation = data.windingTree().orientation;
  parallelFor(0, points.size(), 64, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      exact[i] = windingNumber(triangles, points[i]) * orientation;
      if (query.closed()) {
        const detail::Nearest nearest =
            detail::nearestTriangle(data, points[i], std::numeric_limits<double>::infinity());
        pseudonormal[i] = detail::insideAt(data, points[i], nearest);
      }
    }
  });
  double disagree = 0, ambiguous = 0, pseudonormalWrong = 0, exactAmbiguous = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    ambiguous += answers[i].ambiguous;
    exactAmbiguous += std::abs(exact[i] - 0.5) <= 0.05;
    if (!(answers[i].distance > 0.0) || !(std::abs(exact[i] - 0.5) > 1e-9)) continue;
    disagree += answers[i].inside != (exact[i] > 0.5);
    if (query.closed()) pseudonormalWrong += (pseudonormal[i] != 0) != (exact[i] > 0.5);
  }
  state.counters["points"] = static_cast<double>(points.size());
  state.counters["triangles"] = static_cast<double>(mesh.triangleCount());
  state.counters["self_intersections"] = static_cast<double>(selfIntersections(query).count);
  state.counters["disagree"] = disagree;
  state.counters["ambiguous"] = ambiguous;
  state.counters["exact_ambiguous"] = exactAmbiguous;
  state.counters["pseudonormal_wrong"] = query.closed() ? pseudonormalWrong : NAN;
  state.counters["queries_per_s"] = benchmark::Counter(
      static_cast<double>(points.size()), benchmark::Counter::kIsIterationInvariantRate);
}

void signedQueries(benchmark::State& state, const std::string& name, cd::Sign sign) {
  if (name != "icosphere7" && !fs::exists(kMeshes / "armadillo.off")) {
    state.SkipWithError("no data/meshes (scripts/setup.sh)");
    return;
  }
  const Mesh mesh = named(name);
  const QueryMesh query(mesh);
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Aabb box = mesh.bounds();
  std::vector<Vec3> points(100'000);
  for (Vec3& p : points)
    p = box.lower - box.extent() * 0.1 +
        Vec3{unit(random) * box.extent().x, unit(random) * box.extent().y,
             unit(random) * box.extent().z} *
            1.2;
  cd::PointQuery request;
  request.signedDistance = true;
  request.sign = sign;
  cd::distances(query, points, request);  // the pseudonormals, self-intersections, moments
  for (auto _ : state)
    benchmark::DoNotOptimize(cd::distances(query, points, request));
  state.counters["queries_per_s"] = benchmark::Counter(
      static_cast<double>(points.size()), benchmark::Counter::kIsIterationInvariantRate);
}

void selfIntersectionsOf(benchmark::State& state, const std::string& name) {
  if (name != "icosphere7" && !fs::exists(kMeshes / "armadillo.off")) {
    state.SkipWithError("no data/meshes (scripts/setup.sh)");
    return;
  }
  const Mesh mesh = named(name);
  std::size_t count = 0;
  for (auto _ : state) {
    state.PauseTiming();
    const QueryMesh query(mesh);  // a fresh one: the count is kept by the prepared data
    state.ResumeTiming();
    count = selfIntersections(query).count;
  }
  state.counters["triangles"] = static_cast<double>(mesh.triangleCount());
  state.counters["self_intersections"] = static_cast<double>(count);
  state.counters["triangles_per_s"] = benchmark::Counter(
      static_cast<double>(mesh.triangleCount()), benchmark::Counter::kIsIterationInvariantRate);
}

const int registered = [] {
  for (const char* name : {"ChineseDragon-10kv", "armadillo-hole", "camel", "bull"})
    benchmark::RegisterBenchmark((std::string("Agreement/") + name).c_str(),
                                 [name](benchmark::State& s) { agreement(s, name); })
        ->Iterations(1)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  for (const char* name : {"armadillo", "armadillo-hole", "camel", "ChineseDragon-10kv"})
    for (const cd::Sign sign : {cd::Sign::pseudonormal, cd::Sign::winding}) {
      const bool refused = sign == cd::Sign::pseudonormal && std::string(name) != "armadillo";
      if (refused) continue;  // open or crossing: pseudonormals refuse it
      benchmark::RegisterBenchmark(
          (std::string("Signed/") + name +
           (sign == cd::Sign::winding ? "/winding" : "/pseudonormal"))
              .c_str(),
          [name, sign](benchmark::State& s) { signedQueries(s, name, sign); })
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime();
    }
  for (const char* name : {"armadillo", "camel", "bull", "icosphere7"})
    benchmark::RegisterBenchmark((std::string("SelfIntersections/") + name).c_str(),
                                 [name](benchmark::State& s) { selfIntersectionsOf(s, name); })
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
  return 0;
}();

}  // namespace

int main(int argc, char** argv) {
  benchmark::AddCustomContext("delta_threads", std::to_string(delta::threadCount()));
  return delta::bench::runBenchmarks(argc, argv);
}
