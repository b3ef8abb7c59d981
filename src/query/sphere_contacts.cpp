#include "delta/query/sphere_contacts.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/kernels/sphere.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/query/query_mesh.h"

#include "detail/query_mesh_data.h"

namespace delta::contactdetection {
namespace {

/// Consecutive triangles pruned as one box (as for mesh–mesh contacts).
constexpr std::size_t kBlock = 64;
/// Spheres per parallel chunk: each costs a box test per block and a few kernels.
constexpr std::size_t kGrain = 32;
/// The prune's slack, in units of the coordinates' magnitude: box corners c ± r and their
/// differences round, and so does the kernel's gap (a few ulps of |c − a|, the edges and r), so
/// a box test that is exact to within this never skips a triangle the kernel would report.
constexpr double kPruneUlps = 32.0 * std::numeric_limits<double>::epsilon();

/// The boxes of consecutive blocks of kBlock triangles, and the mesh's box.
struct MeshBoxes {
  std::vector<Aabb> blocks;
  Aabb mesh;
  double scale = 0.0;  ///< the largest absolute coordinate of the mesh
};

MeshBoxes boxesOf(const TriangleSoA& mesh) {
  MeshBoxes boxes;
  boxes.blocks.resize((mesh.size() + kBlock - 1) / kBlock);
  for (std::size_t i = 0; i < mesh.size(); ++i)
    boxes.blocks[i / kBlock].extend(mesh.triangle(i).bounds());
  for (const Aabb& block : boxes.blocks)
    boxes.mesh.extend(block);
  boxes.scale = std::fmax(maxAbs(boxes.mesh.lower), maxAbs(boxes.mesh.upper));
  return boxes;
}

void checkEpsilon(double epsilon) {
  if (!std::isfinite(epsilon) || !(epsilon > 0.0))
    throw Error("sphereContacts: epsilon = " + toString(epsilon) + " must be finite and positive");
}

void checkEpsilonAndMesh(double epsilon, const TriangleSoA& mesh) {
  checkEpsilon(epsilon);
  if (mesh.size() == 0) throw Error("sphereContacts: the mesh has no triangles");
  if (mesh.size() > std::numeric_limits<std::uint32_t>::max())
    throw Error("sphereContacts: the mesh has " + std::to_string(mesh.size()) +
                " triangles, more than 32-bit ids reach");
  checkMeshScale(mesh, "sphereContacts: the mesh");
}

void checkSphere(const Sphere& sphere, std::size_t index) {
  if (!isFinite(sphere.center))
    throw Error("sphereContacts: sphere " + std::to_string(index) +
                " center = " + toString(sphere.center) + " must be finite");
  if (!std::isfinite(sphere.radius) || !(sphere.radius > 0.0))
    throw Error("sphereContacts: sphere " + std::to_string(index) +
                " radius = " + toString(sphere.radius) + " must be finite and positive");
  const Vec3 reach{sphere.radius, sphere.radius, sphere.radius};
  const Aabb box{sphere.center - reach, sphere.center + reach};
  if (boxInCoordinateRange(box)) return;  // the message only for a sphere out of range
  checkCoordinateRange(box, "sphereContacts: sphere " + std::to_string(index) + " (center " +
                                toString(sphere.center) + ", radius " + toString(sphere.radius) +
                                ")");
}

void checkSpheres(std::span<const Sphere> spheres) {
  if (spheres.size() > std::numeric_limits<std::uint32_t>::max())
    throw Error("sphereContacts: " + std::to_string(spheres.size()) +
                " spheres, more than 32-bit ids reach");
  for (std::size_t i = 0; i < spheres.size(); ++i)
    checkSphere(spheres[i], i);
}

/// The contacts of one (validated) sphere with every triangle of `mesh`, in id order.
void contactsOf(const Sphere& sphere, std::size_t index, const TriangleSoA& mesh,
                const MeshBoxes& boxes, double epsilon, std::vector<ContactPoint>& out) {
  const Vec3 extent{sphere.radius, sphere.radius, sphere.radius};
  const Aabb box{sphere.center - extent, sphere.center + extent};
  const double reach = 2.0 * epsilon;
  const double slack = kPruneUlps * (maxAbs(sphere.center) + sphere.radius + boxes.scale);
  if (apart(box, boxes.mesh, reach + slack)) return;
  for (std::size_t block = 0; block < boxes.blocks.size(); ++block) {
    if (apart(box, boxes.blocks[block], reach + slack)) continue;
    const std::size_t end = std::min((block + 1) * kBlock, mesh.size());
    for (std::size_t j = block * kBlock; j < end; ++j) {
      const kernels::SphereContactResult r = kernels::sphereTriangle(sphere, mesh.triangle(j));
      if (r.gap < reach)
        out.push_back(sphereContactPoint(r, static_cast<std::uint32_t>(index),
                                         static_cast<std::uint32_t>(j)));
    }
  }
}

/// The contacts of one (validated) sphere with the triangles of a prepared mesh (its prepared
/// frame), found through its tree: the nodes and then the triangles whose boxes come within
/// reach of the sphere's box, with the same slack as above (the tree's boxes are grown by the
/// mesh's own slack on top), so no triangle the kernel would report is skipped. In id order.
void contactsOf(const Sphere& sphere, std::size_t index, const detail::QueryMeshData& data,
                double scale, double epsilon, std::vector<ContactPoint>& out) {
  const Vec3 extent{sphere.radius, sphere.radius, sphere.radius};
  const Aabb box{sphere.center - extent, sphere.center + extent};
  const double reach = 2.0 * epsilon;
  const double gap = reach + kPruneUlps * (maxAbs(sphere.center) + sphere.radius + scale);
  thread_local std::vector<std::pair<std::size_t, std::size_t>> stack;  // (level, node)
  stack.clear();
  stack.emplace_back(data.levels.size() - 1, 0);
  const std::size_t first = out.size();
  while (!stack.empty()) {
    const auto [level, node] = stack.back();
    stack.pop_back();
    if (apart(box, data.levels[level][node], gap)) continue;
    const std::size_t from = node * detail::kFanout;
    if (level > 0) {
      const std::size_t to = std::min(from + detail::kFanout, data.levels[level - 1].size());
      for (std::size_t child = from; child < to; ++child)
        stack.emplace_back(level - 1, child);
      continue;
    }
    const std::size_t to = std::min(from + detail::kFanout, data.size());
    for (std::size_t k = from; k < to; ++k) {
      const Triangle triangle = data.triangle(k);
      if (apart(box, triangle.bounds(), gap)) continue;
      const kernels::SphereContactResult r = kernels::sphereTriangle(sphere, triangle);
      if (r.gap < reach)
        out.push_back(sphereContactPoint(r, static_cast<std::uint32_t>(index), data.order[k]));
    }
  }
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(),
            [](const ContactPoint& x, const ContactPoint& y) { return x.second < y.second; });
}

/// The contacts of every sphere, each found by `contactsOf(sphere, index, out)`, in sphere order.
template <class ContactsOf>
std::vector<ContactPoint> everySphere(std::span<const Sphere> spheres,
                                      const ContactsOf& contactsOf) {
  // One list per chunk of kGrain spheres, filled in sphere order: chunk k starts at sphere
  // k·kGrain (a serial run hands the whole range to chunk 0, still in order).
  std::vector<std::vector<ContactPoint>> perChunk((spheres.size() + kGrain - 1) / kGrain);
  parallelFor(0, spheres.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    std::vector<ContactPoint>& out = perChunk[begin / kGrain];
    for (std::size_t i = begin; i < end; ++i)
      contactsOf(i, out);
  });
  return detail::joined<ContactPoint>(perChunk);
}

}  // namespace

