#pragma once

#include <cstdint>

#include "delta/core/mat3.h"
#include "delta/core/vec3.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/mesh.h"
#include "delta/query/query_mesh.h"

namespace delta::dem {
class ParticleShape;
}  // namespace delta::dem

namespace delta::detail {
struct PreparedShape;
/// A shape exactly as it was saved (dem/checkpoint.h): `body` already in the body frame and the
/// mass properties as stored, not derived again (moving a mesh to its centre of mass a second
/// time would change the last bits). `sphereRadius` > 0 makes a sphere shape shown as `body`.
/// Throws delta::Error for a density, volume, mass or radius that is not finite and positive, a
/// centroid that is not finite, and properties that are not `body`'s (derived again: a closed,
/// consistently oriented mesh at its centre of mass, within 2⁻³⁰ of the volume, mass and
/// largest inertia entry) or the sphere's: a checkpoint made by hand must not give a body that
/// moves as another.
dem::ParticleShape restoredShape(const Mesh& body, double density, const MassProperties& properties,
                                 double sphereRadius);
}  // namespace delta::detail

namespace delta::dem {

/// What a particle's contacts are computed against: its triangles, or an exact sphere.
///
/// Threading: a value type.
enum class ParticleKind : std::uint8_t {
  Mesh,    ///< a closed triangle mesh: mesh–mesh contacts (narrow_phase.h, pairContacts)
  Sphere,  ///< a ball: analytic sphere–sphere and sphere–triangle contacts
};

/// The shape of a rigid DEM particle, shared by every particle made from it: a closed triangle
/// mesh in its body frame, prepared once for contact detection, with the mass properties of the
/// solid it bounds at a given density.
///
/// The body frame has its origin at the centre of mass and the axes of the mesh as given (not
/// the principal axes: the full inertia tensor is kept). `centroid()` says where the centre of
/// mass was in the mesh's own coordinates, so a particle placed at `centroid()` with the identity
/// orientation sits exactly where the mesh was.
///
/// Throws delta::Error when the mesh does not bound a solid (a particle needs a mass and an
/// inside): when it is not closed and consistently oriented, crosses itself (selfIntersections:
/// its mass properties would count the overlap twice), has parts that do not nest as a solid's
/// boundary (partNesting: an inside-out part, a shell inside a shell of the same orientation, a
/// shell stored twice, parts touching at a vertex), or is inside-out or flat; and when the density
/// is not finite and positive. Degenerate triangles are accepted (they add no mass and take part in
/// contacts as the segments they are).
///
/// A sphere shape (ParticleShape::sphere) is an exact ball for contacts and mass properties:
/// mass 4/3·π·r³·ρ, inertia 2/5·m·r²·I, bounding radius r. Its mesh() is an icosphere of radius r
/// for output only (ParaView frames, triangle counts); no contact is computed with it.
///
/// Threading: immutable once built; copies share the prepared mesh (QueryMesh), and any number
/// of threads may read one at once.
class ParticleShape {
 public:
  /// Prepares `mesh` (copied, then moved into the body frame) with `density`; throws as above.
  ParticleShape(const Mesh& mesh, double density);

  /// A ball of `radius` about the origin (the centre of mass); `displaySubdivisions` (0 to 6)
  /// sets the icosphere that mesh() shows it as (20·4^s triangles). Throws delta::Error when the
  /// radius or the density is not finite and positive, or the subdivisions are out of range.
  static ParticleShape sphere(double radius, double density, int displaySubdivisions = 2);

  ParticleKind kind() const noexcept { return kind_; }
  bool isSphere() const noexcept { return kind_ == ParticleKind::Sphere; }

  /// The surface in the body frame (centre of mass at the origin); for a sphere, the display
  /// icosphere.
  const Mesh& mesh() const noexcept { return mesh_; }
  /// The surface prepared for queries, in the body frame; copy it and transform the copy by a
  /// particle's pose (O(1)) to compare it where the particle is.
  const QueryMesh& queryMesh() const noexcept { return queryMesh_; }
  double density() const noexcept { return density_; }
  double volume() const noexcept { return volume_; }
  double mass() const noexcept { return mass_; }
  /// The inertia tensor about the centre of mass, body frame.
  const Mat3& inertia() const noexcept { return inertia_; }
  /// Its inverse; the world frame's is R·I⁻¹·Rᵀ for orientation R.
  const Mat3& inverseInertia() const noexcept { return inverseInertia_; }
  /// Whether the inverse inertia is a multiple of the identity (a sphere's, a cube's): then
  /// R·I⁻¹·Rᵀ = I⁻¹ whatever R, and a body turns at L/I. Decided once, when made.
  bool isotropicInertia() const noexcept { return isotropic_; }
  /// The largest distance from the centre of mass to a vertex: the broad phase's sphere. For a
  /// sphere shape, its radius.
  double boundingRadius() const noexcept { return boundingRadius_; }
  /// The centre of mass in the coordinates of the mesh that was given.
  const Vec3& centroid() const noexcept { return centroid_; }

 private:
  friend ParticleShape detail::restoredShape(const Mesh&, double, const MassProperties&, double);
  explicit ParticleShape(const detail::PreparedShape& prepared);

  Mesh mesh_;
  QueryMesh queryMesh_;
  double density_;
  double volume_;
  double mass_;
  Mat3 inertia_;
  Mat3 inverseInertia_;
  bool isotropic_;
  double boundingRadius_;
  Vec3 centroid_;
  ParticleKind kind_;
};

/// The inverse of a 3×3 matrix by cofactors, taken scaled by a power of two where the entries lie
/// beyond 2^±250 (a tiny particle's inertia). The caller guarantees it is invertible (an
/// inertia tensor of a solid is symmetric positive definite); a singular matrix gives infinities
/// or NaN, unchecked.
///
/// Threading: a pure function.
Mat3 inverse(const Mat3& m) noexcept;

}  // namespace delta::dem
