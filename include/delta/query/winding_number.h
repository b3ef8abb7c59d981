#pragma once

#include <cstddef>
#include <numbers>

#include "delta/core/triangle.h"
#include "delta/core/vec3.h"
#include "delta/mesh/triangle_soa.h"

namespace delta {

/// The generalized winding number of a triangle mesh at a point (Jacobson, Kavan and
/// Sorkine-Hornung, "Robust Inside-Outside Segmentation using Generalized Winding Numbers",
/// SIGGRAPH 2013): the signed solid angles of the triangles seen from `point`, summed and divided
/// by 4π, each by the formula of Van Oosterom and Strackee (1983).
///
/// For a closed, outward-oriented mesh it is 1 inside and 0 outside (−1 inside an inside-out
/// mesh; k inside k nested shells), robustly: no ray is cast, so a point in line with an edge or
/// a vertex is no special case, and small holes or overlaps change it only near them. On the
/// surface itself it is about ½ and the question "inside?" has no robust answer: there the
/// distance (zero) is what matters. Degenerate (zero-area) triangles contribute 0.
///
/// An empty TriangleSoA gives 0. Any finite coordinates: a solid angle depends on directions
/// only, and its products of degree 3 are taken on the differences scaled by a power of two to
/// about 1 where they would under- or overflow (solidAngle).
///
/// O(triangles). Threading: reads the mesh only; safe to call from any number of threads.
double windingNumber(const TriangleSoA& mesh, const Vec3& point) noexcept;

/// The signed solid angle that triangle `t` subtends at `point` (Van Oosterom and Strackee):
/// positive where the point sees its vertices a, b, c counter-clockwise, in (−2π, 2π], 0 for a
/// degenerate triangle. windingNumber is their sum over 4π.
double solidAngle(const Triangle& t, const Vec3& point) noexcept;

/// windingNumber for `count` triangles held in another form: triangleAt(i) for i < count.
template <class TriangleAt>
double windingNumber(std::size_t count, const TriangleAt& triangleAt, const Vec3& point) noexcept {
  double solidAngles = 0.0;
  for (std::size_t i = 0; i < count; ++i)
    solidAngles += solidAngle(triangleAt(i), point);
  return solidAngles / (4.0 * std::numbers::pi);
}

/// windingNumber(mesh, point) > ½: inside a closed, outward-oriented mesh (on its surface: no
/// robust answer, see above).
///
/// Threading: as windingNumber.
inline bool inside(const TriangleSoA& mesh, const Vec3& point) noexcept {
  return windingNumber(mesh, point) > 0.5;
}

}  // namespace delta
