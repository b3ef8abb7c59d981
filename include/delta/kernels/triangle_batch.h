#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "delta/core/triangle.h"
#include "delta/kernels/hybrid.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/pair_results.h"
#include "delta/kernels/penalty.h"
#include "delta/mesh/triangle_soa.h"

namespace delta::kernels {

/// The three triangle–triangle solvers, interchangeable over the same batches and results.
enum class Solver : std::uint8_t {
  BruteForce,  ///< triangleDistanceBruteForce, one pair at a time: exact, scalar
  Penalty,     ///< penaltyDistances: approximate, SIMD
  Hybrid,      ///< hybridDistances: exact, SIMD with brute-force fallbacks
};

/// "bruteforce", "penalty", "hybrid" (the CLI's --method names).
const char* name(Solver solver) noexcept;
std::optional<Solver> parseSolver(std::string_view text) noexcept;

/// triangleDistanceBruteForce over a batch, in the shape of penaltyDistances: pairs
/// (first[i], second[i]) for i < min(first.size(), second.size(), results.capacity()).
/// errorBound = 0, newtonStep = 0, converged = true.
///
/// Threading: no shared state; concurrent calls are safe with distinct `results`.
BatchStatistics bruteForceDistances(const TriangleSoA& first, const TriangleSoA& second,
                                    PairResults& results) noexcept;

/// The same for one triangle against block[begin, end).
BatchStatistics bruteForceDistances(const Triangle& one, const TriangleSoA& block,
                                    std::size_t begin, std::size_t end,
                                    PairResults& results) noexcept;

/// Runs `solver` (`isa` is ignored by the brute force).
BatchStatistics distances(Solver solver, const TriangleSoA& first, const TriangleSoA& second,
                          PairResults& results, Isa isa = defaultIsa()) noexcept;
BatchStatistics distances(Solver solver, const Triangle& one, const TriangleSoA& block,
                          std::size_t begin, std::size_t end, PairResults& results,
                          Isa isa = defaultIsa()) noexcept;

}  // namespace delta::kernels
