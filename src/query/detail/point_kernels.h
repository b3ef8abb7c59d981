#pragma once

// The point queries' per-ISA table: the nearest-triangle descent with its node bounds and exact
// lanes, built once per instruction set (query/isa/point_table.cpp, src/CMakeLists.txt's
// delta_isa) and picked at run time as the batch kernels are.

#include <cstddef>
#include <cstdint>

#include "delta/kernels/isa.h"

#include "query_mesh_data.h"

namespace delta::detail {

/// One ISA's point kernels. Every answer is the same on every ISA: the bounds only decide what
/// the exact kernel skips, and the exact lanes give the scalar kernel's bits.
struct PointKernels {
  /// The nearest triangle by (squared distance, id) closer than `limitSquared` (query_mesh_data.h,
  /// nearestTriangle), for a limit that is finite or NaN.
  Nearest (*nearest)(const QueryMeshData& mesh, const Vec3& point, double limitSquared) noexcept;
  /// kernels::closestPointOnTriangle(point, mesh.triangle(sorted[i])).distanceSquared into
  /// out[i] for i < count (1 to 8), bit for bit, in lanes; null where the ISA has none.
  void (*exact)(const QueryMeshData& mesh, const Vec3& point, const std::uint32_t* sorted,
                std::size_t count, double* out) noexcept;
  /// The node bounds of the descent (node_bounds.h): the squared distances of a node's eight
  /// children into `out`, and the mask of those not above `prune`.
  unsigned (*children)(const BoxOctet& boxes, const Vec3& point, double prune,
                       double (&out)[kFanout]) noexcept;
  /// The same for eight leaves, raised by their cylinders (shrunk by `shrink`).
  unsigned (*leaves)(const BoxOctet& boxes, const CylinderOctet& cylinders, const Vec3& point,
                     double shrink, double prune, double (&out)[kFanout]) noexcept;
  /// The distance-bound grid's sieve of `count` points (grid_sieve.h's sievePoints): the
  /// offsets of those not beyond `limit` into `kept`, and their number.
  std::size_t (*sieve)(const GridView& grid, const Vec3* points, std::size_t count, double limit,
                       std::uint32_t* kept, bool& inRange) noexcept;
};

/// The table of `isa`, lowered to a supported one (kernels::supportedIsaAtMost).
const PointKernels& pointKernels(kernels::Isa isa) noexcept;

}  // namespace delta::detail
