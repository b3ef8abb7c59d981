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

}  // namespace delta
