#pragma once

#include <cmath>
#include <string>

#include "delta/core/aabb.h"
#include "delta/core/vec3.h"
#include "delta/mesh/triangle_soa.h"

namespace delta {

/// The coordinates Δ's queries answer exactly, and why.
///
/// The kernels multiply coordinate differences: squared distances and cross products (face
/// normals) are of degree 2, the point–triangle and triangle–triangle kernels' edge tests
/// n·(e × r), flatness tests |n|² and segment–segment parameters of degree 4 at most. With every
/// coordinate within ±2²⁰⁰ (kLargestCoordinate, about 1.6e60) a difference is below 2²⁰¹ and a
/// degree-4 product with its constants below 2⁸¹⁵, far from overflow (2¹⁰²⁴). The penalty
/// solver's Newton determinants, of higher degree, are guarded (a lane whose determinant is not
/// finite keeps its point and reports not converged, and the hybrid then falls back to the exact
/// brute force); the single-precision copies of the vertices and boxes that bound a QueryMesh's
/// nodes and leaves reach 3.4e38 only, and beyond it they are rounded outward and bound loosely,
/// never wrongly.
///
/// Beyond the range a squared distance overflows to +∞ from 1.3e154 on and a degree-4 test from
/// 1e77 on, and the tree's bounds can no longer tell a triangle from an empty slot: so every
/// query checks its input against the range once, where it enters (a mesh's box where it is,
/// after its pose or transform; every point, where it is and carried into the mesh's frame;
/// every sphere), and throws delta::Error naming the mesh or the point's index, the offending
/// value and the range. A geometry far from the origin but near its partner can be moved nearer
/// the origin first (a rigid move changes no distance).
///
/// At the small end, a mesh whose largest |coordinate| is below 2⁻²⁰⁰ (kSmallestMeshScale,
/// about 6.2e-61) is refused the same way: there the kernels' degree-4 products underflow below
/// the smallest normal double and a thin triangle would be taken for a flat one (scale such a
/// mesh up by a power of two, which is exact, and the answers down). Above it, rounding
/// dominates underflow: a kernel's distance is exact to a few ulps of the largest coordinate
/// involved, so a point 1e-300 from a mesh of size 1 is within that rounding of its surface; the
/// point queries still give such a point its distance from the closest point, to full relative
/// precision, where the squared distance underflows (below about 1.5e-154).
///
/// The mesh measures (surfaceArea, signedVolume, massProperties) instead rescale by a power of
/// two and answer for any finite mesh, or throw where the answer itself is beyond a double.
inline constexpr double kLargestCoordinate = 0x1p200;
/// The least largest |coordinate| of a mesh the queries accept (see kLargestCoordinate).
inline constexpr double kSmallestMeshScale = 0x1p-200;
/// The least extent a triangle may have in the mesh–mesh queries (contacts, minimumDistance),
/// unless its corners are one point: the same bound, for a triangle near the origin of a larger
/// mesh, whose products of degree 4 underflow as a small mesh's do (a triangle 1e-100 across was
/// taken for flat). The point queries solve such a triangle scaled up instead
/// (kernels::kTinyTriangleSquared).
inline constexpr double kSmallestTriangleExtent = 0x1p-200;

/// Whether every coordinate of `point` lies within ±kLargestCoordinate (false for NaN or ±∞).
inline bool inCoordinateRange(const Vec3& point) noexcept {
  // Each compare is false for NaN (maxAbs would skip a NaN).
  return std::fabs(point.x) <= kLargestCoordinate && std::fabs(point.y) <= kLargestCoordinate &&
         std::fabs(point.z) <= kLargestCoordinate;
}

/// Whether every coordinate of `box` lies within ±kLargestCoordinate (true for an empty box,
/// false where a coordinate is NaN): the check the queries make before building any message.
inline bool boxInCoordinateRange(const Aabb& box) noexcept {
  return box.empty() || (inCoordinateRange(box.lower) && inCoordinateRange(box.upper));
}

/// The largest |coordinate| of `box` (0 for an empty box, NaN where a coordinate is NaN).
double magnitude(const Aabb& box) noexcept;

/// The supported range in words, for error messages: "±2^200 (1.6069380442589903e+60)".
std::string coordinateRangeText();

/// Throws delta::Error unless every coordinate of `box` lies within ±kLargestCoordinate; the
/// message starts with `what` (the query and the geometry, "point distances: the mesh") and
/// gives the box and the range.
void checkCoordinateRange(const Aabb& box, const std::string& what);

/// checkCoordinateRange, and throws as well when the largest |coordinate| of `box` is below
/// kSmallestMeshScale (the mesh is too small for the kernels' products; the message says so).
void checkMeshScale(const Aabb& box, const std::string& what);

/// The box of a flattened mesh's triangles (not its padding); a NaN box where a coordinate is
/// not finite (which every check here refuses).
Aabb boundsOf(const TriangleSoA& mesh) noexcept;

/// checkMeshScale(boundsOf(mesh), what), and checkTriangleExtent for every triangle (the
/// flattened forms serve the mesh–mesh queries only).
void checkMeshScale(const TriangleSoA& mesh, const std::string& what);

/// The largest |difference| of two corners of `triangle` along an axis (0 for one point).
double triangleExtent(const Triangle& triangle) noexcept;

/// Throws delta::Error unless `triangle` (index `index` of the mesh `what` names) is one point or
/// spans at least kSmallestTriangleExtent along an axis (between two of its corners); the
/// message gives its extent and what to do.
void checkTriangleExtent(const Triangle& triangle, std::size_t index, const std::string& what);

/// Throws delta::Error for a point outside the range: "`what` (x, y, z) has a coordinate
/// beyond ±2^200 …" (`what` names the point, "point distances: point 7").
void checkPointRange(const Vec3& point, const std::string& what);

}  // namespace delta
