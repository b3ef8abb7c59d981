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
/// Properties (Revisited)": exact for the polyhedron, summed over the triangles with the origin
/// shifted to the bounding-box centre for accuracy far from the origin). The inertia tensor is
/// ∫ρ(|r|²I − r rᵀ) about the centroid: moments on the diagonal, products of inertia negated off
/// it; it turns as R I Rᵀ when the mesh is rotated by R.
///
/// Throws delta::Error when the mesh is not closed or not consistently oriented
/// (analyzeTopology), when it is inside-out (negative volume) or has zero volume (|V| ≤ 1e-12·d³,
/// d the bounding-box diagonal), or when `density` is not finite and positive. Degenerate
/// (zero-area) triangles contribute nothing. A mesh whose parts overlap (two closed shells that
/// interpenetrate, or a self-intersecting surface) is not checked: the volume they share is
/// counted twice.
MassProperties massProperties(const Mesh& mesh, double density = 1.0);

/// The signed volume enclosed (positive for an outward-oriented closed mesh, negative for an
/// inside-out one, about 0 for a flat one). Meaningful only for closed meshes; does not check
/// (an open mesh gives a value that depends on where the origin is).
///
/// Threading (both functions): read the mesh only; safe to call concurrently.
double signedVolume(const Mesh& mesh) noexcept;

}  // namespace delta
