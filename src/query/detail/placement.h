#pragma once

#include <string>

#include "delta/core/aabb.h"
#include "delta/core/rotation.h"
#include "delta/query/query_mesh.h"

namespace delta::detail {

/// The box of `box`'s eight corners moved by `motion`: it holds every point of `box` moved (a
/// rigid motion maps the box to a parallelepiped, the hull of its moved corners), up to the
/// rounding of the motion.
Aabb movedBox(const Aabb& box, const RigidTransform& motion) noexcept;

/// The coordinate range of a query between two prepared meshes (coordinate_range.h): each where
/// it is (its box moved by its pose) and the second carried into the first's prepared frame,
/// where the kernels meet them, lie within ±kLargestCoordinate. (Each one's prepared box was
/// checked when it was prepared.) Throws delta::Error starting with `query`.
void checkPlacedPair(const QueryMesh& first, const QueryMesh& second, const char* query);

}  // namespace delta::detail
