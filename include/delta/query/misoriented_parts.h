#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "delta/query/query_mesh.h"

namespace delta {

/// The parts of a closed mesh that are oriented against the parts around them.
///
/// A closed mesh that does not cross itself bounds a solid only where its parts (its triangles
/// joined across edges) nest as a solid's boundary does: a part whose own orientation — the
/// sign of the volume it encloses, taken relative to the whole mesh's (an inside-out mesh is
/// handled as a whole, query_mesh.h) — is outward must lie where the other parts' winding number
/// is 0 (an outer boundary), and one that is inward (a cavity's wall) where it is 1. Then the
/// winding number is 0 or 1 everywhere off the surface, and the pseudonormal of the nearest
/// feature gives its sign. A part that breaks the rule — an inside-out part outside the others,
/// a shell inside a shell of the same orientation, a cavity's wall outside the solid — makes the
/// winding number −1 or 2 within it, and there pseudonormal signs name the wrong side.
///
/// Threading: a value type; no shared state.
struct MisorientedParts {
  std::size_t parts = 0;  ///< the closed mesh's parts (0 for a mesh that is not closed)
  std::size_t count = 0;  ///< of them, how many are oriented against the parts around them
  /// Of them, how many no exact ray could place (every ray from 32 of its vertices met another
  /// part's edge or vertex, or a coordinate below 2⁻²⁵⁰ but not 0): taken as oriented well.
  std::size_t undecided = 0;
  /// For the first kListedParts misoriented parts, each part's smallest triangle id (mesh
  /// order), ascending: for a message or a test.
  std::vector<std::uint32_t> triangles;

  /// How many parts `triangles` lists at most.
  static constexpr std::size_t kListedParts = 16;
  bool any() const noexcept { return count != 0; }
};

/// The parts of `mesh`, if it is closed, that are oriented against the parts around them (see
/// MisorientedParts); nothing for a mesh that is not closed. Meaningful for a mesh that does not
/// cross itself (selfIntersections()), where parts nest.
///
/// Each part is placed exactly: its orientation is the sign of its signed volume about its box's
/// centre where that exceeds a bound on the sum's rounding (a part whose volume is within
/// rounding of 0 encloses nothing and passes), and the other parts' winding number at one of its
/// vertices is the signed sum of an exact ray's crossings with them (exact orientation
/// predicates; the ray along ±x, ±y or ±z from the first vertex where one meets no edge, vertex
/// or plane of theirs). A mesh of one part has nothing to place. O(n) and a ray walk per part
/// otherwise, in parallel over the parts; found on the first call and kept by the QueryMesh's
/// shared data (thread-safe); the pose is irrelevant.
///
/// Pseudonormal signs, the overlap query, the volume contact law and particle shapes refuse a
/// mesh with such parts, naming them; winding signs, and the overlap markers of the point and
/// mesh contacts, take the winding number there.
///
/// Throws std::bad_alloc only.
///
/// Threading: any number of threads may call it on one QueryMesh (or its copies) at once.
const MisorientedParts& misorientedParts(const QueryMesh& mesh);

/// Whether `mesh` bounds a solid: closed and consistently oriented, crossing itself nowhere
/// (selfIntersections()), and with no misoriented parts. Then the winding number off its surface
/// is 0 or 1 and pseudonormal signs are exact. Finds what it needs on the first call, as those do.
///
/// Threading: as misorientedParts.
bool boundsSolid(const QueryMesh& mesh);

/// "2 of its 3 parts are oriented against the parts around them (the part of triangle 40, …)",
/// for a message; empty where there are none.
///
/// Threading: a pure function.
std::string describeMisorientedParts(const MisorientedParts& parts);

}  // namespace delta
