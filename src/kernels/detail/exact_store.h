#pragma once

// Writes an exact (brute-force) triangle–triangle answer into a batch's result streams. For the
// baseline translation units only (hybrid.cpp, triangle_batch.cpp): a non-template inline
// function must not be compiled into the per-ISA units (src/kernels/isa/).

#include <cstddef>

#include "delta/kernels/detail/batch_views.h"
#include "delta/kernels/triangle_triangle.h"

namespace delta::detail {

/// Pair `i` gets `exact`: its distance, points and intersect flag, error bound 0, converged.
/// The Newton step stream is left to the caller.
inline void storeExact(const PairStreams& out, std::size_t i,
                       const kernels::TriangleDistanceResult& exact) noexcept {
  out.distanceSquared[i] = exact.distanceSquared;
  out.p[0][i] = exact.p.x;
  out.p[1][i] = exact.p.y;
  out.p[2][i] = exact.p.z;
  out.q[0][i] = exact.q.x;
  out.q[1][i] = exact.q.y;
  out.q[2][i] = exact.q.z;
  out.errorBound[i] = 0.0;
  out.intersect[i] = exact.intersect;
  out.converged[i] = 1;
}

}  // namespace delta::detail
