#pragma once

#include <span>

#include "delta/core/sphere.h"
#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

namespace delta {

/// A tight bounding sphere of a point set: it contains every point (guaranteed, rounding
/// included: `Sphere::contains` is true for each) and its radius is within a few percent of the
/// minimal enclosing sphere's (in practice equal to it to about 1e-9). Expected O(n): Welzl's
/// minimal ball of the extreme points along 13 directions, grown by the farthest point a few
/// times. Any point set works: one point (radius 0), duplicates, collinear or coplanar points,
/// points far from the origin. Throws delta::Error for an empty or non-finite point set, or
/// points so far apart that their squared distances overflow (from about 1.3e154 apart, where
/// `Sphere::contains` could not hold; meshes lie within ±2²⁰⁰, about 1.6e60). For sets below
/// about 1e-154 across, whose squared distances are subnormal, the radius is that of
/// `Sphere::contains`'s rounded distances, up to about 1e-4 above the minimal ball's.
///
/// Threading: reads its input only; safe to call concurrently.
Sphere boundingSphere(std::span<const Vec3> points);

/// The bounding sphere of the mesh's vertices, referenced by a triangle or not (a Mesh always has
/// some, all finite, so this throws only when their squared distances overflow).
///
/// Threading: reads the mesh only; safe to call concurrently.
Sphere boundingSphere(const Mesh& mesh);

}  // namespace delta
