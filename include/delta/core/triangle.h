#pragma once

#include "delta/core/aabb.h"
#include "delta/core/vec3.h"

namespace delta {

/// Three vertices, in the order that fixes the face's orientation: the normal (b−a)×(c−a) points
/// outward on an outward-oriented mesh. A zero-area ("degenerate") triangle is a valid value.
///
/// Threading: a value type; no shared state.
struct Triangle {
  Vec3 a;
  Vec3 b;
  Vec3 c;

  /// (b−a)×(c−a): its length is twice the area; zero for a degenerate triangle.
  constexpr Vec3 areaVector() const noexcept { return cross(b - a, c - a); }
  /// Half |areaVector()|; 0 for a degenerate triangle (see isDegenerate for the scale-aware test).
  double area() const noexcept { return 0.5 * length(areaVector()); }
  /// (a + b + c) / 3, a point of the triangle also when it is degenerate.
  constexpr Vec3 centroid() const noexcept { return (a + b + c) / 3.0; }
  /// The box of the three vertices.
  constexpr Aabb bounds() const noexcept { return {min(min(a, b), c), max(max(a, b), c)}; }
};

}  // namespace delta
