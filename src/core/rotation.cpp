#include "delta/core/rotation.h"

#include <cmath>
#include <sstream>

#include "delta/core/error.h"
#include "delta/core/format.h"

namespace delta {
using detail::normalizedOrIdentity;

Quaternion Quaternion::fromAxisAngle(const Vec3& axis, double radians) {
  if (!std::isfinite(radians))
    throw Error("rotation: angle " + toString(radians) + " (radians) is not finite");
  const double largest = maxAbs(axis);
  if (!isFinite(axis) || !(largest > 0.0))
    throw Error("rotation: axis " + toString(axis) + " must be finite and non-zero");
  // An axis whose squared length over- or underflows is scaled by a power of two (exact) first.
  Vec3 direction = axis;
  double n = length(direction);
  if (!(n > 0x1p-500 && n < 0x1p500)) {
    const int exponent = -std::ilogb(largest);
    direction = ldexp(axis, exponent);
    n = length(direction);
  }
  const double s = std::sin(0.5 * radians) / n;
  return normalizedOrIdentity(std::cos(0.5 * radians), direction.x * s, direction.y * s,
                              direction.z * s);
}

Quaternion Quaternion::fromComponents(double w, double x, double y, double z) {
  const bool finite = std::isfinite(w) && std::isfinite(x) && std::isfinite(y) && std::isfinite(z);
  if (!finite || (w == 0.0 && x == 0.0 && y == 0.0 && z == 0.0)) {
    throw Error("rotation: quaternion (" + toString(w) + ", " + toString(x) + ", " + toString(y) +
                ", " + toString(z) + ") is zero or not finite");
  }
  return normalizedOrIdentity(w, x, y, z);
}

Quaternion Quaternion::fromMatrix(const Mat3& m) {
  bool finite = true;
  for (double e : m.entries)
    finite = finite && std::isfinite(e);
  const double error = finite ? orthonormalityError(m) : INFINITY;
  if (!(error <= 1e-6) || !(m.determinant() > 0.0)) {
    std::ostringstream message;
    message.precision(17);
    message << "rotation: matrix [";
    for (int i = 0; i < 9; ++i)
      message << (i ? (i % 3 ? ", " : "; ") : "") << m.entries[i];
    message << "] is not a rotation (|MᵀM − I| = " << error << ", det = " << m.determinant() << ")";
    throw Error(message.str());
  }
  // Shepperd's method: pivot on the largest of w², x², y², z² for accuracy.
  const double trace = m(0, 0) + m(1, 1) + m(2, 2);
  if (trace >= m(0, 0) && trace >= m(1, 1) && trace >= m(2, 2)) {
    const double r = std::sqrt(1.0 + trace);
    const double s = 0.5 / r;
    return normalizedOrIdentity(0.5 * r, (m(2, 1) - m(1, 2)) * s, (m(0, 2) - m(2, 0)) * s,
                                (m(1, 0) - m(0, 1)) * s);
  }
  if (m(0, 0) >= m(1, 1) && m(0, 0) >= m(2, 2)) {
    const double r = std::sqrt(1.0 + m(0, 0) - m(1, 1) - m(2, 2));
    const double s = 0.5 / r;
    return normalizedOrIdentity((m(2, 1) - m(1, 2)) * s, 0.5 * r, (m(0, 1) + m(1, 0)) * s,
                                (m(0, 2) + m(2, 0)) * s);
  }
  if (m(1, 1) >= m(2, 2)) {
    const double r = std::sqrt(1.0 - m(0, 0) + m(1, 1) - m(2, 2));
    const double s = 0.5 / r;
    return normalizedOrIdentity((m(0, 2) - m(2, 0)) * s, (m(0, 1) + m(1, 0)) * s, 0.5 * r,
                                (m(1, 2) + m(2, 1)) * s);
  }
  const double r = std::sqrt(1.0 - m(0, 0) - m(1, 1) + m(2, 2));
  const double s = 0.5 / r;
  return normalizedOrIdentity((m(1, 0) - m(0, 1)) * s, (m(0, 2) + m(2, 0)) * s,
                              (m(1, 2) + m(2, 1)) * s, 0.5 * r);
}

Mat3 Quaternion::matrix() const noexcept {
  const double xx = x * x, yy = y * y, zz = z * z;
  const double xy = x * y, xz = x * z, yz = y * z;
  const double wx = w * x, wy = w * y, wz = w * z;
  return {{1 - 2 * (yy + zz), 2 * (xy - wz), 2 * (xz + wy),  //
           2 * (xy + wz), 1 - 2 * (xx + zz), 2 * (yz - wx),  //
           2 * (xz - wy), 2 * (yz + wx), 1 - 2 * (xx + yy)}};
}

Aabb movedBox(const Aabb& box, const RigidTransform& motion) noexcept {
  Aabb moved;
  if (box.empty()) return moved;
  for (int corner = 0; corner < 8; ++corner)
    moved.extend(motion.apply(box.corner(corner)));
  return moved;
}

}  // namespace delta
