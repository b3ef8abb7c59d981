#include "delta/mesh/triangle_soa.h"

#include <limits>

#include "delta/mesh/mesh.h"

namespace delta {

TriangleSoA::TriangleSoA(const Mesh& mesh)
    : size_(mesh.triangleCount()),
      paddedSize_((size_ + kLaneMultiple - 1) / kLaneMultiple * kLaneMultiple),
      data_(9 * paddedSize_, std::numeric_limits<double>::quiet_NaN()) {
  const auto vertices = mesh.vertices();
  const auto triangles = mesh.triangles();
  double* streams[9];
  for (int s = 0; s < 9; ++s)
    streams[s] = data_.data() + s * paddedSize_;
  for (std::size_t i = 0; i < size_; ++i) {
    for (int slot = 0; slot < 3; ++slot) {
      const Vec3& p = vertices[triangles[i][slot]];
      streams[slot * 3 + 0][i] = p.x;
      streams[slot * 3 + 1][i] = p.y;
      streams[slot * 3 + 2][i] = p.z;
    }
  }
}

void TriangleSoA::assign(std::span<const Triangle> triangles) {
  const std::size_t padded = (triangles.size() + kLaneMultiple - 1) / kLaneMultiple * kLaneMultiple;
  if (data_.size() < 9 * padded) data_.resize(9 * padded);
  size_ = triangles.size();
  paddedSize_ = padded;
  double* streams[9];
  for (int s = 0; s < 9; ++s)
    streams[s] = data_.data() + s * paddedSize_;
  for (std::size_t i = 0; i < paddedSize_; ++i)
    for (int slot = 0; slot < 3; ++slot) {
      constexpr double nan = std::numeric_limits<double>::quiet_NaN();
      const Vec3 p = i >= size_  ? Vec3{nan, nan, nan}
                     : slot == 0 ? triangles[i].a
                     : slot == 1 ? triangles[i].b
                                 : triangles[i].c;
      streams[slot * 3 + 0][i] = p.x;
      streams[slot * 3 + 1][i] = p.y;
      streams[slot * 3 + 2][i] = p.z;
    }
}

TriangleSoA TriangleSoA::transformed(const RigidTransform& motion) const {
  TriangleSoA moved = *this;
  const Quaternion& q = motion.rotation;  // as Mesh::transform: the same vertices, bit for bit
  const Mat3 rotation = Quaternion::fromComponents(q.w, q.x, q.y, q.z).matrix();
  for (int slot = 0; slot < 3; ++slot) {
    double* x = moved.data_.data() + static_cast<std::size_t>(slot * 3) * paddedSize_;
    double* y = x + paddedSize_;
    double* z = y + paddedSize_;
    for (std::size_t i = 0; i < size_; ++i) {
      const Vec3 p = rotation * Vec3{x[i], y[i], z[i]} + motion.translation;
      x[i] = p.x;
      y[i] = p.y;
      z[i] = p.z;
    }
  }
  return moved;
}

}  // namespace delta
