#pragma once

#include <cmath>
#include <cstdint>
#include <span>
#include <string>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

namespace delta::detail {

/// The frame the mesh measures sum in (mass_properties.cpp, measures.cpp): the box's centre as
/// origin, and the coordinates relative to it scaled by 2^-exponent (exact) so that the largest
/// is about 1. The sums are of degree up to 5 in the coordinates (the inertia): unscaled, a mesh
/// of size 1e62 overflows them and one of 1e-62 underflows them; scaled, any finite mesh sums
/// them at full precision, and only the answer, scaled back, can leave the range of a double
/// (then an error says so).
struct ScaledFrame {
  Vec3 origin;
  int exponent = 0;

  /// v·2^-exponent, exactly where the result is a normal number. By ldexp, not by a factor:
  /// for a mesh of subnormal size the factor 2^-exponent (up to 2^1074) is itself beyond a
  /// double.
  Vec3 scaled(const Vec3& v) const noexcept { return ldexp(v, -exponent); }
  /// (p − origin)·2^-exponent, computed from p and origin each scaled: nothing overflows even
  /// where the coordinates span the whole double range.
  Vec3 operator()(const Vec3& p) const noexcept { return scaled(p) - scaled(origin); }
};

/// The box of the vertices the triangles use: the measures' frame (a vertex no triangle uses,
/// which a Mesh keeps, at 1e110 scaled a unit tetrahedron's area to 0). Empty without triangles.
inline Aabb referencedBounds(const Mesh& mesh) noexcept {
  Aabb box;
  const std::span<const Vec3> vertices = mesh.vertices();
  for (const TriangleIndices& t : mesh.triangles())
    for (const std::uint32_t v : t)
      box.extend(vertices[v]);
  return box;
}

inline ScaledFrame scaledFrame(const Aabb& box) noexcept {
  ScaledFrame frame;
  frame.origin = box.lower * 0.5 + box.upper * 0.5;  // no overflow, unlike (lower + upper)/2
  const double halfExtent = maxAbs(box.upper * 0.5 - box.lower * 0.5);
  if (halfExtent > 0.0 && std::isfinite(halfExtent)) {
    frame.exponent = std::ilogb(halfExtent);
  }
  return frame;
}

/// `value`·2^exponent, exactly, or delta::Error naming `what` where that overflows a double or
/// underflows below its smallest normal number (a rounded answer).
inline double scaledBack(double value, int exponent, const char* caller, const char* what) {
  const double result = std::ldexp(value, exponent);
  if (std::isfinite(result) && (value == 0.0 || std::abs(result) >= 0x1p-1022)) return result;
  throw Error(std::string(caller) + ": the " + what + " (" + toString(value) + " × 2^" +
              std::to_string(exponent) + ") " +
              (std::isfinite(result) ? "underflows below the smallest normal double"
                                     : "overflows a double") +
              "; scale the mesh by a power of two first");
}

}  // namespace delta::detail
