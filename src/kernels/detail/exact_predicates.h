#pragma once

// Exact orientation predicates on double coordinates: for the overlap query, with the symbolic
// perturbation that makes every configuration generic, and for the triangle–triangle kernel's
// piercing test where its rounding bounds cannot decide (triangle_triangle.cpp), the winding
// number's signs and the part nesting.
//
// orient(p, q, r, s) = (s − p)·((q − p) × (r − p)): positive where s lies on the side of the
// plane through p, q, r that the right-handed normal (q − p) × (r − p) points to. Its sign comes
// from a floating-point filter (Shewchuk's error bound for the 3×3 determinant of differences,
// "Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric Predicates", 1997)
// and, where the filter cannot decide, from an exact evaluation in expansion arithmetic.
//
// The perturbation: the second mesh (B) is translated by t = (δ, δ², δ³), δ → 0⁺. A sign that
// is zero for the meshes as given is the sign of the first non-vanishing term in δ:
//   - a vertex s of A against a triangle (p, q, r) of B: orient(p+t, q+t, r+t, s) = D − t·N,
//     N = (q − p) × (r − p);
//   - a vertex s of B against a triangle of A: D + t·N;
//   - an edge (a0, a1) of A against an edge (b0, b1) of B: orient(a0, a1, b0+t, b1+t) =
//     D + t·((b1 − b0) × (a1 − a0)).
// t·v has the sign of v's first non-zero component. These are zero only for a triangle of zero
// area (N = 0) and for parallel edges, where the callers never need them (a segment parallel
// to an edge of a triangle is parallel to its plane and cannot cross it).
//
// One predicate of degree 6 orders the points where an edge crosses two planes of the other
// mesh (crossingOrder): where the edge crosses plane k at λ_k = m_k/n_k along it, m_k =
// orient(T_k, e0) = D_k − τ·N_k (τ the displacement of the triangles against the edge: t for an
// edge of A, −t for one of B) and n_k = orient(T_k, e0) − orient(T_k, e1), which the
// displacement does not change, λ_1 − λ_2 has the sign of n_1·n_2·(F − τ·G), F = D_1 n_2 −
// D_2 n_1 and G = n_2 N_1 − n_1 N_2.

#include <array>
#include <cmath>
#include <vector>

#include "delta/core/vec3.h"

namespace delta::detail {

/// The least non-zero |coordinate| the predicates take, 2⁻²⁵⁰: their products of three coordinate
/// differences are then multiples of 2⁻⁹⁰⁶, normal doubles, so the filters' relative error bounds
/// and the expansions' error-free products hold. Below it (a mesh of size 1 moved by 1e-300) they
/// would round by underflow, and a sign could be wrong.
inline constexpr double kSmallestExactCoordinate = 0x1p-250;

/// Whether every coordinate of `p` is 0 or at least kSmallestExactCoordinate in magnitude.
inline bool predicatesExactAt(const Vec3& p) noexcept {
  const auto exact = [](double c) { return c == 0.0 || !(std::abs(c) < kSmallestExactCoordinate); };
  return exact(p.x) && exact(p.y) && exact(p.z);
}

/// The exact sign of orient(p, q, r, s) (−1, 0, +1), without orientSign's filter: 0 at once for
/// two equal points or a zero factor in every product, else a double-double evaluation where its
/// error bound decides (128ε² of the permanent), else expansion arithmetic.
int exactOrientSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) noexcept;

/// The exact sign of the first non-zero component of (q − p) × (s − r), in the order x, y, z
/// (0 where the cross product is the zero vector).
int exactCrossLeadingSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) noexcept;

/// The order along the edge e0 → e1 of the points where it crosses the planes of triangles
/// `first` and `second` of the other mesh, B perturbed: −1 where it crosses `first`'s first,
/// +1 where `second`'s, 0 where the two planes cross its line at one point whatever the
/// displacement (one plane, or parallel ones through one point: the triangles lie in one plane).
/// `edgeOfA`: the edge is A's and the triangles B's; else the other way round. Neither plane
/// may be parallel to the edge (both cross it, where the callers ask).
///
/// Its sign is exact: a floating-point filter (Shewchuk's bounds on the determinants of degree
/// 3, carried through the products), then integer arithmetic on the stack (the products of six
/// coordinate differences span up to some 3,000 bits, beyond a double's exponents, which the
/// expansions would need); a coordinate outside that range throws delta::Error. Every coordinate as
/// the other predicates take them (0 or at least kSmallestExactCoordinate in magnitude, within the
/// coordinate range). For crossings that lie on one another to within their rounding: where an edge
/// lies in the other's plane to an ulp (faces coplanar but for the rounding of their turned
/// corners), the rounded crossing points are anywhere along it, and no tolerance orders them.
int crossingOrder(const Vec3& e0, const Vec3& e1, const std::array<Vec3, 3>& first,
                  const std::array<Vec3, 3>& second, bool edgeOfA);

