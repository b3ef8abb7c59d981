#include "delta/kernels/triangle_batch.h"

#include "delta/kernels/detail/batch_dispatch.h"
#include "delta/kernels/triangle_triangle.h"

#include "detail/exact_store.h"

namespace delta::kernels {
namespace {

void store(const detail::PairStreams& out, std::size_t i,
           const TriangleDistanceResult& result) noexcept {
  detail::storeExact(out, i, result);
  out.newtonStep[i] = 0.0;
}

}  // namespace

const char* name(Solver solver) noexcept {
  switch (solver) {
    case Solver::BruteForce:
      return "bruteforce";
    case Solver::Penalty:
      return "penalty";
    case Solver::Hybrid:
      return "hybrid";
  }
  return "?";
}

std::optional<Solver> parseSolver(std::string_view text) noexcept {
  for (Solver solver : {Solver::BruteForce, Solver::Penalty, Solver::Hybrid})
    if (text == name(solver)) return solver;
  return std::nullopt;
}

BatchStatistics bruteForceDistances(const TriangleSoA& first, const TriangleSoA& second,
                                    PairResults& results) noexcept {
  const detail::PairStreams out = results.prepare(detail::blockPairCount(first, second));
  for (std::size_t i = 0; i < results.size(); ++i)
    store(out, i, triangleDistanceBruteForce(first.triangle(i), second.triangle(i)));
  return {results.size(), 0, 0, 0};
}

BatchStatistics bruteForceDistances(const Triangle& one, const TriangleSoA& block,
                                    std::size_t begin, std::size_t end,
                                    PairResults& results) noexcept {
  const detail::PairStreams out = results.prepare(detail::rangePairCount(block, begin, end));
  for (std::size_t j = 0; j < results.size(); ++j)
    store(out, j, triangleDistanceBruteForce(one, block.triangle(begin + j)));
  return {results.size(), 0, 0, 0};
}

BatchStatistics distances(Solver solver, const TriangleSoA& first, const TriangleSoA& second,
                          PairResults& results, Isa isa) noexcept {
  switch (solver) {
    case Solver::Penalty:
      return penaltyDistances(first, second, results, isa);
    case Solver::Hybrid:
      return hybridDistances(first, second, results, isa);
    case Solver::BruteForce:
      break;
  }
  return bruteForceDistances(first, second, results);
}

BatchStatistics distances(Solver solver, const Triangle& one, const TriangleSoA& block,
                          std::size_t begin, std::size_t end, PairResults& results,
                          Isa isa) noexcept {
  switch (solver) {
    case Solver::Penalty:
      return penaltyDistances(one, block, begin, end, results, isa);
    case Solver::Hybrid:
      return hybridDistances(one, block, begin, end, results, isa);
    case Solver::BruteForce:
      break;
  }
  return bruteForceDistances(one, block, begin, end, results);
}

}  // namespace delta::kernels
