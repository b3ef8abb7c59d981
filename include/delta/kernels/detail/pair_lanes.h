#pragma once

// W triangle pairs in registers, in the local frame of the first triangle's first vertex, and the
// loops that feed them from TriangleSoA streams and write PairResults streams.

#include <cstddef>
#include <cstdint>

#include "delta/kernels/detail/batch_views.h"
#include "delta/kernels/detail/lanes.h"

namespace delta::detail {

/// What one kernel call computes for W pairs, stored by `storeLanes`.
template <int W>
struct PairOutputLanes {
  Real<W> distanceSquared;
  Vec3Lanes<W> p, q;
  Real<W> errorBound;
  Real<W> newtonStep;
  Mask<W> intersect;
  Mask<W> converged;
};

/// A pair of triangles A = (A0, A1, A2), B = (B0, B1, B2) per lane, relative to A0 (the local
/// frame keeps the digits that large offsets would eat).
template <int W>
struct PairLanes {
  Vec3Lanes<W> origin;  ///< A0, in world coordinates
  Vec3Lanes<W> e1, e2;  ///< A1 − A0, A2 − A0
  Vec3Lanes<W> r;       ///< B0 − A0
  Vec3Lanes<W> f1, f2;  ///< B1 − B0, B2 − B0
};

template <int W>
struct TriangleLanes {
  Vec3Lanes<W> v[3];
};

template <int W>
inline TriangleLanes<W> loadTriangles(const SoaView& soa, std::size_t index) noexcept {
  TriangleLanes<W> t;
  for (int vertex = 0; vertex < 3; ++vertex) {
    t.v[vertex].x = load<W>(soa.streams[3 * vertex + 0] + index);
    t.v[vertex].y = load<W>(soa.streams[3 * vertex + 1] + index);
    t.v[vertex].z = load<W>(soa.streams[3 * vertex + 2] + index);
  }
  return t;
}

/// Lanes [index, index + count) of the streams, count < W, the other lanes copies of lane
/// `index` (so that they compute something finite); for the last, partial register of a range.
template <int W>
inline TriangleLanes<W> loadTrianglesPartial(const SoaView& soa, std::size_t index,
                                             std::size_t count) noexcept {
  TriangleLanes<W> t;
  for (int vertex = 0; vertex < 3; ++vertex) {
    Real<W>* axes[3] = {&t.v[vertex].x, &t.v[vertex].y, &t.v[vertex].z};
    for (int axis = 0; axis < 3; ++axis) {
      const double* stream = soa.streams[3 * vertex + axis] + index;
      for (int lane = 0; lane < W; ++lane)
        axes[axis]->setLane(lane, stream[static_cast<std::size_t>(lane) < count ? lane : 0]);
    }
  }
  return t;
}

template <int W>
inline TriangleLanes<W> splatTriangle(const TriangleCoordinates& one) noexcept {
  TriangleLanes<W> t;
  for (int vertex = 0; vertex < 3; ++vertex)
    t.v[vertex] = {splat<W>(one.values[3 * vertex]), splat<W>(one.values[3 * vertex + 1]),
                   splat<W>(one.values[3 * vertex + 2])};
  return t;
}

template <int W>
inline PairLanes<W> makePairLanes(const TriangleLanes<W>& a, const TriangleLanes<W>& b) noexcept {
  PairLanes<W> pair;
  pair.origin = a.v[0];
  pair.e1 = a.v[1] - a.v[0];
  pair.e2 = a.v[2] - a.v[0];
  pair.r = b.v[0] - a.v[0];
  pair.f1 = b.v[1] - b.v[0];
  pair.f2 = b.v[2] - b.v[0];
  return pair;
}

/// Writes lanes [0, count) of `lanes` to pairs [index, index + count) of `out`.
template <int W>
inline void storeLanes(const PairStreams& out, std::size_t index, std::size_t count,
                       const PairOutputLanes<W>& lanes) noexcept {
  const Vec3Lanes<W>* points[2] = {&lanes.p, &lanes.q};
  double* const* targets[2] = {out.p, out.q};
  if (count == static_cast<std::size_t>(W)) {
    store<W>(out.distanceSquared + index, lanes.distanceSquared);
    for (int k = 0; k < 2; ++k) {
      store<W>(targets[k][0] + index, points[k]->x);
      store<W>(targets[k][1] + index, points[k]->y);
      store<W>(targets[k][2] + index, points[k]->z);
    }
    store<W>(out.errorBound + index, lanes.errorBound);
    store<W>(out.newtonStep + index, lanes.newtonStep);
  } else {
    for (std::size_t lane = 0; lane < count; ++lane) {
      const int i = static_cast<int>(lane);
      out.distanceSquared[index + lane] = lanes.distanceSquared.lane(i);
      for (int k = 0; k < 2; ++k) {
        targets[k][0][index + lane] = points[k]->x.lane(i);
        targets[k][1][index + lane] = points[k]->y.lane(i);
        targets[k][2][index + lane] = points[k]->z.lane(i);
      }
      out.errorBound[index + lane] = lanes.errorBound.lane(i);
      out.newtonStep[index + lane] = lanes.newtonStep.lane(i);
    }
  }
  if (count == static_cast<std::size_t>(W)) {
    lanes.intersect.storeBytes(out.intersect + index);
    lanes.converged.storeBytes(out.converged + index);
  } else {
    for (std::size_t lane = 0; lane < count; ++lane) {
      out.intersect[index + lane] = lanes.intersect.lane(static_cast<int>(lane));
      out.converged[index + lane] = lanes.converged.lane(static_cast<int>(lane));
    }
  }
}

/// Lanes [index, index + count) of the streams (count ≤ W): straight loads where the padded
/// streams hold W doubles from `index`, else lane by lane.
template <int W>
inline TriangleLanes<W> loadTrianglesAt(const SoaView& soa, std::size_t index,
                                        std::size_t count) noexcept {
  return index + W <= soa.paddedSize ? loadTriangles<W>(soa, index)
                                     : loadTrianglesPartial<W>(soa, index, count);
}

/// Runs `kernel` (PairLanes<W> → PairOutputLanes<W>) on pairs (first[i], second[i]),
/// i ∈ [0, count), W at a time; only lanes below `count` are stored.
template <int W, class Kernel>
inline void forEachPairOfBlocks(const SoaView& first, const SoaView& second, std::size_t count,
                                const PairStreams& out, const Kernel& kernel) noexcept {
  for (std::size_t i = 0; i < count; i += W) {
    const std::size_t lanes = count - i < static_cast<std::size_t>(W) ? count - i : W;
    const PairLanes<W> pair =
        makePairLanes<W>(loadTrianglesAt<W>(first, i, lanes), loadTrianglesAt<W>(second, i, lanes));
    storeLanes<W>(out, i, lanes, kernel(pair));
  }
}

/// Runs `kernel` on pairs (one, block[begin + j]), j ∈ [0, count), writing pair j of `out`.
template <int W, class Kernel>
inline void forEachPairOfOne(const TriangleCoordinates& one, const SoaView& block,
                             std::size_t begin, std::size_t count, const PairStreams& out,
                             const Kernel& kernel) noexcept {
  const TriangleLanes<W> a = splatTriangle<W>(one);
  for (std::size_t j = 0; j < count; j += W) {
    const std::size_t lanes = count - j < static_cast<std::size_t>(W) ? count - j : W;
    const std::size_t index = begin + j;
    storeLanes<W>(out, j, lanes,
                  kernel(makePairLanes<W>(a, loadTrianglesAt<W>(block, index, lanes))));
  }
}

}  // namespace delta::detail
