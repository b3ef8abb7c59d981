#pragma once

// Plain views that cross from the dispatching code into the per-ISA batch kernels: raw pointers
// and sizes only, so the kernels compiled for one instruction set share no inline code with the
// rest of the library.

#include <cstddef>
#include <cstdint>

namespace delta::detail {

/// The nine streams of a TriangleSoA (vertex slot v, axis a at index 3v + a), as plain pointers.
struct SoaView {
  const double* streams[9];
  std::size_t paddedSize;  ///< readable doubles in every stream
};

/// Triangles in single precision, less an origin, eight at a time: the eight triangles [8i, 8i +
/// 8) are the 72 floats at leaves + 72i, slot j (3·vertex + axis, as SoaView's streams) at +8j,
/// so a tree leaf is one contiguous block. Every vertex lies within `rounding` (Euclidean) of the
/// double vertex less the origin that it stands for. The point queries' leaf bounds read them
/// (point_lanes.h).
struct FloatLeavesView {
  const float* leaves;
  double rounding;  ///< δ; +∞ where a coordinate is beyond single precision
  double offset;    ///< the origin's largest absolute coordinate
};

/// One triangle's nine coordinates (a.x, a.y, a.z, b.x, …, c.z), broadcast to every lane.
struct TriangleCoordinates {
  double values[9];
};

/// Where a batched kernel writes: the streams of a PairResults, from its first pair on.
struct PairStreams {
  double* distanceSquared;
  double* p[3];
  double* q[3];
  double* errorBound;
  double* newtonStep;
  std::uint8_t* intersect;
  std::uint8_t* converged;
};

/// The batched kernels of one instruction set (one table per ISA, in src/kernels/isa/).
struct BatchKernels {
  int lanes;
  /// Pairs (first[i], second[i]), i < count; writes pairs [0, count) of `out`.
  void (*penaltyBlocks)(const SoaView& first, const SoaView& second, std::size_t count,
                        const PairStreams& out) noexcept;
  /// Pairs (one, block[begin + j]), j < count; writes pairs [0, count) of `out`.
  void (*penaltyOne)(const TriangleCoordinates& one, const SoaView& block, std::size_t begin,
                     std::size_t count, const PairStreams& out) noexcept;
  /// The hybrid's first stage: `converged` is 0 where the pair needs the second.
  void (*hybridBlocks)(const SoaView& first, const SoaView& second, std::size_t count,
                       const PairStreams& out) noexcept;
  void (*hybridOne)(const TriangleCoordinates& one, const SoaView& block, std::size_t begin,
                    std::size_t count, const PairStreams& out) noexcept;
  /// The hybrid's second stage (all 15 candidates), on pairs gathered from the first's
  /// failures: `converged` is 0 where the scalar brute force must recompute the pair.
  void (*exhaustiveBlocks)(const SoaView& first, const SoaView& second, std::size_t count,
                           const PairStreams& out) noexcept;
  /// Lower and upper bounds of the squared distances from `point` (less the block's origin) to
  /// the eight triangles [first, first + 8) of `block` (point_lanes.h), for the point queries'
  /// leaves; false, and nothing written, where their boxes alone put all eight beyond `prune`.
  bool (*pointTriangleBounds)(const FloatLeavesView& block, std::size_t first,
                              const double (&point)[3], double prune, double (&lower)[8],
                              double (&upper)[8]) noexcept;
};

}  // namespace delta::detail
