#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "delta/core/sphere.h"

namespace delta::dem {

/// Two sphere indices, first < second.
///
/// Threading: a value type; no shared state.
struct CandidatePair {
  std::uint32_t first = 0;
  std::uint32_t second = 0;

  friend constexpr bool operator==(const CandidatePair&, const CandidatePair&) = default;
};

/// The DEM broad phase: every pair of spheres whose surfaces are closer than `margin`
/// (|cᵢ − cⱼ| < rᵢ + rⱼ + margin, strictly, compared as computed in doubles: the squared
/// distance against the squared reach, each rounded, so a pair within a few ulps of the reach
/// may fall either way; callers that must not miss such a pair allow for it, as the World's
/// skin and its pair test do), sorted by (first, second), the same for any thread count.
///
/// A cell list rebuilt on every call: cells of edge 2·r_max + margin, so each sphere meets only
/// the spheres of its own and the 26 neighbouring cells. Where the spheres' box holds at most
/// about eight cells a sphere (a pile, a flow), the cells are a dense grid and the spheres are
/// sorted by cell, so that each row of three neighbouring cells is one run of them; otherwise
/// cells are hashed into a table of about twice as many buckets as spheres and filled by a
/// counting sort. Either way the work is O(n) for spheres of similar size in any packing and the
/// memory O(n) however far apart they are.
/// Where the cells of the largest sphere would be more than twice those of the smallest and
/// hold more than 128 spheres a sphere's cell on average (cells as large as the largest crowd the
/// small ones: one boulder among 64,000 grains took 4.6 s), each sphere lives on a level of
/// hashed cells that holds its own size (edges doubling from the smallest's) and looks for
/// partners around itself on its own level and every level above: O(n · levels) however the
/// sizes crowd, the same pairs in the same order. Cells are 2⁻¹⁸ larger than the reach they
/// hold, so that the rounding of a centre's cell never parts a pair.
///
/// Throws delta::Error when the margin or a radius is neither 0 nor within [2⁻⁴⁸¹, 2²⁰⁰] (negative,
/// not finite, so small that its square is subnormal, or so large that squares could overflow),
/// a centre lies beyond the coordinate range (±2²⁰⁰, mesh/coordinate_range.h, or is not finite;
/// naming the sphere), or there are 2³² or more spheres.
///
/// Threading: reads its input only; safe to call from any number of threads at once. Runs in
/// parallel over the spheres itself (core/parallel.h).
std::vector<CandidatePair> nearbyPairs(std::span<const Sphere> spheres, double margin);

}  // namespace delta::dem
