#pragma once

#include <cstddef>
#include <vector>

#include "delta/core/vec3.h"

namespace delta::detail {

struct QueryMeshData;

/// A tree node's far-field moments for the generalized winding number (Barill, Dickson, Schmidt,
/// Levin and Jacobson, "Fast Winding Numbers for Soups and Clouds", SIGGRAPH 2018, order 2 of
/// their expansion): seen from a point q far from the node, its triangles' solid angle over 4π is
///   w ≈ [ (û·N)/d² + (tr T − 3 ûᵀTû)/d³ ] / 4π,   u = centre − q, d = |u|, û = u/d,
/// the Taylor expansion of ∫ (x − q)·n / |x − q|³ dA about `centre` to first order in x − centre.
/// Its error is at most 3·area·r² / (4π (d − r)⁴) for d > r = `radius` (the third derivatives of
/// 1/|x| are bounded by 6/|x|⁴: the remainder of a second-order Taylor term), rigorous up to
/// rounding.
struct WindingNode {
  Vec3 centre;          ///< the area-weighted centroid of the node's triangles
  double radius = 0.0;  ///< every vertex of the node lies within it of `centre`
  Vec3 normal;          ///< N: Σ of the triangles' area vectors (area × unit normal)
  double area = 0.0;    ///< Σ of the triangles' areas (0: every triangle degenerate)
  /// T (row-major): Σ (centroid_t − centre) ⊗ area vector_t, the first moment of the normal.
  double tensor[9] = {};
};

/// The moments of every node of a QueryMesh's tree, levels as QueryMeshData::levels (level 0:
/// the leaves of kFanout sorted triangles), and the orientation that signs its winding numbers.
struct WindingTree {
  std::vector<std::vector<WindingNode>> levels;
  /// +1 or −1: a closed mesh's QueryMeshData::orientation (the sign of its volume); for any other
  /// mesh, the sign of its signed volume about the box's centre (+1 where that is 0), so that an
  /// inside-out mesh with a hole still has its inside at w·orientation ≈ 1.
  double orientation = 1.0;

  std::size_t memoryBytes() const noexcept {
    std::size_t bytes = 0;
    for (const std::vector<WindingNode>& level : levels)
      bytes += level.capacity() * sizeof(WindingNode);
    return bytes;
  }
};

/// The moments of `mesh`'s tree, bottom-up (the leaves from their triangles, a parent from its
/// children's moments shifted to its centre), in parallel; deterministic. O(n).
WindingTree buildWindingTree(const QueryMeshData& mesh);

/// The hierarchical winding number at `point` (the mesh's prepared frame): nodes whose centre is
/// further than β·radius (β > 1) from the point by their moments, the others opened, leaves
/// that are not far by the exact solid angle of each triangle (delta::solidAngle). `errorBound`
/// receives the sum of the far nodes' error bounds: |result − exact| ≤ errorBound up to rounding.
/// Not multiplied by the orientation.
double hierarchicalWindingNumber(const QueryMeshData& mesh, const WindingTree& tree,
                                 const Vec3& point, double beta, double& errorBound) noexcept;

/// The winding number over every triangle (delta::windingNumber on the sorted triangles): O(n).
double exactWindingNumber(const QueryMeshData& mesh, const Vec3& point) noexcept;

/// A point's winding-number sign.
struct WindingSign {
  double winding = 0.0;    ///< times the orientation: ≈ 1 inside, ≈ 0 outside
  bool inside = false;     ///< winding > ½
  bool ambiguous = false;  ///< |winding − ½| ≤ tolerance
};

/// The sign of the winding number at `point` (prepared frame; not on the surface), exactly as
/// exactWindingNumber would give it: the hierarchy with β = 4, where its error bound leaves
/// in doubt whether |w − ½| ≤ tolerance, or on which side of ½ w lies, again with β = 10, and
/// where still in doubt the exact sum.
/// (Measured on camel and armadillo: β = 3 leaves the bound above ½ at 40% of points in the
/// box, β = 4 at none, for 1.5 times the cost; Barill's β = 2 is accurate in practice but its
/// rigorous bound decides almost nothing.) The
/// winding number returned is the exact one where the exact sum ran, else the approximation.
WindingSign windingSign(const QueryMeshData& mesh, const Vec3& point, double tolerance) noexcept;

}  // namespace delta::detail
