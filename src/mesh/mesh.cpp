#include "delta/mesh/mesh.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

#include "delta/core/error.h"
#include "delta/core/format.h"

namespace delta {
namespace {

[[noreturn]] void fail(const std::string& what) {
  throw Error("mesh: " + what);
}

}  // namespace

Mesh::Mesh(std::vector<Vec3> vertices, std::vector<TriangleIndices> triangles)
    : vertices_(std::move(vertices)), triangles_(std::move(triangles)) {
  if (triangles_.empty()) fail("has no triangles");
  if (vertices_.size() > std::numeric_limits<std::uint32_t>::max())
    fail("has " + std::to_string(vertices_.size()) + " vertices, more than 32-bit indices reach");
  for (std::size_t i = 0; i < vertices_.size(); ++i)
    if (!isFinite(vertices_[i]))
      fail("vertex " + std::to_string(i) +
           " has a coordinate that is not finite: " + toString(vertices_[i]));
  const std::size_t count = vertices_.size();
  for (std::size_t t = 0; t < triangles_.size(); ++t)
    for (std::uint32_t index : triangles_[t])
      if (index >= count)
        fail("triangle " + std::to_string(t) + " refers to vertex " + std::to_string(index) +
             ", but there are only " + std::to_string(count) + " vertices");
}

Aabb Mesh::bounds() const noexcept {
  Aabb box;
  for (const Vec3& v : vertices_)
    box.extend(v);
  return box;
}

std::size_t Mesh::memoryBytes() const noexcept {
  return vertices_.capacity() * sizeof(Vec3) + triangles_.capacity() * sizeof(TriangleIndices);
}

template <typename Map>
Mesh& Mesh::mapVertices(const Map& map, const char* operation) {
  std::vector<Vec3> moved(vertices_.size());
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    moved[i] = map(vertices_[i]);
    if (!isFinite(moved[i]))
      fail(std::string(operation) + " takes vertex " + std::to_string(i) + " " +
           toString(vertices_[i]) + " to " + toString(moved[i]) +
           ", which is not finite; the mesh is unchanged");
  }
  vertices_ = std::move(moved);
  return *this;
}

Mesh& Mesh::translate(const Vec3& offset) {
  if (!isFinite(offset)) fail("translate: offset " + toString(offset) + " is not finite");
  return mapVertices([&](const Vec3& p) { return p + offset; }, "translate");
}

Mesh& Mesh::scale(double factor, const Vec3& pivot) {
  return stretch({factor, factor, factor}, pivot);
}

Mesh& Mesh::stretch(const Vec3& factors, const Vec3& pivot) {
  if (!isFinite(factors) || !(factors.x > 0.0 && factors.y > 0.0 && factors.z > 0.0))
    fail("scale factors " + toString(factors) + " must be finite and positive");
  if (!isFinite(pivot)) fail("scale: pivot " + toString(pivot) + " is not finite");
  return mapVertices(
      [&](const Vec3& p) {
        return Vec3{pivot.x + (p.x - pivot.x) * factors.x, pivot.y + (p.y - pivot.y) * factors.y,
                    pivot.z + (p.z - pivot.z) * factors.z};
      },
      "scale");
}

Mesh& Mesh::rotate(const Quaternion& rotation, const Vec3& pivot) {
  if (!isFinite(pivot)) fail("rotate: pivot " + toString(pivot) + " is not finite");
  return transform(RigidTransform::rotationAbout(
      Quaternion::fromComponents(rotation.w, rotation.x, rotation.y, rotation.z), pivot));
}

Mesh& Mesh::rotate(const Vec3& axis, double radians, const Vec3& pivot) {
  return rotate(Quaternion::fromAxisAngle(axis, radians), pivot);
}

Mesh& Mesh::rotate(const Mat3& rotation, const Vec3& pivot) {
  return rotate(Quaternion::fromMatrix(rotation), pivot);
}

Mesh& Mesh::transform(const RigidTransform& motion) {
  const Quaternion& q = motion.rotation;
  const Mat3 r = Quaternion::fromComponents(q.w, q.x, q.y, q.z).matrix();
  const Vec3 t = motion.translation;
  if (!isFinite(t)) fail("transform: translation " + toString(t) + " is not finite");
  return mapVertices([&](const Vec3& p) { return r * p + t; }, "transform");
}

}  // namespace delta
