#pragma once

// The per-ISA table of batched kernels, as a template over the lane count W.
// src/kernels/isa/batch_table.cpp instantiates it once per ISA, for that ISA's W, compiled with
// its flags.

#include <cstddef>

#include "delta/kernels/detail/batch_views.h"
#include "delta/kernels/detail/hybrid_candidates.h"
#include "delta/kernels/detail/pair_lanes.h"
#include "delta/kernels/detail/penalty_newton.h"
#include "delta/kernels/detail/point_lanes.h"

namespace delta::detail {

template <int W>
struct PenaltyKernel {
  PairOutputLanes<W> operator()(const PairLanes<W>& pair) const noexcept {
    return penaltyLanes<W>(pair, PenaltySchedule::kTolerance);
  }
};

template <int W>
struct HybridKernel {
  PairOutputLanes<W> operator()(const PairLanes<W>& pair) const noexcept {
    return hybridLanes<W>(pair);
  }
};

// [[gnu::flatten]]: everything the loop calls is inlined into it (GCC's heuristics would keep the
// small Pack helpers out of line, passing registers through memory).
template <int W>
struct ExhaustiveKernel {
  PairOutputLanes<W> operator()(const PairLanes<W>& pair) const noexcept {
    return exhaustiveLanes<W>(pair);
  }
};

template <int W, template <int> class Kernel>
[[gnu::flatten]] void runBlocks(const SoaView& first, const SoaView& second, std::size_t count,
                                const PairStreams& out) noexcept {
  forEachPairOfBlocks<W>(first, second, count, out, Kernel<W>{});
}

template <int W, template <int> class Kernel>
[[gnu::flatten]] void runOne(const TriangleCoordinates& one, const SoaView& block,
                             std::size_t begin, std::size_t count,
                             const PairStreams& out) noexcept {
  forEachPairOfOne<W>(one, block, begin, count, out, Kernel<W>{});
}

// Out of line also where the point descent's flattened entry calls it (query/isa/point_table.cpp):
// inlined into the descent's loop, W1 took 2% longer.
template <int W>
[[gnu::noinline, gnu::flatten]] bool pointBounds(const FloatLeavesView& block, std::size_t first,
                                                 const double (&point)[3], double prune,
                                                 double (&lower)[8], double (&upper)[8]) noexcept {
  return pointTriangleBounds8<Shape<W>::H>(block, first, point, prune, lower, upper);
}

template <int W>
constexpr BatchKernels makeBatchKernels() noexcept {
  return {W,
          &runBlocks<W, PenaltyKernel>,
          &runOne<W, PenaltyKernel>,
          &runBlocks<W, HybridKernel>,
          &runOne<W, HybridKernel>,
          &runBlocks<W, ExhaustiveKernel>,
          &pointBounds<W>};
}

}  // namespace delta::detail
