// The guide's "Choosing a solver" (docs/guide.md): the three triangle–triangle solvers through
// the contact query, and batched over a code's own triangle pairs.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "delta/delta.h"

int main() try {
  namespace cd = delta::contactdetection;
  namespace kernels = delta::kernels;
  const delta::QueryMesh a(delta::primitives::granulate(1));
  delta::QueryMesh b(delta::primitives::granulate(2));
  b.transform(delta::RigidTransform::translationBy({1.8, 0.1, 0.2}));
  const double epsilon = 0.05;

  // [guide:begin query]
  using kernels::Solver;
  const auto exact = cd::contacts(a, b, epsilon);  // Solver::Hybrid: exact, SIMD
  const auto reference = cd::contacts(a, b, epsilon, Solver::BruteForce);  // exact, scalar
  const auto approximate = cd::contacts(a, b, epsilon, Solver::Penalty);   // may miss or misplace
  // [guide:end query]
  std::printf("%zu contacts (hybrid), %zu (brute force), %zu (penalty)\n", exact.size(),
              reference.size(), approximate.size());

  // The hybrid's contacts are the brute force's: the same pairs, distances to 1e-12 of the size.
  bool same = !exact.empty() && exact.size() == reference.size();
  for (std::size_t i = 0; same && i < exact.size(); ++i)
    same = exact[i].first == reference[i].first && exact[i].second == reference[i].second &&
           std::abs(exact[i].distance - reference[i].distance) <= 1e-12 * 2.0;
  if (!same) {
    std::fprintf(stderr, "the hybrid's contacts differ from the brute force's\n");
    return 1;
  }

  // Batched: a code's own pairs, triangle i of `first` against triangle i of `second`, here a
  // particle against a slightly turned and moved copy: near, nearly parallel pairs.
  delta::Mesh moved = delta::primitives::granulate(1);
  moved.rotate({1, 2, 3}, 0.05).translate({0.01, 0.02, 0.03});
  const delta::TriangleSoA first = delta::flatten(delta::primitives::granulate(1));
  const delta::TriangleSoA second = delta::flatten(moved);

  // [guide:begin batch]
  kernels::PairResults results(first.size());  // allocated once, reused batch after batch
  kernels::BatchStatistics statistics = kernels::penaltyDistances(first, second, results);
  std::printf("penalty: %zu of %zu pairs not converged\n", statistics.unconverged, results.size());
  std::vector<double> penalty(results.size());
  for (std::size_t i = 0; i < results.size(); ++i)
    penalty[i] = results.converged(i) ? results.distance(i) : -1.0;  // -1: do not trust it

  statistics = kernels::hybridDistances(first, second, results);  // exact, every pair
  std::printf("hybrid: %zu pairs, %zu left to the brute force\n", results.size(),
              statistics.fallbacks);
  // [guide:end batch]

  // A converged penalty answer is within its tolerance of the exact distance, relative to the
  // pair's size (its longest edge).
  const auto longestEdge = [](const delta::Triangle& t) {
    return std::max(
        {delta::distance(t.a, t.b), delta::distance(t.b, t.c), delta::distance(t.c, t.a)});
  };
  for (std::size_t i = 0; i < results.size(); ++i) {
    const double size = std::max(longestEdge(first.triangle(i)), longestEdge(second.triangle(i)));
    if (penalty[i] >= 0.0 &&
        std::abs(penalty[i] - results.distance(i)) > 1.01 * kernels::kPenaltyTolerance * size) {
      std::fprintf(stderr, "pair %zu: penalty %.17g, hybrid %.17g\n", i, penalty[i],
                   results.distance(i));
      return 1;
    }
  }
  return 0;
} catch (const delta::Error& error) {
  std::fprintf(stderr, "choosing_a_solver: %s\n", error.what());
  return 1;
}
