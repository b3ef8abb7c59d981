#pragma once

#include <span>

#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

namespace delta::detail {

/// The convex hull of `points` by qhull (libqhull_r, option 'Qt': facets merged for precision
/// are triangulated; if qhull still fails, 'QJ' joggles the input): a closed mesh with
/// triangles counter-clockwise seen from outside. Its vertices are the input points that are
/// hull vertices, each once, in input order; duplicate points and points inside or on a face
/// (coplanar) are left out. A face merged from coplanar points may be triangulated with
/// zero-area triangles (qhull's 'Qt' does that to keep the mesh closed).
///
/// Throws delta::Error, with qhull's first message line, when there is no hull: fewer than 4
/// points, all points coplanar, or non-finite coordinates. qhull never prints.
///
/// Threading: each call runs qhull with its own context (qhT); calls may run concurrently.
Mesh convexHull(std::span<const Vec3> points);

}  // namespace delta::detail
