// FCL 0.7 as the mesh–mesh peer: two BVHModel<OBBRSSd> placed by transforms, fcl::distance for
// the minimum distance and fcl::collide for the intersecting triangle pairs.
#include <fcl/config.h>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "peers.h"

namespace delta::bench {
namespace {

using Model = fcl::BVHModel<fcl::OBBRSSd>;

std::shared_ptr<Model> buildModel(const Mesh& mesh) {
  std::vector<fcl::Vector3d> vertices;
  vertices.reserve(mesh.vertexCount());
  for (const Vec3& v : mesh.vertices())
    vertices.emplace_back(v.x, v.y, v.z);
  std::vector<fcl::Triangle> triangles;
  triangles.reserve(mesh.triangleCount());
  for (const TriangleIndices& t : mesh.triangles())
    triangles.emplace_back(t[0], t[1], t[2]);
  auto model = std::make_shared<Model>();
  if (model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(vertices.size())) !=
          fcl::BVH_OK ||
      model->addSubModel(vertices, triangles) != fcl::BVH_OK || model->endModel() != fcl::BVH_OK)
    throw std::runtime_error("FCL: building the BVHModel<OBBRSSd> failed");
  return model;
}

fcl::Transform3d transform(const RigidTransform& motion) {
  const Mat3 r = motion.rotation.matrix();
  fcl::Matrix3d rotation;
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 3; ++column)
      rotation(row, column) = r(row, column);
  fcl::Transform3d placed = fcl::Transform3d::Identity();
  placed.linear() = rotation;
  placed.translation() =
      fcl::Vector3d(motion.translation.x, motion.translation.y, motion.translation.z);
  return placed;
}

class FclPair final : public FclMeshPair {
 public:
  FclPair(const Mesh& first, const Mesh& second) {
    const std::size_t heapBefore = heapBytesInUse();
    first_ = buildModel(first);
    second_ = buildModel(second);
    const std::size_t heapAfter = heapBytesInUse();
    bytes_ = heapAfter > heapBefore ? heapAfter - heapBefore : 0;
  }

  std::size_t memoryBytes() const noexcept override { return bytes_; }

  Distance minimumDistance(const RigidTransform& secondMotion) const override {
    const fcl::CollisionObjectd a(first_, fcl::Transform3d::Identity());
    const fcl::CollisionObjectd b(second_, transform(secondMotion));
    const fcl::DistanceRequestd request;
    fcl::DistanceResultd result;
    fcl::distance(&a, &b, request, result);
    return {result.min_distance, static_cast<std::uint32_t>(result.b1),
            static_cast<std::uint32_t>(result.b2)};
  }

  Collision collide(const RigidTransform& secondMotion, std::size_t maxContacts) const override {
    const fcl::CollisionObjectd a(first_, fcl::Transform3d::Identity());
    const fcl::CollisionObjectd b(second_, transform(secondMotion));
    const fcl::CollisionRequestd request(maxContacts, true);
    fcl::CollisionResultd result;
    fcl::collide(&a, &b, request, result);
    std::vector<fcl::Contactd> contacts;
    result.getContacts(contacts);
    Collision collision;
    collision.contacts = contacts.size();
    for (const fcl::Contactd& contact : contacts)
      collision.pairs.emplace_back(static_cast<std::uint32_t>(contact.b1),
                                   static_cast<std::uint32_t>(contact.b2));
    std::sort(collision.pairs.begin(), collision.pairs.end());
    collision.pairs.erase(std::unique(collision.pairs.begin(), collision.pairs.end()),
                          collision.pairs.end());
    return collision;
  }

 private:
  std::shared_ptr<Model> first_, second_;
  std::size_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<FclMeshPair> makeFclPair(const Mesh& first, const Mesh& second) {
  return std::make_unique<FclPair>(first, second);
}

const char* fclVersion() noexcept {
  return FCL_VERSION;
}

}  // namespace delta::bench
