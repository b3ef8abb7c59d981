#pragma once

#include "delta/core/mat3.h"
#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

namespace delta {

/// Mass properties of the solid a closed, outward-oriented mesh bounds, with density ρ.
///
/// Threading: a value type; no shared state.
struct MassProperties {
  double volume = 0.0;
  double mass = 0.0;  ///< ρ · volume
  Vec3 centroid;      ///< centre of mass
  Mat3 inertia;       ///< inertia tensor about the centroid, in the mesh's axes
};

/// Volume, centroid and inertia tensor by the divergence theorem (Eberly, "Polyhedral Mass
/// Properties (Revisited)": exact for the polyhedron, summed over each part's triangles (the
/// triangles joined through shared corners) with the origin shifted to the centre of the part's
/// box, for accuracy far from the origin and for parts far apart, then carried to one origin).
/// The inertia tensor is
/// ∫ρ(|r|²I − r rᵀ) about the centroid: moments on the diagonal, products of inertia negated off
/// it; it turns as R I Rᵀ when the mesh is rotated by R.
///
/// Any finite mesh, scaled as signedVolume while it is summed; throws delta::Error when the
/// volume, the mass or a nonzero entry of the inertia tensor is beyond a double or below its
/// smallest normal number (the inertia, of degree 5, leaves the range from meshes of size 1e61
/// or 1e-61 on).
///
/// Throws delta::Error when the mesh is not closed or not consistently oriented
/// (analyzeTopology), when it is inside-out (negative volume) or has zero volume (|V| ≤ 1e-12·Σd³,
/// d each part's box diagonal), or when `density` is not finite and positive. Degenerate
/// (zero-area) triangles contribute nothing. A mesh whose parts overlap (two closed shells that
/// interpenetrate, or a self-intersecting surface) is not checked: the volume they share is
/// counted twice.
MassProperties massProperties(const Mesh& mesh, double density = 1.0);

/// The signed volume enclosed (positive for an outward-oriented closed mesh, negative for an
/// inside-out one, about 0 for a flat one). Meaningful only for closed meshes; does not check
/// (an open mesh gives a value that depends on where the origin is).
///
/// Any finite mesh: summed part by part (the triangles joined through shared corners), with the
/// coordinates relative to the centre of the part's box, scaled by a power of two to about 1
/// (exact), so that no product under- or overflows and parts far apart keep their accuracy
/// (about one point, two boxes 1×2×3 10¹² apart gave −67,108,860 for 12), then scaled back.
/// Vertices no triangle uses are left out of the scale. Throws
/// delta::Error when the volume itself is beyond a double (a mesh of size 1e103 or more) or below
/// its smallest normal number (a nonzero volume of a mesh of size 1e-103 or less).
///
/// Threading (both functions): read the mesh only; safe to call concurrently.
double signedVolume(const Mesh& mesh);

}  // namespace delta