/// The exact sign of ((b − a) × (c − a))·((e − s) × (p − s)) (−1, 0, +1): the side of the line
/// through s and e, within the plane of triangle (a, b, c), on which p's projection onto that
/// plane lies; positive on the side the triangle's corners lie on, for an edge (s, e) of it in
/// its order (a, b), (b, c) or (c, a). For the point–triangle kernel, where its rounded face
/// test leaves p's projection within rounding of an edge's line (robust_geometry.h). In integer
/// arithmetic (degree 4, up to some 2,300 bits); every coordinate must be 0 or at least
/// kSmallestExactCoordinate in magnitude and within the coordinate range (2²⁰⁰), else
/// delta::Error.
int exactFaceAreaSign(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& s, const Vec3& e,
                      const Vec3& p);

/// An exact sum of triple products a·(b × c) (six times a closed surface's signed volume, one
/// term a triangle): its sign where a float sum's rounding leaves it in doubt. Every coordinate
/// must be 0 or at least kSmallestExactCoordinate in magnitude (predicatesExactAt), and within
/// the coordinate range.
class ExactTripleProductSum {
 public:
  /// Adds a·(b × c), exactly (expansion arithmetic; may throw std::bad_alloc).
  void add(const Vec3& a, const Vec3& b, const Vec3& c);
  /// The sum's sign: −1, 0 or +1.
  int sign() const noexcept;

 private:
  std::vector<double> sum_;  ///< an expansion: non-overlapping, increasing magnitude
};

/// Shewchuk's bound on the rounding of orient's determinant of differences, relative to its
/// permanent (the sum of the absolute values of its products): (7 + 56ε)ε, ε = 2⁻⁵³.
inline constexpr double kOrientErrorBound = (7.0 + 56.0 * 0x1p-53) * 0x1p-53;

/// The filter's sign of orient(p, q, r, s) from the differences u = q − p, v = r − p,
/// w = s − p (rounded): the determinant u·(v × w) in floating point, decided where it exceeds
/// Shewchuk's bound on its rounding; 0 where it cannot decide.
[[gnu::always_inline]] inline int filteredOrientSign(const Vec3& u, const Vec3& v,
                                                     const Vec3& w) noexcept {
  const double a = v.y * w.z, b = v.z * w.y, c = v.z * w.x, d = v.x * w.z, e = v.x * w.y,
               f = v.y * w.x;
  const double det = u.x * (a - b) + u.y * (c - d) + u.z * (e - f);
  const double permanent = std::abs(u.x) * (std::abs(a) + std::abs(b)) +
                           std::abs(u.y) * (std::abs(c) + std::abs(d)) +
                           std::abs(u.z) * (std::abs(e) + std::abs(f));
  const double bound = kOrientErrorBound * permanent;
  // Without branches: the callers' signs are a coin toss to the predictor.
  return static_cast<int>(det > bound) - static_cast<int>(-det > bound);
}

/// The sign of orient(p, q, r, s) (−1, 0, +1): filtered, exact where the filter fails.
inline int orientSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) noexcept {
  const int sign = filteredOrientSign(q - p, r - p, s - p);
  return sign != 0 ? sign : exactOrientSign(p, q, r, s);
}

/// The side of triangle (p, q, r) of A on which vertex s of B lies, B perturbed (never 0 unless
/// the triangle has zero area).
inline int sideOfBVertex(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const int sign = orientSign(p, q, r, s);
  return sign != 0 ? sign : exactCrossLeadingSign(p, q, p, r);
}

/// The side of triangle (p, q, r) of B on which vertex s of A lies, B perturbed.
inline int sideOfAVertex(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const int sign = orientSign(p, q, r, s);
  return sign != 0 ? sign : -exactCrossLeadingSign(p, q, p, r);
}

/// The sign of orient(a0, a1, b0 + t, b1 + t): edge (a0, a1) of A against edge (b0, b1) of B,
/// B perturbed (0 only for parallel edges on one line or plane).
inline int edgeSign(const Vec3& a0, const Vec3& a1, const Vec3& b0, const Vec3& b1) {
  const int sign = orientSign(a0, a1, b0, b1);
  return sign != 0 ? sign : exactCrossLeadingSign(b0, b1, a0, a1);
}

}  // namespace delta::detail
