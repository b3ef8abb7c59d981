#pragma once

#include <string>

#include "delta/core/aabb.h"
#include "delta/core/rotation.h"
#include "delta/query/query_mesh.h"

namespace delta::detail {

/// A sufficient test that every point of `box` moved by `motion` lies within the coordinate
/// range (one rotation: the ball about the moved centre), false also where it overflows or meets
/// a NaN. QueryMesh makes it once a pose (QueryMesh::placedSurelyInRange).
bool surelyInRange(const Aabb& box, const RigidTransform& motion) noexcept;

/// The coordinate range of a query between two prepared meshes (coordinate_range.h): each where
/// it is (its box moved by its pose) and the second carried into the first's prepared frame,
/// where the kernels meet them, lie within ±kLargestCoordinate. (Each one's prepared box was
/// checked when it was prepared.) Returns the second's pose in the first's prepared frame,
/// first.inversePose() * second.pose(). Throws delta::Error starting with `query`.
RigidTransform checkPlacedPair(const QueryMesh& first, const QueryMesh& second, const char* query);

/// Throws delta::Error (checkTriangleExtent's, naming `what`) where `mesh` holds a triangle that
/// is not one point and less than kSmallestTriangleExtent across: the mesh–mesh kernels would
/// take it for flat.
void requireTrianglesSpan(const QueryMesh& mesh, const std::string& what);

}  // namespace delta::detail
