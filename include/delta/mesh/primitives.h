#pragma once

#include <cstdint>

#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

/// Built-in meshes. Every one except `quad` is closed and outward-oriented, with vertices joined.
/// Invalid parameters (non-positive sizes, too few or too many segments, non-finite values)
/// throw delta::Error naming the parameter and its value; a size beyond its limit, or one whose
/// mesh would not fit in memory (core/memory.h), is refused before anything is allocated, with
/// the limit and the memory it would need.
///
/// Threading: no shared state (each granulate runs qhull with its own context); every function
/// may be called from any number of threads at once.
namespace delta::primitives {

/// The finest icosphere: 20·4⁸ = 1,310,720 triangles.
inline constexpr int kMaxIcosphereSubdivisions = 8;

/// The most segments of a cylinder: its 4·segments triangles keep 32-bit ids (ContactPoint,
/// query results), and its 2·segments + 2 vertices 32-bit indices.
inline constexpr int kMaxCylinderSegments = 1'073'741'823;  // (2³² − 1) / 4

/// A cylinder's memory a segment: two vertices and four triangles.
inline constexpr double kCylinderBytesPerSegment =
    2.0 * sizeof(Vec3) + 4.0 * sizeof(TriangleIndices);

/// A sphere: the icosahedron (20 triangles) subdivided `subdivisions` times (0–8; 20·4ⁿ
/// triangles), vertices projected onto the sphere (so inscribed in it). `radius` > 0.
Mesh icosphere(int subdivisions = 2, double radius = 1.0, const Vec3& center = {});

/// An axis-aligned box with the given edge lengths (each > 0): 12 triangles.
Mesh box(const Vec3& size = {1.0, 1.0, 1.0}, const Vec3& center = {});

/// A cylinder along z, centred on `center`, with `segments` (3 to kMaxCylinderSegments, and
/// within the memory limit at kCylinderBytesPerSegment) around: 4·segments triangles, capped.
/// `radius` and `height` > 0.
Mesh cylinder(double radius = 1.0, double height = 1.0, int segments = 32, const Vec3& center = {});

/// A flat rectangle in the plane z = center.z, normal +z, two triangles. Open (a floor or wall).
/// Sizes > 0.
Mesh quad(double sizeX = 1.0, double sizeY = 1.0, const Vec3& center = {});

/// A random convex granulate (a DEM particle): the convex hull (qhull, triangulated) of `points`
/// (≥ 4) random points on the ellipsoid with the given semi-axes, centred at the origin: unit
/// directions uniform on the sphere (Marsaglia's method on std::mt19937_64's raw output, no
/// standard-library distribution), stretched by the semi-axes. The same seed gives the same mesh
/// on every machine. Vertices are the hull's points in the order drawn. With all points on the
/// hull it has 2·points − 4 triangles (the default 42 points: 80 triangles). Semi-axes > 0;
/// `points` within the memory limit (an estimate of 512 bytes a point, qhull's included).
/// Duplicate points and points that fall on a face of the hull are dropped, so a particle may
/// have fewer triangles; a face that qhull merged from coplanar points may be triangulated with
/// zero-area triangles (detail/convex_hull.h), which every query accepts.
Mesh granulate(std::uint64_t seed, const Vec3& semiAxes = {1.0, 1.0, 1.0}, int points = 42);

}  // namespace delta::primitives