std::vector<ContactPoint> sphereContacts(const Sphere& sphere, const TriangleSoA& mesh,
                                         double epsilon) {
  checkEpsilonAndMesh(epsilon, mesh);
  checkSphere(sphere, 0);
  std::vector<ContactPoint> found;
  contactsOf(sphere, 0, mesh, boxesOf(mesh), epsilon, found);
  return found;
}

std::vector<ContactPoint> sphereContacts(std::span<const Sphere> spheres, const TriangleSoA& mesh,
                                         double epsilon) {
  checkEpsilonAndMesh(epsilon, mesh);
  checkSpheres(spheres);
  if (spheres.empty()) return {};
  const MeshBoxes boxes = boxesOf(mesh);
  return everySphere(spheres, [&](std::size_t i, std::vector<ContactPoint>& out) {
    contactsOf(spheres[i], i, mesh, boxes, epsilon, out);
  });
}

std::vector<ContactPoint> sphereContacts(std::span<const Sphere> spheres, const QueryMesh& mesh,
                                         double epsilon) {
  checkEpsilon(epsilon);  // a QueryMesh has triangles, 32-bit ids, coordinates in range
  checkSpheres(spheres);
  if (spheres.empty()) return {};
  const detail::QueryMeshData& data = mesh.data();
  const double scale = std::fmax(maxAbs(data.bounds.lower), maxAbs(data.bounds.upper));
  return everySphere(spheres, [&](std::size_t i, std::vector<ContactPoint>& out) {
    contactsOf(spheres[i], i, data, scale, epsilon, out);
  });
}

ContactPoint sphereContactPoint(const kernels::SphereContactResult& result, std::uint32_t first,
                                std::uint32_t second) noexcept {
  ContactPoint contact;
  contact.x = (result.p + result.q) * 0.5;
  contact.normal = result.p - contact.x;
  contact.direction = result.normal;
  contact.distance = std::fabs(result.gap);
  contact.overlap = result.overlap;
  contact.first = first;
  contact.second = second;
  return contact;
}

}  // namespace delta::contactdetection
