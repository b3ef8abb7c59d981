#pragma once

#include <cmath>
#include <cstddef>

namespace delta {

/// A point or vector in 3-space, double precision. A plain aggregate: `Vec3{x, y, z}`.
///
/// Threading: a value type; no shared state.
struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;

  constexpr double& operator[](std::size_t axis) noexcept {
    return axis == 0 ? x : (axis == 1 ? y : z);
  }
  constexpr double operator[](std::size_t axis) const noexcept {
    return axis == 0 ? x : (axis == 1 ? y : z);
  }

  constexpr Vec3& operator+=(const Vec3& v) noexcept {
    x += v.x;
    y += v.y;
    z += v.z;
    return *this;
  }
  constexpr Vec3& operator-=(const Vec3& v) noexcept {
    x -= v.x;
    y -= v.y;
    z -= v.z;
    return *this;
  }
  constexpr Vec3& operator*=(double s) noexcept {
    x *= s;
    y *= s;
    z *= s;
    return *this;
  }

  friend constexpr bool operator==(const Vec3&, const Vec3&) = default;
};

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

constexpr double dot(const Vec3& a, const Vec3& b) noexcept {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
constexpr Vec3 cross(const Vec3& a, const Vec3& b) noexcept {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
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

/// The largest absolute coordinate, the scale that relative tolerances are taken against.
inline double maxAbs(const Vec3& v) noexcept {
  return std::fmax(std::fabs(v.x), std::fmax(std::fabs(v.y), std::fabs(v.z)));
}

inline bool isFinite(const Vec3& v) noexcept {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

/// `v / |v|`, or the zero vector when `v` is zero (no NaN).
inline Vec3 normalized(const Vec3& v) noexcept {
  const double n = length(v);
  return n > 0.0 ? v / n : Vec3{};
}

}  // namespace delta
