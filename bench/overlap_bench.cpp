// The overlap of two closed meshes (query/overlap.h, issue 24), on one thread:
//
//  - Granulates/curves_off, Granulates/curves_on: pairs of 80-triangle granulates
//    (primitives::granulate, semi-axes 1), the second turned at random and moved along x until
//    they touch, then 1% of the radius further (a DEM contact); 64 pairs, one pair an
//    iteration, so the time is Δ's time a pair (target: 10 µs or less). Counters: the mean
//    volume, regions and segments a pair, pairs_per_s.
//  - Armadillo/delta: CGAL's armadillo (52,000 triangles) against peers' W4b copy (turned
//    0.6 rad about (1, 2, 3) around its box centre, moved along (1, 0.5, 0.25) to a gap of 0.1%
//    of the box diagonal D, then 5% of D further in), curves on and off; the copy is the same
//    QueryMesh at another pose. Armadillo/delta_prepare: a fresh QueryMesh of the armadillo and
//    its self-intersection check (what overlap() needs once a shape).
//  - Armadillo/cgal (built with CGAL): CGAL's corefine_and_compute_intersection then volume, on
//    Surface_meshes with Exact_predicates_inexact_constructions_kernel, of the world-frame
//    meshes; each iteration cuts fresh copies of the inputs, made outside the timing and timed
//    on their own as Armadillo/cgal_copy. Counters: CGAL's volume and its relative difference
//    from Δ's.
//  - Cubes/<pose>: two unit cubes (12 triangles each) sharing faces' planes, the exact
//    predicates' worst case: `turned_coplanar` (the second turned 30° about z and moved by
//    (0.5, 0.2, 0): top and bottom faces in the planes z = ±0.5), `turned_apart` (the same moved
//    10⁻³ further along z), `tilted_alike` (both tilted by one rotation, the second moved by
//    (0.5, 0.25, 0) in their frame: four pairs of faces coplanar but for the rounding of the
//    turned corners) and `tilted_diagonal` (moved by (0.5, 0.25, 0.125) instead).
//
// Run: build/bench/delta_bench_overlap --benchmark_repetitions=3 (data/meshes from
// scripts/setup.sh).

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "delta/core/rotation.h"
#include "delta/io/mesh_io.h"
#include "delta/mesh/primitives.h"
#include "delta/query/minimum_distance.h"
#include "delta/query/overlap.h"
#include "delta/query/query_mesh.h"
#include "delta/query/self_intersections.h"

#include "bench_main.h"
#include "omp_threads.h"
#ifdef DELTA_HAVE_CGAL
#include "overlap_cgal.h"
#endif

