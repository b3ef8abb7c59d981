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

#include "detail/placement.h"
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

/// Whether the ball of `radius` about `center` lies further than `gap` from `box`: the distance
/// from the centre to the box (not the box around the ball, which meets every box along its
/// diagonals: a sphere of radius 1e3 beside an icosphere, approached along a diagonal, ran a
/// kernel on every triangle). `gap` must cover a few ulps of the coordinates, the radius and the
/// box (kPruneUlps does).
bool ballApart(const Vec3& center, double radius, const Aabb& box, double gap) noexcept {
  const double dx = std::max({box.lower.x - center.x, center.x - box.upper.x, 0.0});
  const double dy = std::max({box.lower.y - center.y, center.y - box.upper.y, 0.0});
  const double dz = std::max({box.lower.z - center.z, center.z - box.upper.z, 0.0});
  const double reach = radius + gap;
  return dx * dx + dy * dy + dz * dz > reach * reach;
}

/// Whether the ball lies further than `gap` from a node's oriented slab (query_mesh_data.h): the
/// long slivers of a turned CAD cylinder have boxes as wide as they are long, and a sphere
/// 1.5e-3 above its cap's centre met the boxes of every wedge (5.8 ms a sphere at 100,000
/// segments); the cap's slabs are as thin as the cap.
bool ballApart(const Vec3& center, double radius, const detail::NodeSlab& slab,
               double gap) noexcept {
  const double height = dot(slab.normal, center);
  return height < slab.low - (radius + gap) || height > slab.high + (radius + gap);
}

/// A triangle of a prepared mesh near a sphere: its prepared (tree) index, its id, the kernel's
/// answer, and the triangle made ready for the kernel (which a SphereContactCache keeps).
struct NearTriangle {
  std::uint32_t index;
  std::uint32_t id;
  kernels::SphereContactResult result;
  kernels::PreparedTriangle prepared;
};

/// The triangles of a prepared mesh (its prepared frame) whose kernel gap to one (validated)
/// sphere is below `reach`, found through its tree: the nodes whose boxes and slabs, and then
/// the triangles whose boxes, come within reach of the ball, with the same slack as above (the
/// tree's boxes and slabs are grown by the mesh's own slack on top), so no triangle the kernel
/// would report is skipped. In id order.
void nearTriangles(const Sphere& sphere, const detail::QueryMeshData& data, double scale,
                   double reach, std::vector<NearTriangle>& out) {
  const Vec3 extent{sphere.radius, sphere.radius, sphere.radius};
  const Aabb box{sphere.center - extent, sphere.center + extent};  // a first, cheaper test
  const double gap = reach + kPruneUlps * (maxAbs(sphere.center) + sphere.radius + scale);
  thread_local std::vector<std::pair<std::size_t, std::size_t>> stack;  // (level, node)
  stack.clear();
  stack.emplace_back(data.levels.size() - 1, 0);
  out.clear();
  while (!stack.empty()) {
    const auto [level, node] = stack.back();
    stack.pop_back();
    const Aabb& nodeBox = data.levels[level][node];
    if (apart(box, nodeBox, gap) || ballApart(sphere.center, sphere.radius, nodeBox, gap) ||
        ballApart(sphere.center, sphere.radius, data.slabs[level][node], gap))
      continue;
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
      const Aabb bounds = triangle.bounds();
      if (apart(box, bounds, gap) || ballApart(sphere.center, sphere.radius, bounds, gap)) continue;
      const kernels::PreparedTriangle prepared(triangle);
      const kernels::SphereContactResult r = kernels::sphereTriangle(sphere, prepared);
      if (r.gap < reach) out.push_back({static_cast<std::uint32_t>(k), data.order[k], r, prepared});
    }
  }
  std::sort(out.begin(), out.end(),
            [](const NearTriangle& x, const NearTriangle& y) { return x.id < y.id; });
}

/// The contacts of one (validated) sphere with the triangles of a prepared mesh (its prepared
/// frame): nearTriangles within 2ε, in id order.
void contactsOf(const Sphere& sphere, std::size_t index, const detail::QueryMeshData& data,
                double scale, double epsilon, std::vector<ContactPoint>& out) {
  thread_local std::vector<NearTriangle> near;
  nearTriangles(sphere, data, scale, 2.0 * epsilon, near);
  for (const NearTriangle& triangle : near)
    out.push_back(
        sphereContactPoint(triangle.result, static_cast<std::uint32_t>(index), triangle.id));
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
  detail::requireTrianglesSpan(mesh, "sphereContacts: the mesh");
  checkSpheres(spheres);
  if (spheres.empty()) return {};
  const detail::QueryMeshData& data = mesh.data();
  const double scale = std::max(maxAbs(data.bounds.lower), maxAbs(data.bounds.upper));  // finite
  return everySphere(spheres, [&](std::size_t i, std::vector<ContactPoint>& out) {
    contactsOf(spheres[i], i, data, scale, epsilon, out);
  });
}

void sphereContacts(const Sphere& sphere, const QueryMesh& mesh, double epsilon,
                    SphereContactCache& cache, std::vector<ContactPoint>& out) {
  checkEpsilon(epsilon);
  detail::requireTrianglesSpan(mesh, "sphereContacts: the mesh");
  checkSphere(sphere, 0);
  out.clear();
  const detail::QueryMeshData& data = mesh.data();
  const double reach = 2.0 * epsilon;
  const bool same = cache.valid_ && cache.meshData_.get() == &data && cache.epsilon_ == epsilon &&
                    cache.radius_ == sphere.radius;
  const double move = same ? distance(sphere.center, cache.center_) : 0.0;
  if (same && move <= cache.budget_) {
    // A kept triangle whose gap, less the move and the rounding, is 2ε or more is still apart;
    // the others go to the kernel as the tree would hand them over, in index order.
    const double nearer = reach + move + cache.allowance_;
    for (const SphereContactCache::KeptTriangle& kept : cache.triangles_) {
      if (!(kept.gap < nearer)) continue;
      const kernels::SphereContactResult r = kernels::sphereTriangle(sphere, kept.triangle);
      if (r.gap < reach) out.push_back(sphereContactPoint(r, 0, data.order[kept.index]));
    }
    ++cache.reused_;
    return;
  }
  const double scale = std::max(maxAbs(data.bounds.lower), maxAbs(data.bounds.upper));  // finite
  const double skin = cache.skin_;
  if (!(std::isfinite(skin) && skin > 0.0)) {
    contactsOf(sphere, 0, data, scale, epsilon, out);
    ++cache.made_;
    return;
  }
  // The triangles within 2ε + skin, and of those the ones within 2ε (the kernel's own test).
  thread_local std::vector<NearTriangle> near;
  nearTriangles(sphere, data, scale, reach + skin, near);
  cache.triangles_.clear();
  for (const NearTriangle& triangle : near) {
    cache.triangles_.push_back({triangle.index, triangle.result.gap, triangle.prepared});
    if (triangle.result.gap < reach)
      out.push_back(sphereContactPoint(triangle.result, 0, triangle.id));
  }
  cache.valid_ = true;
  cache.meshData_ = mesh.sharedData();
  cache.epsilon_ = epsilon;
  cache.radius_ = sphere.radius;
  cache.center_ = sphere.center;
  // The kernel's gaps at both centres and the move round to a few ulps of the coordinates;
  // allowed 2⁻³⁶ of the largest, as the mesh pairs' cache does.
  cache.allowance_ = 0x1p-36 * (maxAbs(sphere.center) + sphere.radius + scale);
  cache.budget_ = skin - cache.allowance_;
  ++cache.made_;
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
