#include "delta/dem/particle_shape.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/primitives.h"
#include "delta/mesh/topology.h"
#include "delta/query/part_nesting.h"
#include "delta/query/self_intersections.h"

namespace delta::detail {
/// A particle's mesh, checked and moved to its centre of mass, and its mass properties.
struct PreparedShape {
  Mesh body;
  MassProperties properties;  ///< inertia about the centroid; centroid in the given coordinates
  double density;
  double sphereRadius = 0.0;  ///< > 0: a sphere shape of this radius; `body` is for display
};
}  // namespace delta::detail

namespace delta::dem {

namespace {

void requireDensity(double density) {
  if (!std::isfinite(density) || !(density > 0.0))
    throw Error("particle shape: density = " + toString(density) + " must be finite and positive");
}

detail::PreparedShape prepare(const Mesh& mesh, double density) {
  requireDensity(density);
  const Topology topology = analyzeTopology(mesh);
  if (!topology.closed || !topology.consistentlyOriented)
    throw Error("particle shape: the mesh must be closed and consistently oriented (" +
                describeDefects(topology) + ")");
  const MassProperties properties = massProperties(mesh, density);
  Mesh body = mesh;
  body.translate(-properties.centroid);
  return {std::move(body), properties, density};
}

/// Throws unless the closed `mesh` bounds a solid: where it crosses itself, or a part is oriented
/// against the others, its mass properties would count a region twice or take it away.
void requireSolid(const QueryMesh& mesh) {
  const SelfIntersections& crossings = selfIntersections(mesh);
  if (crossings.any())
    throw Error("particle shape: the mesh crosses itself (" + std::to_string(crossings.count) +
                " pairs of triangles intersect, such as " +
                std::to_string(crossings.pairs.front().first) + " and " +
                std::to_string(crossings.pairs.front().second) +
                "): it bounds no solid, and its mass would count the overlap twice");
  const PartNesting& nesting = partNesting(mesh);
  if (!nesting.nested())
    throw Error("particle shape: the mesh bounds no solid: " + describePartNesting(nesting));
}

double largestVertexDistance(const Mesh& mesh) noexcept {
  double largest = 0.0;
  for (const Vec3& vertex : mesh.vertices())
    largest = std::max(largest, lengthSquared(vertex));
  return std::sqrt(largest);
}

}  // namespace

Mat3 inverse(const Mat3& m) noexcept {
  // The determinant is of degree 3 in the entries: for a matrix whose entries lie far from 1 (the
  // inertia of a particle of radius 1e-22 is about 1e-107, its determinant 1e-321, subnormal) it
  // would under- or overflow. Such a matrix is inverted scaled by a power of two (exact), the
  // inverse scaled back; elsewhere nothing is scaled.
  double largest = 0.0;
  for (const double entry : m.entries)
    largest = std::max(largest, std::abs(entry));
  const int exponent =
      largest > 0.0 && std::isfinite(largest) && !(largest > 0x1p-250 && largest < 0x1p250)
          ? std::ilogb(largest)
          : 0;
  Mat3 scaled = m;
  for (double& entry : scaled.entries)
    entry = std::ldexp(entry, -exponent);
  const Vec3 r0 = scaled.row(0), r1 = scaled.row(1), r2 = scaled.row(2);
  // The columns of the inverse are the cross products of the rows over the determinant.
  const Vec3 c0 = cross(r1, r2), c1 = cross(r2, r0), c2 = cross(r0, r1);
  const double scale = 1.0 / dot(r0, c0);
  Mat3 result = Mat3::fromRows(c0, c1, c2).transposed() * scale;
  for (double& entry : result.entries)
    entry = std::ldexp(entry, -exponent);
  return result;
}

ParticleShape::ParticleShape(const Mesh& mesh, double density)
    : ParticleShape(prepare(mesh, density)) {}

ParticleShape ParticleShape::sphere(double radius, double density, int displaySubdivisions) {
  if (!std::isfinite(radius) || !(radius > 0.0))
    throw Error("particle shape: sphere radius = " + toString(radius) +
                " must be finite and positive");
  requireDensity(density);
  if (displaySubdivisions < 0 || displaySubdivisions > 6)
    throw Error("particle shape: sphere displaySubdivisions = " +
                std::to_string(displaySubdivisions) + " must lie in [0, 6]");
  MassProperties properties;
  properties.volume = 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
  properties.mass = density * properties.volume;
  properties.inertia = Mat3::identity() * (0.4 * properties.mass * radius * radius);
  return ParticleShape(detail::PreparedShape{primitives::icosphere(displaySubdivisions, radius),
                                             properties, density, radius});
}

ParticleShape::ParticleShape(const detail::PreparedShape& prepared)
    : mesh_(prepared.body),
      queryMesh_(mesh_),
      density_(prepared.density),
      volume_(prepared.properties.volume),
      mass_(prepared.properties.mass),
      inertia_(prepared.properties.inertia),
      inverseInertia_(inverse(prepared.properties.inertia)),
      isotropic_(isMultipleOfIdentity(inverseInertia_)),
      boundingRadius_(prepared.sphereRadius > 0.0 ? prepared.sphereRadius
                                                  : largestVertexDistance(mesh_)),
      centroid_(prepared.properties.centroid),
      kind_(prepared.sphereRadius > 0.0 ? ParticleKind::Sphere : ParticleKind::Mesh) {
  if (kind_ == ParticleKind::Mesh) requireSolid(queryMesh_);
}

}  // namespace delta::dem