namespace {

using namespace delta;
namespace fs = std::filesystem;
namespace cd = contactdetection;

const fs::path kMeshes = fs::path(DELTA_DATA_DIR) / "meshes";

constexpr std::size_t kGranulatePairs = 64;
constexpr double kGranulateOverlap = 0.01;  // of the radius
constexpr double kGapFraction = 1e-3;       // peers' W4a gap, of the diagonal
constexpr double kOverlapFraction = 0.05;   // peers' W4b overlap, of the diagonal
constexpr double kRotationRadians = 0.6;    // peers' W4 copy
const Vec3 kRotationAxis{1, 2, 3};
const Vec3 kApproach = normalized(Vec3{1, 0.5, 0.25});

struct GranulatePair {
  QueryMesh first, second;
};

/// Granulate 2k+1 at the origin and granulate 2k+2 turned at random, moved along −x from its
/// +x side until the two touch (bisection on the minimum distance, to 10⁻⁶ of the radius), then
/// 1% of the radius further in.
std::vector<GranulatePair> granulatePairs() {
  std::mt19937_64 random(24);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<GranulatePair> pairs;
  for (std::uint64_t k = 0; k < kGranulatePairs; ++k) {
    const QueryMesh first(primitives::granulate(2 * k + 1));
    QueryMesh second(primitives::granulate(2 * k + 2));
    const double w = unit(random), x = unit(random), y = unit(random), z = unit(random);
    const RigidTransform turn{Quaternion::fromComponents(w, x, y, z), {}};
    double touching = 0.0, apart = 4.0;  // the radii are 1
    while (apart - touching > 1e-6) {
      const double middle = 0.5 * (touching + apart);
      second.setPose(RigidTransform::translationBy({middle, 0, 0}) * turn);
      (cd::minimumDistance(first, second).distance > 0.0 ? apart : touching) = middle;
    }
    second.setPose(RigidTransform::translationBy({touching - kGranulateOverlap, 0, 0}) * turn);
    selfIntersections(first);  // made once a shape, outside the timing
    selfIntersections(second);
    pairs.push_back({first, second});
  }
  return pairs;
}

void granulates(benchmark::State& state, bool curves) {
  const bench::OmpThreads threads(1);
  const std::vector<GranulatePair> pairs = granulatePairs();
  cd::OverlapOptions options;
  options.curves = curves;
  std::size_t next = 0;
  for (auto _ : state) {
    const GranulatePair& pair = pairs[next];
    next = next + 1 == pairs.size() ? 0 : next + 1;
    benchmark::DoNotOptimize(cd::overlap(pair.first, pair.second, options).total.volume);
  }
  double volume = 0.0, regions = 0.0, segments = 0.0;
  for (const GranulatePair& pair : pairs) {
    const cd::Overlap found = cd::overlap(pair.first, pair.second, options);
    volume += found.total.volume;
    regions += static_cast<double>(found.regions.size());
    segments += static_cast<double>(found.segments);
  }
  const double count = static_cast<double>(pairs.size());
  state.counters["volume"] = volume / count;
  state.counters["regions"] = regions / count;
  state.counters["segments"] = segments / count;
  state.counters["pairs_per_s"] =
      benchmark::Counter(1.0, benchmark::Counter::kIsIterationInvariantRate);
}

/// The armadillo and peers' W4b copy: one QueryMesh, two poses.
struct Armadillo {
  Mesh mesh;
  QueryMesh first, second;
};

/// The copy's pose: turned about the box centre, then moved `shift` along kApproach.
RigidTransform copyPose(const Mesh& mesh, double shift) {
  const RigidTransform turn = RigidTransform::rotationAbout(
      Quaternion::fromAxisAngle(kRotationAxis, kRotationRadians), mesh.bounds().center());
  return RigidTransform::translationBy(kApproach * shift) * turn;
}

/// As peers' W4b: the shift that leaves a gap of 0.1% of D (to 1%, by bisection on the minimum
/// distance), less 5% of D.
const Armadillo& armadillo() {
  static const Armadillo made = [] {
    const Mesh mesh = io::load(kMeshes / "armadillo.off");
    const QueryMesh first(mesh);
    QueryMesh second = first;
    const double diagonal = mesh.bounds().diagonal(), gap = kGapFraction * diagonal;
    const auto gapAt = [&](double shift) {
      second.setPose(copyPose(mesh, shift));
      return cd::minimumDistance(first, second).distance;
    };
    double low = 0.0, high = 2.0 * diagonal, shift = 0.5 * (low + high);
    if (gapAt(low) >= gap || gapAt(high) <= gap)
      throw std::runtime_error("the turned copy does not cross the gap between 0 and 2 D");
    for (int step = 0; step < 200; ++step) {
      shift = 0.5 * (low + high);
      const double at = gapAt(shift);
      if (std::abs(at - gap) <= 0.01 * gap) break;
      (at < gap ? low : high) = shift;
    }
    second.setPose(copyPose(mesh, shift - kOverlapFraction * diagonal));
    selfIntersections(first);  // shared by the copy
    return Armadillo{mesh, first, second};
  }();
  return made;
}

bool armadilloMissing(benchmark::State& state) {
  if (fs::exists(kMeshes / "armadillo.off")) return false;
  state.SkipWithError("no data/meshes/armadillo.off (scripts/setup.sh)");
  return true;
}

/// A QueryMesh's mesh where its pose puts it (as overlap() sees it).
Mesh worldMesh(const QueryMesh& mesh) {
  Mesh moved = mesh.mesh();
  moved.transform(mesh.pose());
  return moved;
}

void armadilloDelta(benchmark::State& state, bool curves) {
  if (armadilloMissing(state)) return;
  const bench::OmpThreads threads(1);
  const Armadillo& scene = armadillo();
  cd::OverlapOptions options;
  options.curves = curves;
  cd::Overlap found;
  for (auto _ : state) {
    found = cd::overlap(scene.first, scene.second, options);
    // The whole result: benchmark 1.7.1's DoNotOptimize on a double member ("+m,r") came
    // back as garbage with GCC 12 here.
    benchmark::DoNotOptimize(found);
  }
  state.counters["volume"] = found.total.volume;
  state.counters["regions"] = static_cast<double>(found.regions.size());
  state.counters["segments"] = static_cast<double>(found.segments);
  state.counters["curves"] = static_cast<double>(found.curves.size());
}

void armadilloPrepare(benchmark::State& state) {
  if (armadilloMissing(state)) return;
  const bench::OmpThreads threads(1);
  const Mesh& mesh = armadillo().mesh;
  for (auto _ : state) {
    const QueryMesh prepared(mesh);
    benchmark::DoNotOptimize(selfIntersections(prepared).count);
  }
}

/// Cubes/<pose>: the two cubes' poses.
struct CubePoses {
  const char* name;
  RigidTransform first, second;
};

std::vector<CubePoses> cubePoses() {
  const double half = 0.5235987755982988 / 2.0;  // 30°
  const Quaternion turn = Quaternion::fromComponents(std::cos(half), 0.0, 0.0, std::sin(half));
  const RigidTransform tilt{Quaternion::fromComponents(0.9, 0.3, -0.2, 0.1), {}};
  return {{"turned_coplanar", {}, RigidTransform{turn, {0.5, 0.2, 0.0}}},
          {"turned_apart", {}, RigidTransform{turn, {0.5, 0.2, 1e-3}}},
          {"tilted_alike", tilt, tilt * RigidTransform::translationBy({0.5, 0.25, 0.0})},
          {"tilted_diagonal", tilt, tilt * RigidTransform::translationBy({0.5, 0.25, 0.125})}};
}

void cubes(benchmark::State& state, const CubePoses& poses) {
  const bench::OmpThreads threads(1);
  QueryMesh first(primitives::box()), second(primitives::box());
  first.setPose(poses.first);
  second.setPose(poses.second);
  cd::OverlapOptions options;
  options.curves = false;  // as a DEM step
  cd::Overlap found;
  for (auto _ : state) {
    found = cd::overlap(first, second, options);
    benchmark::DoNotOptimize(found);
  }
  state.counters["volume"] = found.total.volume;
  state.counters["segments"] = static_cast<double>(found.segments);
}

#ifdef DELTA_HAVE_CGAL
void armadilloCgal(benchmark::State& state) {
  if (armadilloMissing(state)) return;
  const bench::OmpThreads threads(1);
  const Armadillo& scene = armadillo();
  bench::CgalIntersection cgal(worldMesh(scene.first), worldMesh(scene.second));
  double volume = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    cgal.copyInputs();
    state.ResumeTiming();
    volume = cgal.intersectCopies();
  }
  const double delta = cd::overlap(scene.first, scene.second).total.volume;
  state.counters["volume"] = volume;
  state.counters["relative_difference"] = std::abs(volume - delta) / delta;
  if (std::isnan(volume)) state.SkipWithError("CGAL could not corefine (non-manifold result)");
}

