#pragma once

#include <cstddef>

#include "delta/core/triangle.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/pair_results.h"
#include "delta/mesh/triangle_soa.h"

namespace delta::kernels {

/// The penalty solver's converged threshold, relative to the pair's size L (its longest edge):
/// a pair is flagged converged when its certified error bound is at most this·L.
inline constexpr double kPenaltyTolerance = 1e-6;

/// Fixed Newton iterations of the penalty solver (unrolled at compile time).
inline constexpr int kPenaltyIterations = 6;

/// Triangle–triangle distances by the seed's penalty Newton (section 3.1, equation 1), batched:
/// one SIMD lane per pair, branch-free, a fixed count of iterations; approximate.
///
/// Method: minimise ½|T1(a1, a2) − T2(a3, a4)|² over the four barycentric unknowns with a
/// quadratic penalty ρ·½·min(c, 0)² on the six constraints (a1, a2 ≥ 0, a1 + a2 ≤ 1, likewise
/// a3, a4) and a diagonal regularisation α of the Newton matrix, from the centroids, in the local
/// frame of the first triangle's first vertex and in units of the pair's size L (its longest
/// edge). ρ rises 10² → 10⁸ and α falls 10⁻² → 10⁻⁸ over the kPenaltyIterations steps; each step
/// solves the 4×4 system explicitly (one division).
///
/// Contract, per pair:
/// - p and q are the Newton point projected onto the triangles, so they lie on them and
///   distance ≥ the true distance, always, converged or not.
/// - errorBound ≥ distance − true distance (certified by convexity: the duality gap of the
///   linearised problem, up to rounding of a few ulps of distance + L); it is the distance
///   itself where nothing better is known.
/// - converged = errorBound ≤ kPenaltyTolerance·L. A pair not converged still gets its feasible
///   p, q and their distance, which may be grossly too large (the iteration can cycle between
///   active sets); newtonStep says how far the last step moved.
/// - intersect = converged and distance ≤ kPenaltyTolerance·L: touching within the tolerance,
///   not an exact test (hybridDistances is exact).
/// - Results are finite for every finite pair whose coordinates stay within ±1e150 and whose
///   size exceeds 1e-150 (L² must neither overflow nor underflow): zero-area triangles and
///   points included, though those are often not converged (a step whose 4×4 system comes out
///   singular in rounding is skipped).
///
/// Pairs: (first[i], second[i]) for i < min(first.size(), second.size(), results.capacity()).
/// SoA padding lanes are computed but never stored, so results.size() is that count.
///
/// `isa` picks the instruction set (default: defaultIsa()); one the CPU cannot run is lowered
/// (supportedIsaAtMost). Every ISA runs the same arithmetic; SSE2 gives the scalar reference's
/// results to the bit. AVX2 and AVX-512 contract multiply–adds into FMAs, whose different last
/// bits the ill-conditioned Newton systems (ρ/α up to 10¹⁶) can amplify: about 1% of pairs are
/// converged on one ISA and not on another; where both converge, the distances agree within
/// their error bounds.
///
/// Threading: no shared state; concurrent calls are safe with distinct `results`.
BatchStatistics penaltyDistances(const TriangleSoA& first, const TriangleSoA& second,
                                 PairResults& results, Isa isa = defaultIsa()) noexcept;

/// The same for one triangle against block[begin, end): pair j is (one, block[begin + j]), for
/// j < min(end, block.size()) − begin, at most results.capacity() (none when begin ≥ end).
/// The same contract and threading.
BatchStatistics penaltyDistances(const Triangle& one, const TriangleSoA& block, std::size_t begin,
                                 std::size_t end, PairResults& results,
                                 Isa isa = defaultIsa()) noexcept;

}  // namespace delta::kernels
