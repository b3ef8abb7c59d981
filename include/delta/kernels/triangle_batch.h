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

/// The three triangle–triangle solvers, interchangeable over the same batches and results
/// (docs/triangle_solvers.md compares them).
enum class Solver : std::uint8_t {
  BruteForce,  ///< triangleDistanceBruteForce, one pair at a time: exact, scalar
  Penalty,     ///< penaltyDistances: approximate, SIMD
  Hybrid,      ///< hybridDistances: exact, SIMD with brute-force fallbacks
};

/// "bruteforce", "penalty", "hybrid" (the CLI's --method names).
///
/// Threading: a pure function.
const char* name(Solver solver) noexcept;
/// The inverse of name(); nullopt for anything else.
///
/// Threading: a pure function.
std::optional<Solver> parseSolver(std::string_view text) noexcept;

/// triangleDistanceBruteForce over a batch, in the shape of penaltyDistances: pairs
/// (first[i], second[i]) for i < min(first.size(), second.size(), results.capacity()).
/// errorBound = 0, newtonStep = 0, converged = true; everything else as triangleDistanceBruteForce
/// (degenerate, touching and intersecting pairs included). Padding lanes are never computed.
///
/// Threading: no shared state; concurrent calls are safe with distinct `results`.
BatchStatistics bruteForceDistances(const TriangleSoA& first, const TriangleSoA& second,
                                    PairResults& results) noexcept;

/// The same for one triangle against block[begin, end): pair j is (one, block[begin + j]), for
/// j < min(end, block.size()) − begin, at most results.capacity() (none when begin ≥ end).
BatchStatistics bruteForceDistances(const Triangle& one, const TriangleSoA& block,
                                    std::size_t begin, std::size_t end,
                                    PairResults& results) noexcept;

/// Runs `solver` (`isa` is ignored by the brute force): the contract and threading of the
/// solver's own function, for both pair shapes.
BatchStatistics distances(Solver solver, const TriangleSoA& first, const TriangleSoA& second,
                          PairResults& results, Isa isa = defaultIsa()) noexcept;
BatchStatistics distances(Solver solver, const Triangle& one, const TriangleSoA& block,
                          std::size_t begin, std::size_t end, PairResults& results,
                          Isa isa = defaultIsa()) noexcept;

}  // namespace delta::kernels