namespace delta {

namespace {

/// Whether `stored` is `derived` up to the rounding of deriving it again (2⁻³⁰ of the larger).
bool agrees(double stored, double derived) noexcept {
  return std::abs(stored - derived) <= 0x1p-30 * std::max(std::abs(stored), std::abs(derived));
}

/// Throws unless `properties` are what `body` (a sphere of `sphereRadius` > 0, or the mesh at
/// its centre of mass) and `density` give, up to rounding: a shape whose stored numbers do not
/// match its mesh would move as some other body.
void requireMatchingProperties(const Mesh& body, double density, const MassProperties& properties,
                               double sphereRadius) {
  MassProperties derived;
  if (sphereRadius > 0.0) {
    const dem::ParticleShape sphere = dem::ParticleShape::sphere(sphereRadius, density, 0);
    derived.volume = sphere.volume();
    derived.mass = sphere.mass();
    derived.inertia = sphere.inertia();
  } else {
    const Topology topology = analyzeTopology(body);
    if (!topology.closed || !topology.consistentlyOriented)
      throw Error("particle shape: the mesh must be closed and consistently oriented (" +
                  describeDefects(topology) + ")");
    derived = massProperties(body, density);
    // The body is at its centre of mass: its centroid is 0 up to rounding of its size.
    const double size = std::max(maxAbs(body.bounds().lower), maxAbs(body.bounds().upper));
    if (!(maxAbs(derived.centroid) <= 0x1p-30 * size))
      throw Error("particle shape: the mesh's centre of mass " + toString(derived.centroid) +
                  " is not at its origin");
  }
  bool matches = agrees(properties.volume, derived.volume) && agrees(properties.mass, derived.mass);
  double largest = 0.0;
  for (const double entry : derived.inertia.entries)
    largest = std::max(largest, std::abs(entry));
  for (std::size_t k = 0; k < 9; ++k)
    matches = matches && std::abs(properties.inertia.entries[k] - derived.inertia.entries[k]) <=
                             0x1p-30 * largest;
  if (!matches)
    throw Error("particle shape: the stored volume " + toString(properties.volume) + ", mass " +
                toString(properties.mass) +
                " and inertia do not match the mesh and density (volume " +
                toString(derived.volume) + ", mass " + toString(derived.mass) + ")");
}

}  // namespace

dem::ParticleShape detail::restoredShape(const Mesh& body, double density,
                                         const MassProperties& properties, double sphereRadius) {
  dem::requireDensity(density);
  for (const double value : {properties.volume, properties.mass})
    if (!std::isfinite(value) || !(value > 0.0))
      throw Error("particle shape: volume and mass must be finite and positive (not " +
                  toString(value) + ")");
  if (!std::isfinite(sphereRadius) || sphereRadius < 0.0)
    throw Error("particle shape: sphere radius = " + toString(sphereRadius) +
                " must be finite and non-negative");
  if (!isFinite(properties.centroid))
    throw Error("particle shape: centroid " + toString(properties.centroid) + " is not finite");
  requireMatchingProperties(body, density, properties, sphereRadius);
  return dem::ParticleShape(PreparedShape{body, properties, density, sphereRadius});
}

}  // namespace delta
