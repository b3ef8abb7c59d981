#include "delta/query/minimum_distance.h"

#include <cmath>
#include <limits>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/parallel.h"
#include "delta/kernels/pair_results.h"

namespace delta::contactdetection {
namespace {

/// Pairs handed to the kernels at once: one triangle against this many of the other mesh.
constexpr std::size_t kBlock = 256;
/// Triangles of the first mesh per parallel chunk.
constexpr std::size_t kGrain = 8;

struct Closest {
  double distanceSquared = std::numeric_limits<double>::infinity();
  std::uint32_t second = 0;
  Vec3 p, q;
  bool intersect = false;
};

/// The closest triangle of `second` to `one`; ties go to the smallest id (blocks and pairs are
/// visited in order and only a strictly smaller distance replaces the best).
Closest closestTo(const Triangle& one, const TriangleSoA& second, kernels::Solver solver,
                  kernels::PairResults& results) {
  Closest best;
  for (std::size_t begin = 0; begin < second.size(); begin += kBlock) {
    const std::size_t end = begin + kBlock < second.size() ? begin + kBlock : second.size();
    kernels::distances(solver, one, second, begin, end, results);
    for (std::size_t j = 0; j < results.size(); ++j)
      if (results.distanceSquared(j) < best.distanceSquared) {
        best.distanceSquared = results.distanceSquared(j);
        best.second = static_cast<std::uint32_t>(begin + j);
        best.p = results.p(j);
        best.q = results.q(j);
        best.intersect = results.intersect(j);
      }
  }
  return best;
}

}  // namespace

MinimumDistance minimumDistance(const TriangleSoA& first, const TriangleSoA& second,
                                kernels::Solver solver) {
  if (first.size() == 0 || second.size() == 0)
    throw Error("minimumDistance: a mesh has no triangles");
  std::vector<Closest> closest(first.size());
  parallelFor(0, first.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    kernels::PairResults results(kBlock);
    for (std::size_t i = begin; i < end; ++i)
      closest[i] = closestTo(first.triangle(i), second, solver, results);
  });
  std::size_t bestFirst = 0;  // serial reduction in id order: the same answer for any threads
  for (std::size_t i = 1; i < closest.size(); ++i)
    if (closest[i].distanceSquared < closest[bestFirst].distanceSquared) bestFirst = i;
  const Closest& best = closest[bestFirst];
  return {std::sqrt(best.distanceSquared),
          static_cast<std::uint32_t>(bestFirst),
          best.second,
          best.p,
          best.q,
          best.intersect};
}

}  // namespace delta::contactdetection
