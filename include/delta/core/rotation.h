#pragma once

#include <cmath>

#include "delta/core/aabb.h"
#include "delta/core/mat3.h"
#include "delta/core/vec3.h"

namespace delta {

/// A unit quaternion w + xi + yj + zk representing a rotation. Rotations compose as quaternions
/// and are renormalised after every product, so a long chain of them (a DEM particle turned every
/// time step) stays a rotation: its matrix is orthonormal to 1e-14. Default-constructed it is the
/// identity. The factories and the product always give a unit quaternion; one whose components
/// are set by hand should go through fromComponents (matrix() and rotate() assume unit length).
///
/// Threading: a value type; no shared state.
struct Quaternion {
  double w = 1.0;
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;

  static constexpr Quaternion identity() noexcept { return {}; }

  /// The rotation by `radians` about `axis` (right-handed): any finite, non-zero axis, however
  /// long or short (its direction is what counts). Throws delta::Error when the axis is zero or
  /// either argument is not finite.
  static Quaternion fromAxisAngle(const Vec3& axis, double radians);

  /// The rotation of an orthonormal matrix with determinant +1. Throws delta::Error when `m` is
  /// further than 1e-6 from a rotation (not orthonormal, a reflection, not finite); a matrix
  /// within that distance is projected onto the nearest rotation.
  static Quaternion fromMatrix(const Mat3& m);

  /// Throws delta::Error when (w, x, y, z) is zero or not finite; otherwise the unit quaternion
  /// in its direction (so a "unit" quaternion read from a file with 8 digits is accepted).
  static Quaternion fromComponents(double w, double x, double y, double z);

  /// The rotation matrix; orthonormal to round-off for a unit quaternion.
  Mat3 matrix() const noexcept;

  /// Rotates a vector (same as `matrix() * v`, to round-off).
  Vec3 rotate(const Vec3& v) const noexcept {
    // v' = v + 2 u × (u × v + w v), u = (x, y, z): 15 multiplications, no matrix.
    const Vec3 u{x, y, z};
    const Vec3 t = cross(u, v) * 2.0;
    return v + t * w + cross(u, t);
  }

  /// The inverse rotation (for a unit quaternion).
  Quaternion conjugate() const noexcept { return {w, -x, -y, -z}; }
};

namespace detail {
/// (w, x, y, z) / |(w, x, y, z)|, or the identity for a zero (or NaN) one. Where the sum of
/// squares would over- or underflow (components beyond about 1e150 or all below 1e-150), the
/// components are first scaled by a power of two (exact), so a finite, non-zero quaternion
/// always keeps its direction; elsewhere nothing is scaled and no bit changes.
inline Quaternion normalizedOrIdentity(double w, double x, double y, double z) noexcept {
  double n = std::sqrt(w * w + x * x + y * y + z * z);
  if (!(n > 0x1p-500 && n < 0x1p500)) [[unlikely]] {
    const double largest =
        std::fmax(std::fmax(std::fabs(w), std::fabs(x)), std::fmax(std::fabs(y), std::fabs(z)));
    if (!(largest > 0.0) || !std::isfinite(largest)) return Quaternion{};
    const int exponent = -std::ilogb(largest);  // ldexp, not a factor: 2^1074 overflows
    w = std::ldexp(w, exponent), x = std::ldexp(x, exponent);
    y = std::ldexp(y, exponent), z = std::ldexp(z, exponent);
    n = std::sqrt(w * w + x * x + y * y + z * z);
  }
  if (!(n > 0.0)) return Quaternion{};
  return {w / n, x / n, y / n, z / n};
}

/// A quaternion's components in any number type with +, − and × (two quaternions to a vector
/// register in the DEM's turns, src/dem/world.cpp).
///
/// Threading: a value type; no shared state.
template <class T>
struct QuaternionParts {
  T w, x, y, z;
};

/// The product a·b, not normalised: operator*'s arithmetic, in its order, for any such type.
template <class T>
QuaternionParts<T> product(const QuaternionParts<T>& a, const QuaternionParts<T>& b) noexcept {
  return {
      a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z, a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x, a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}
}  // namespace detail

/// The rotation `a` after `b` (first `b`, then `a`), renormalised (the identity should the product
/// come out zero, which unit factors never give).
///
/// Threading: a pure function.
inline Quaternion operator*(const Quaternion& a, const Quaternion& b) noexcept {
  const detail::QuaternionParts<double> p =
      detail::product<double>({a.w, a.x, a.y, a.z}, {b.w, b.x, b.y, b.z});
  return detail::normalizedOrIdentity(p.w, p.x, p.y, p.z);
}

/// A rigid motion p ↦ R p + t, with the rotation kept as a unit quaternion. Compose with `*`
/// (`a * b` applies b first); the inverse undoes it. Default-constructed it is the identity.
/// Whoever takes one (Mesh::transform, QueryMesh::transform) checks it: a non-finite translation
/// or a zero or non-finite rotation throws delta::Error there.
///
/// Threading: a value type; no shared state.
struct RigidTransform {
  Quaternion rotation;
  Vec3 translation;

  /// p ↦ p + t.
  static RigidTransform translationBy(const Vec3& t) noexcept { return {Quaternion{}, t}; }
  /// Rotation about the line through `pivot` (not through the origin).
  static RigidTransform rotationAbout(const Quaternion& q, const Vec3& pivot) noexcept {
    return {q, pivot - q.rotate(pivot)};
  }

  /// R p + t.
  Vec3 apply(const Vec3& p) const noexcept { return rotation.rotate(p) + translation; }
  /// The motion that undoes this one (exact up to rounding).
  RigidTransform inverse() const noexcept {
    const Quaternion back = rotation.conjugate();
    return {back, -back.rotate(translation)};
  }
};

/// `a` after `b`: p ↦ a(b(p)).
///
/// Threading: a pure function.
inline RigidTransform operator*(const RigidTransform& a, const RigidTransform& b) noexcept {
  return {a.rotation * b.rotation, a.rotation.rotate(b.translation) + a.translation};
}

/// The box of `box`'s eight corners moved by `motion`: it holds every point of `box` moved (a
/// rigid motion maps the box to a parallelepiped, the hull of its moved corners), up to the
/// rounding of the motion. Empty for an empty box.
///
/// Threading: a pure function.
Aabb movedBox(const Aabb& box, const RigidTransform& motion) noexcept;

}  // namespace delta
