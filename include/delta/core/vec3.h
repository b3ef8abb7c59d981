#pragma once

#include <cmath>
#include <cstddef>

namespace delta {

/// A point or vector in 3-space, double precision. A plain aggregate: `Vec3{x, y, z}`,
/// default-constructed zero. Nothing here checks for NaN or infinities: Δ validates coordinates
/// where they enter (Mesh construction, file import, each query), not in this arithmetic.
///
/// Threading: a value type; no shared state; the operators and functions below are pure.
struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;

  /// Coordinate `axis`: 0 → x, 1 → y, anything else → z.
  constexpr double& operator[](std::size_t axis) noexcept {
    return axis == 0 ? x : (axis == 1 ? y : z);
  }
  constexpr double operator[](std::size_t axis) const noexcept {
    return axis == 0 ? x : (axis == 1 ? y : z);
  }

  // Always inlined, as aabb.h's distanceSquared(Vec3, Aabb) and QueryMeshData::triangle are:
  // the per-ISA point tables call them (src/CMakeLists.txt), and an out-of-line copy built with
  // one ISA's flags could stand in for every caller's (clang 14 with the sanitizers left them
  // out of line; ISA.NoSharedCodeBetweenInstructionSets).
  [[gnu::always_inline]] constexpr Vec3& operator+=(const Vec3& v) noexcept {
    x += v.x;
    y += v.y;
    z += v.z;
    return *this;
  }
  [[gnu::always_inline]] constexpr Vec3& operator-=(const Vec3& v) noexcept {
    x -= v.x;
    y -= v.y;
    z -= v.z;
    return *this;
  }
  [[gnu::always_inline]] constexpr Vec3& operator*=(double s) noexcept {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }

  friend constexpr bool operator==(const Vec3&, const Vec3&) = default;
};

/// Vector arithmetic, component-wise (a Vec3 divided by 0 gives infinities or NaN, as doubles do).
constexpr Vec3 operator+(Vec3 a, const Vec3& b) noexcept {
  return a += b;
}
constexpr Vec3 operator-(Vec3 a, const Vec3& b) noexcept {
  return a -= b;
}
constexpr Vec3 operator-(const Vec3& a) noexcept {
  return {-a.x, -a.y, -a.z};
}
constexpr Vec3 operator*(Vec3 a, double s) noexcept {
  return a *= s;
}
constexpr Vec3 operator*(double s, Vec3 a) noexcept {
  return a *= s;
}
constexpr Vec3 operator/(const Vec3& a, double s) noexcept {
  return {a.x / s, a.y / s, a.z / s};
}

/// The scalar product a·b.
constexpr double dot(const Vec3& a, const Vec3& b) noexcept {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
/// The vector product a × b (zero for parallel vectors).
constexpr Vec3 cross(const Vec3& a, const Vec3& b) noexcept {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// |v|², |v|, |a − b|² and |a − b|, unscaled: overflow to +∞ beyond about 1e154 (kernels that
/// must work at any scale compute in a local frame instead).
constexpr double lengthSquared(const Vec3& v) noexcept {
  return dot(v, v);
}
inline double length(const Vec3& v) noexcept {
  return std::sqrt(dot(v, v));
}
constexpr double distanceSquared(const Vec3& a, const Vec3& b) noexcept {
  return lengthSquared(a - b);
}
inline double distance(const Vec3& a, const Vec3& b) noexcept {
  return length(a - b);
}

/// Component-wise minimum and maximum.
constexpr Vec3 min(const Vec3& a, const Vec3& b) noexcept {
  return {a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y, a.z < b.z ? a.z : b.z};
}
constexpr Vec3 max(const Vec3& a, const Vec3& b) noexcept {
  return {a.x > b.x ? a.x : b.x, a.y > b.y ? a.y : b.y, a.z > b.z ? a.z : b.z};
}

/// The largest absolute coordinate, the scale that relative tolerances are taken against. As
/// std::fmax of the three magnitudes (a NaN coordinate is passed over; all NaN: NaN), written out
/// so that it inlines: on the x86-64 baseline std::fmax is a library call (maxsd differs from it
/// on NaN), which cost 1.3% of a sphere pile's step.
inline double maxAbs(const Vec3& v) noexcept {
  // fmax(a, b) for a, b ≥ 0 or NaN: b where a is NaN or below it, else a.
  const auto larger = [](double a, double b) { return (a < b || a != a) ? b : a; };
  return larger(std::fabs(v.x), larger(std::fabs(v.y), std::fabs(v.z)));
}

/// v·2^exponent coordinate by coordinate, by std::ldexp: exact wherever the result is a normal
/// number, and defined for exponents whose power of two is itself beyond a double (scaling a
/// subnormal vector up by 2^1074), where a multiplication by the factor is not.
inline Vec3 ldexp(const Vec3& v, int exponent) noexcept {
  return {std::ldexp(v.x, exponent), std::ldexp(v.y, exponent), std::ldexp(v.z, exponent)};
}

/// Whether no coordinate is NaN or infinite.
inline bool isFinite(const Vec3& v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// `v / |v|`, or the zero vector when `v` is zero (no NaN).
inline Vec3 normalized(const Vec3& v) noexcept {
  const double n = length(v);
  return n > 0.0 ? v / n : Vec3{};
}

}  // namespace delta
