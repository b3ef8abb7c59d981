#pragma once

#include <cstddef>

#include "delta/core/triangle.h"
#include "delta/kernels/isa.h"
#include "delta/kernels/pair_results.h"
#include "delta/mesh/triangle_soa.h"

namespace delta::kernels {

/// Fixed Newton iterations of the hybrid's first stage (it only has to name features; see
/// docs/triangle_solvers.md for the measured trade-off against 4).
inline constexpr int kHybridIterations = 3;

/// Triangle–triangle distances, exact and batched: the seed's hybrid (section 3.1). A penalty
/// Newton (the method of penaltyDistances, 3 steps: ρ 10² → 10⁸, α 10⁻² → 10⁻⁸) runs on every
/// pair, one SIMD lane each; its end point names the features the minimum lies on, whose
/// closest points are then solved in closed form and certified. Three stages, each for the pairs
/// the one before could not certify:
///
/// 1. SIMD, every pair: three candidates from the Newton point's barycentric weights (the vertex
///    of B with the largest weight against triangle A, the vertex of A likewise against B, and
///    the edges of A and B opposite their smallest weights, edge against edge with clamping);
///    the nearest is certified by the optimality (KKT) conditions of this convex problem: with
///    d = P − Q, the slacks d·(A_i − P) and d·(Q − B_j) over the vertices of A and B must total
///    at least −2·10⁻¹³·L·|d| (L the pair's longest edge), which bounds |P − Q| − (true distance)
///    by 2·10⁻¹³·L; and |d| must exceed 10⁻⁹·L (nearer pairs are a rounding question the brute
///    force decides). An intersection is certified by an edge of one triangle that crosses the
///    other's plane (both ends at least 10⁻⁹·L from it) at a point inside the other face by a
///    barycentric margin of 10⁻⁹, that face being no sliver (height ≥ about 10⁻³·L).
/// 2. SIMD, on the few pairs gathered from stage 1's failures (about 2% of near contacts): all
///    15 candidates (6 vertex–face, 9 edge–edge) and the same certificates.
/// 3. Scalar, triangleDistanceBruteForce: what neither certifies (touching, coplanar and
///    degenerate pairs).
///
/// Contract: the same answer as triangleDistanceBruteForce on every pair: the distance to
/// 10⁻¹² of the pair's size, the same `intersect` flag (intersect ⇔ distance 0, consistent with
/// trianglesIntersect: a pair is certified intersecting only with a margin, and a touching or
/// nearly touching pair goes to the brute force), and the same closest points where they are
/// unique. For an intersecting pair p = q, a point of both triangles (stages 1–2: where an edge
/// pierces the other triangle; stage 3: the brute force's point). errorBound is 0 and converged
/// is true for every pair; newtonStep is the Newton's last step (+∞ where it diverged).
/// A pair's answer is the same bits whatever batch it is in, and on AVX2 as on AVX-512 (SSE2
/// as the scalar build, which round a·b + c twice where those fuse it): a lone pair the first
/// stage left goes to the narrowest table of the same arithmetic.
///
/// Pairs: as penaltyDistances. Returns the count of pairs, of pairs left to stage 2
/// (`rechecked`) and of pairs recomputed by the brute force (`fallbacks`); padding lanes are
/// never counted, stored, nor recomputed. No heap allocation: stage 2 gathers its pairs in a
/// 14 KB block on the stack.
///
/// Threading: no shared state; concurrent calls are safe with distinct `results`.
BatchStatistics hybridDistances(const TriangleSoA& first, const TriangleSoA& second,
                                PairResults& results, Isa isa = defaultIsa()) noexcept;

/// The same for one triangle against block[begin, end): pair j is (one, block[begin + j]), for
/// j < min(end, block.size()) − begin, at most results.capacity() (none when begin ≥ end).
/// The same contract and threading.
BatchStatistics hybridDistances(const Triangle& one, const TriangleSoA& block, std::size_t begin,
                                std::size_t end, PairResults& results,
                                Isa isa = defaultIsa()) noexcept;

}  // namespace delta::kernels