void armadilloCgalCopy(benchmark::State& state) {
  if (armadilloMissing(state)) return;
  const Armadillo& scene = armadillo();
  bench::CgalIntersection cgal(worldMesh(scene.first), worldMesh(scene.second));
  for (auto _ : state)
    cgal.copyInputs();
}
#endif

const int registered = [] {
  for (const bool curves : {false, true})
    benchmark::RegisterBenchmark(curves ? "Granulates/curves_on" : "Granulates/curves_off",
                                 [curves](benchmark::State& s) { granulates(s, curves); })
        ->Unit(benchmark::kMicrosecond);
  for (const CubePoses& poses : cubePoses())
    benchmark::RegisterBenchmark((std::string("Cubes/") + poses.name).c_str(),
                                 [poses](benchmark::State& s) { cubes(s, poses); })
        ->Unit(benchmark::kMicrosecond);
  for (const bool curves : {false, true})
    benchmark::RegisterBenchmark(
        curves ? "Armadillo/delta/curves_on" : "Armadillo/delta/curves_off",
        [curves](benchmark::State& s) { armadilloDelta(s, curves); })
        ->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Armadillo/delta_prepare", armadilloPrepare)
      ->Unit(benchmark::kMillisecond);
#ifdef DELTA_HAVE_CGAL
  benchmark::RegisterBenchmark("Armadillo/cgal", armadilloCgal)->Unit(benchmark::kMillisecond);
  benchmark::RegisterBenchmark("Armadillo/cgal_copy", armadilloCgalCopy)
      ->Unit(benchmark::kMillisecond);
#endif
  return 0;
}();

}  // namespace

int main(int argc, char** argv) {
  benchmark::AddCustomContext("delta_threads", "1");
#ifdef DELTA_HAVE_CGAL
  benchmark::AddCustomContext("cgal_peer", "corefine_and_compute_intersection, Epick");
#endif
  return delta::bench::runBenchmarks(argc, argv);
}
