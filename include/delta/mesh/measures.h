#pragma once

#include <cstddef>

#include "delta/core/triangle.h"
#include "delta/mesh/mesh.h"

namespace delta {

/// Edge-length statistics over the mesh's distinct edges: the mesh size h that a user passes to
/// filter(h), and the scale of the mesh's finest detail.
///
/// Threading: a value type; no shared state.
struct EdgeLengths {
  double min = 0.0;
  double mean = 0.0;
  double max = 0.0;
};

/// True when the triangle's area is zero relative to its size: |(b−a)×(c−a)| ≤ 1e-12 · L², with
/// L its longest edge (so a triangle whose three vertices coincide is degenerate too). The test
/// is scale-invariant: it gives the same answer for a triangle scaled by 1e-9 or 1e9 (the edges
/// are rescaled by a power of two before squaring, so nothing under- or overflows).
///
/// Threading (every function here): reads its arguments only; safe to call concurrently.
bool isDegenerate(const Triangle& triangle) noexcept;

/// The number of degenerate triangles (see isDegenerate).
///
/// Threading: reads the mesh only; safe to call concurrently.
std::size_t degenerateTriangleCount(const Mesh& mesh) noexcept;

/// The sum of the triangles' areas (degenerate ones add 0; overlapping triangles each count).
/// Any finite mesh: the edges are scaled by a power of two to about the mesh's size 1 (exact; the
/// size of the vertices the triangles use: one unused at 1e110 made a unit tetrahedron's area 0)
/// while the cross products are summed, then the sum is scaled back. Throws delta::Error when
/// the area itself is beyond a double (a mesh of size 1e154 or more) or a nonzero area is below
/// its smallest normal number.
///
/// Threading: reads the mesh only; safe to call concurrently.
double surfaceArea(const Mesh& mesh);

/// Lengths of the distinct edges (an edge shared by two triangles counts once; triangles with a
/// repeated index add none, as in analyzeTopology). Zero-length edges count; with no edge at
/// all every statistic is 0 (never NaN). Measured with the coordinates scaled by a power of two
/// (exact) so that no square overflows; throws delta::Error when the longest edge itself is
/// beyond a double (vertices near ±1.8e308 on opposite sides).
///
/// Threading: reads the mesh only; safe to call concurrently.
EdgeLengths edgeLengths(const Mesh& mesh);

}  // namespace delta
