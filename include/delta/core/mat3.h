#pragma once

#include <array>

#include "delta/core/vec3.h"

namespace delta {

/// A 3×3 matrix, row-major: `m(row, column)`. Used for rotations and inertia tensors.
/// Default-constructed it is zero. Indices are unchecked (0 to 2).
///
/// Threading: a value type; no shared state; the operators below are pure functions.
struct Mat3 {
  std::array<double, 9> entries{};

  static constexpr Mat3 identity() noexcept { return {{1, 0, 0, 0, 1, 0, 0, 0, 1}}; }
  static constexpr Mat3 fromRows(const Vec3& r0, const Vec3& r1, const Vec3& r2) noexcept {
    return {{r0.x, r0.y, r0.z, r1.x, r1.y, r1.z, r2.x, r2.y, r2.z}};
  }
  static constexpr Mat3 diagonal(const Vec3& d) noexcept {
    return {{d.x, 0, 0, 0, d.y, 0, 0, 0, d.z}};
  }

  constexpr double& operator()(int row, int column) noexcept { return entries[row * 3 + column]; }
  constexpr double operator()(int row, int column) const noexcept {
    return entries[row * 3 + column];
  }
  constexpr Vec3 row(int r) const noexcept {
    return {entries[r * 3], entries[r * 3 + 1], entries[r * 3 + 2]};
  }
  constexpr Vec3 column(int c) const noexcept {
    return {entries[c], entries[3 + c], entries[6 + c]};
  }

  constexpr Mat3 transposed() const noexcept { return fromRows(column(0), column(1), column(2)); }
  constexpr double determinant() const noexcept { return dot(row(0), cross(row(1), row(2))); }

  friend constexpr bool operator==(const Mat3&, const Mat3&) = default;
};

constexpr Vec3 operator*(const Mat3& m, const Vec3& v) noexcept {
  return {dot(m.row(0), v), dot(m.row(1), v), dot(m.row(2), v)};
}

constexpr Mat3 operator*(const Mat3& a, const Mat3& b) noexcept {
  Mat3 product;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      product(r, c) = dot(a.row(r), b.column(c));
  return product;
}

constexpr Mat3 operator+(const Mat3& a, const Mat3& b) noexcept {
  Mat3 sum;
  for (int i = 0; i < 9; ++i)
    sum.entries[i] = a.entries[i] + b.entries[i];
  return sum;
}

constexpr Mat3 operator*(const Mat3& a, double s) noexcept {
  Mat3 scaled;
  for (int i = 0; i < 9; ++i)
    scaled.entries[i] = a.entries[i] * s;
  return scaled;
}

/// Whether `m` is a multiple of the identity, exactly (R·m·Rᵀ = m for every rotation R: a
/// sphere's inertia). False where an entry is NaN.
///
/// Threading: a pure function.
constexpr bool isMultipleOfIdentity(const Mat3& m) noexcept {
  return m(0, 1) == 0.0 && m(0, 2) == 0.0 && m(1, 0) == 0.0 && m(1, 2) == 0.0 && m(2, 0) == 0.0 &&
         m(2, 1) == 0.0 && m(0, 0) == m(1, 1) && m(1, 1) == m(2, 2);
}

/// max |(MᵀM − I)ᵢⱼ|: how far `m` is from orthonormal (0 for a rotation or a reflection; NaN
/// when an entry is NaN).
///
/// Threading: a pure function.
double orthonormalityError(const Mat3& m) noexcept;

}  // namespace delta
