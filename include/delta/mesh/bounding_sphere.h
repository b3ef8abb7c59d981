#pragma once

#include <span>

#include "delta/core/sphere.h"
#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

namespace delta {

/// A tight bounding sphere of a point set: it contains every point (guaranteed, rounding
/// included) and its radius is within a few percent of the minimal enclosing sphere's. Expected
/// O(n). Throws delta::Error for an empty or non-finite point set.
Sphere boundingSphere(std::span<const Vec3> points);

/// The bounding sphere of the mesh's vertices.
Sphere boundingSphere(const Mesh& mesh);

}  // namespace delta
