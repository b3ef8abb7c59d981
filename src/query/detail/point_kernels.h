#pragma once

// The point queries' per-ISA table: the nearest-triangle descent with its node bounds and exact
// lanes, built once per instruction set (query/isa/point_table.cpp, src/CMakeLists.txt's
// delta_isa) and picked at run time as the batch kernels are.

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "delta/kernels/isa.h"

#include "query_mesh_data.h"

namespace delta::detail {

/// Leaves packed eight to an octet as a level-1 node of the tree holds its children's boxes and
/// cylinders (PointKernels::among's view of LeafCandidates): `octets` of each, and kFanout leaf
/// indices an octet (kNoLeaf in the padding, whose boxes are empty).
struct CandidateView {
  static constexpr std::uint32_t kNoLeaf = std::numeric_limits<std::uint32_t>::max();
  const BoxOctet* boxes = nullptr;
  const CylinderOctet* cylinders = nullptr;
  const std::uint32_t* leaves = nullptr;
  std::size_t octets = 0;
};

/// Most leaves a cluster gathers (PointKernels::collect); a cluster near more is searched from
/// the root.
inline constexpr std::size_t kMostCandidates = 256;

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
  /// children into `out`, and the mask of those not above `prune`. `point` is less the octets'
  /// origin (FloatTriangles::origin), as their boxes are.
  unsigned (*children)(const BoxOctet& boxes, const Vec3& point, double prune,
                       double (&out)[kFanout]) noexcept;
  /// The same for eight leaves, raised by their cylinders (shrunk by `shrink`).
  unsigned (*leaves)(const BoxOctet& boxes, const CylinderOctet& cylinders, const Vec3& point,
                     double shrink, double prune, double (&out)[kFanout]) noexcept;
  /// The distance-bound grid's sieve of `count` points (grid_sieve.h's sievePoints): the
  /// offsets of those not beyond `limit` into `kept`, and their number.
  std::size_t (*sieve)(const GridView& grid, const Vec3* points, std::size_t count, double limit,
                       std::uint32_t* kept, bool& inRange) noexcept;
  /// Into leaves[0, count), ascending, every leaf whose bound (its box's distance raised by its
  /// cylinder's, as the descent's) from `center` is not above `radiusSquared`; returns the
  /// count, or kMostCandidates + 1 where there are more (leaves then holds some of them) or the
  /// tree is one leaf (then there is no level-1 node to gather it from). For
  /// points within r of the centre these are all the leaves that hold a triangle within ε of
  /// one of them, where radiusSquared ≥ (ε + r)² (the bounds are lower bounds of the distances).
  std::size_t (*collect)(const QueryMeshData& mesh, const Vec3& center, double radiusSquared,
                         std::uint32_t* leaves) noexcept;
  /// nearest's answer, searching only the leaves of `candidates`, which must hold every
  /// triangle closer than √limitSquared to `point` (a finite limit).
  Nearest (*among)(const QueryMeshData& mesh, const Vec3& point, double limitSquared,
                   const CandidateView& candidates) noexcept;
};

/// The table of `isa`, lowered to a supported one (kernels::supportedIsaAtMost).
const PointKernels& pointKernels(kernels::Isa isa) noexcept;

/// The leaves near a cluster of points (a few within a cell of the bound grid), gathered once
/// and searched for each point of the cluster (nearestAmong) instead of the tree from its root:
/// an ε-limited batch's points left in doubt by the grid (point_distance.cpp). A thread keeps one
/// and refills it cluster after cluster.
class LeafCandidates {
 public:
  /// Gathers the leaves whose bound from `center` is not above `radiusSquared`
  /// (PointKernels::collect), with the tables of kernels::defaultIsa() or `isa`; false, holding
  /// none, where there are more than kMostCandidates or the tree is one leaf.
  bool collect(const QueryMeshData& mesh, const Vec3& center, double radiusSquared);
  bool collect(const QueryMeshData& mesh, const Vec3& center, double radiusSquared,
               kernels::Isa isa);
  std::size_t size() const noexcept { return count_; }
  CandidateView view() const noexcept {
    return {boxes_.data(), cylinders_.data(), leaves_.data(), boxes_.size()};
  }

 private:
  bool pack(const QueryMeshData& mesh, std::size_t found);

  std::vector<BoxOctet> boxes_;
  std::vector<CylinderOctet> cylinders_;
  std::vector<std::uint32_t> leaves_;
  std::array<std::uint32_t, kMostCandidates + 1> found_{};
  std::size_t count_ = 0;
};

/// nearestTriangle's answer for `point`, searching only `candidates`, which must hold every leaf
/// with a triangle closer than √limitSquared to it (a finite limit), with the tables of
/// kernels::defaultIsa() or `isa`.
Nearest nearestAmong(const QueryMeshData& mesh, const Vec3& point, double limitSquared,
                     const LeafCandidates& candidates) noexcept;
Nearest nearestAmong(const QueryMeshData& mesh, const Vec3& point, double limitSquared,
                     const LeafCandidates& candidates, kernels::Isa isa) noexcept;

}  // namespace delta::detail
