#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "delta/query/query_mesh.h"

namespace delta {

/// How a closed mesh's parts nest, and what keeps them from bounding a solid.
///
/// A closed mesh that does not cross itself bounds a solid only where its parts (its triangles
/// joined across edges) nest as a solid's boundary does: a part whose own orientation — the sign
/// of the volume it encloses, taken relative to the whole mesh's (an inside-out mesh is handled as
/// a whole, query_mesh.h) — is outward must lie where the other parts' winding number is 0 (an
/// outer boundary), and one that is inward (a cavity's wall) where it is 1; and the surface must
/// not meet itself at a vertex. Then the winding number is 0 or 1 everywhere off the surface, and
/// the angle-weighted pseudonormal of the nearest feature gives its sign.
///
/// What breaks it:
/// - a misoriented part — an inside-out part outside the others, a shell inside a shell of the
///   same orientation, a cavity's wall outside the solid — makes the winding number −1 or 2
///   within it, and there pseudonormal signs name the wrong side;
/// - a pinched vertex — two vertices at the same coordinates (parts touching at a vertex, cubes
///   of a voxel block sharing their faces, a shell stored twice), or a vertex whose triangles make
///   more than one fan — joins sheets that the pseudonormals at it and at the faces there take for
///   one surface, and near it they name the wrong side (self_intersections.h does not count
///   triangles that share a vertex as crossing);
/// - a flat part — a closed part enclosing no volume (a triangle stored twice, back to back) —
///   has faces that coincide with opposite normals, and the pseudonormal of whichever comes first
///   names a side of a surface that has none;
/// - an undecided part: one whose place no exact ray found (every ray from its vertices met
///   another part's edge, vertex or plane, or a coordinate below 2⁻²⁵⁰ but not 0), which may be
///   misoriented.
///
/// Threading: a value type; no shared state.
struct PartNesting {
  std::size_t parts = 0;        ///< the closed mesh's parts (0 for a mesh that is not closed)
  std::size_t misoriented = 0;  ///< parts oriented against the parts around them
  std::size_t pinched = 0;      ///< pinched vertices
  std::size_t flat = 0;         ///< parts enclosing no volume
  std::size_t undecided = 0;    ///< parts no exact ray placed
  /// For the first kListed misoriented parts, each part's smallest triangle id (mesh order),
  /// ascending: for a message or a test.
  std::vector<std::uint32_t> misorientedTriangles;
  /// A triangle at the first pinched vertex (the smallest id there), where there is one.
  std::uint32_t pinchedTriangle = 0;

  /// How many parts misorientedTriangles lists at most.
  static constexpr std::size_t kListed = 16;
  /// Whether the parts nest as a solid's boundary: nothing misoriented, pinched, flat or
  /// undecided.
  bool nested() const noexcept {
    return misoriented == 0 && pinched == 0 && flat == 0 && undecided == 0;
  }
};

/// How the parts of `mesh`, if it is closed, nest (see PartNesting); nothing for a mesh that is
/// not closed. Meaningful for a mesh that does not cross itself (selfIntersections()).
///
/// Each part is placed exactly: its orientation is the exact sign of its signed volume (a float
/// sum, and expansion arithmetic where the float sum's rounding bound leaves it in doubt; a part
/// of volume exactly 0 is flat), and the other parts' winding number at one
/// of its vertices is the signed sum of an exact ray's crossings with them (exact orientation
/// predicates; the ray towards the nearest side of the mesh's box first, along an axis, then the
/// other axis rays, then six turned off the axes by about 2⁻²¹ rad, from the first of up to 32
/// of its vertices where one meets no edge, vertex or plane of theirs). Pinched vertices are
/// found by sorting the vertices by coordinates and walking each vertex's fan across edges. A
/// mesh of one part has nothing to place it against (but may be flat). O(n log n) and a ray walk
/// per part (each to the nearest side of the box), in parallel over the parts; found on the first
/// call and kept by the QueryMesh's shared data (thread-safe); the pose is irrelevant.
///
/// Pseudonormal signs, the overlap query, the volume contact law and particle shapes refuse a
/// mesh whose parts are not nested, naming the defect; winding signs, and the overlap markers of
/// the point and mesh contacts, take the winding number there.
///
/// Throws std::bad_alloc only.
///
/// Threading: any number of threads may call it on one QueryMesh (or its copies) at once.
const PartNesting& partNesting(const QueryMesh& mesh);

/// Whether `mesh` bounds a solid: closed and consistently oriented, crossing itself nowhere
/// (selfIntersections()), and its parts nested (partNesting().nested()). Then the winding number
/// off its surface is 0 or 1 and pseudonormal signs are exact. Finds what it needs on the first
/// call, as those do.
///
/// Threading: as partNesting.
bool boundsSolid(const QueryMesh& mesh);

/// What keeps the parts from nesting, for a message: "1 of its 2 parts is oriented against the
/// parts around them (…), such as the part of triangle 320", "its surface meets itself at 12
/// vertices (…), such as one of triangle 4", "1 of its 3 parts could not be placed exactly (…)";
/// empty where they nest.
///
/// Threading: a pure function.
std::string describePartNesting(const PartNesting& nesting);

}  // namespace delta
