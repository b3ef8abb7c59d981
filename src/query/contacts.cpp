#include "delta/query/contacts.h"

#include <algorithm>
#include <cmath>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/kernels/pair_results.h"

#include "detail/query_mesh_data.h"

namespace delta::contactdetection {
namespace {

/// Triangles of the second mesh handed to the kernels at once, and pruned as one box.
constexpr std::size_t kBlock = 64;
/// Triangle ids are 32-bit (ContactPoint).
constexpr std::size_t kMaxTriangles = std::size_t{1} << 32;
/// Tasks (one triangle against one block, at most kBlock kernel pairs, a few µs) per parallel
/// chunk: enough to amortise the chunk's scratch and scheduling, few enough to balance.
constexpr std::size_t kTaskGrain = 2;

/// The boxes of consecutive blocks of kBlock triangles.
std::vector<Aabb> blockBoxes(const TriangleSoA& mesh) {
  std::vector<Aabb> boxes((mesh.size() + kBlock - 1) / kBlock);
  for (std::size_t i = 0; i < mesh.size(); ++i)
    boxes[i / kBlock].extend(mesh.triangle(i).bounds());
  return boxes;
}

Aabb meshBox(const std::vector<Aabb>& blocks) {
  Aabb box;
  for (const Aabb& block : blocks)
    box.extend(block);
  return box;
}

/// The contact direction where the closest points coincide, from the faces (see contacts.h).
Vec3 faceDirection(const Triangle& first, const Triangle& second) noexcept {
  const Vec3 n1 = normalized(first.areaVector());
  const Vec3 n2 = normalized(second.areaVector());
  for (const Vec3& candidate : {n2 - n1, n2, -n1}) {
    const Vec3 unit = normalized(candidate);
    if (lengthSquared(unit) > 0.5) return unit;
  }
  return {0, 0, 1};
}

ContactPoint contactPoint(const Triangle& first, const Triangle& second, const Vec3& p,
                          const Vec3& q, bool intersect, std::size_t i, std::size_t j) {
  ContactPoint contact;
  contact.x = (p + q) * 0.5;
  contact.normal = p - contact.x;
  contact.distance = distance(p, q);
  contact.direction = normalized(p - q);
  if (!(lengthSquared(contact.direction) > 0.5)) contact.direction = faceDirection(first, second);
  contact.overlap = intersect;
  contact.first = static_cast<std::uint32_t>(i);
  contact.second = static_cast<std::uint32_t>(j);
  return contact;
}

/// One unit of parallel work: a triangle of the first mesh against a block of the second.
struct Task {
  std::uint32_t triangle;
  std::uint32_t block;
};

/// The (triangle, block) pairs whose boxes come within `reach` of each other, in (triangle,
/// block) order: blocks of the first mesh against blocks of the second, then each triangle of
/// a first block against the second blocks that block reaches. Listing the work first lets the
/// parallel loop hand out only pairs that reach the kernels, in even pieces.
std::vector<Task> tasksWithin(const TriangleSoA& first, const std::vector<Aabb>& firstBlocks,
                              const std::vector<Aabb>& secondBlocks, double reach) {
  std::vector<Task> tasks;
  std::vector<std::uint32_t> near;
  for (std::size_t a = 0; a < firstBlocks.size(); ++a) {
    near.clear();
    for (std::size_t b = 0; b < secondBlocks.size(); ++b)
      if (!apart(firstBlocks[a], secondBlocks[b], reach))
        near.push_back(static_cast<std::uint32_t>(b));
    if (near.empty()) continue;
    const std::size_t end = std::min((a + 1) * kBlock, first.size());
    for (std::size_t i = a * kBlock; i < end; ++i) {
      const Aabb box = first.triangle(i).bounds();
      for (std::uint32_t b : near)
        if (!apart(box, secondBlocks[b], reach))
          tasks.push_back({static_cast<std::uint32_t>(i), b});
    }
  }
  return tasks;
}

/// The contacts of one task's pairs, in id order.
void contactsOf(const Task& task, const TriangleSoA& first, const TriangleSoA& second,
                double epsilon, kernels::Solver solver, kernels::PairResults& results,
                std::vector<ContactPoint>& out) {
  const Triangle one = first.triangle(task.triangle);
  const double reach = 2.0 * epsilon;
  const std::size_t begin = std::size_t{task.block} * kBlock;
  const std::size_t end = std::min(begin + kBlock, second.size());
  kernels::distances(solver, one, second, begin, end, results);
  for (std::size_t k = 0; k < results.size(); ++k)
    if (results.distanceSquared(k) < reach * reach)
      out.push_back(contactPoint(one, second.triangle(begin + k), results.p(k), results.q(k),
                                 results.intersect(k), task.triangle, begin + k));
}

}  // namespace

std::vector<ContactPoint> contacts(const TriangleSoA& first, const TriangleSoA& second,
                                   double epsilon, kernels::Solver solver) {
  if (!std::isfinite(epsilon) || !(epsilon > 0.0))
    throw Error("contacts: epsilon = " + toString(epsilon) + " must be finite and positive");
  if (first.size() == 0 || second.size() == 0) throw Error("contacts: a mesh has no triangles");
  if (first.size() >= kMaxTriangles || second.size() >= kMaxTriangles)
    throw Error("contacts: a mesh has more triangles than 32-bit ids can name");
  const std::vector<Aabb> firstBlocks = blockBoxes(first), secondBlocks = blockBoxes(second);
  const Aabb firstBox = meshBox(firstBlocks), secondBox = meshBox(secondBlocks);
  // Boxes are compared with a slack far above the rounding of a kernel's distance (a few ulps of
  // the coordinates), so pruning never drops a pair the kernel would find closer than 2ε.
  const double slack =
      0x1p-36 * std::max({maxAbs(firstBox.lower), maxAbs(firstBox.upper), maxAbs(secondBox.lower),
                          maxAbs(secondBox.upper), firstBox.diagonal(), secondBox.diagonal()});
  const double reach = 2.0 * epsilon + slack;
  if (apart(firstBox, secondBox, reach)) return {};
  const std::vector<Task> tasks = tasksWithin(first, firstBlocks, secondBlocks, reach);

  // Chunks of kTaskGrain tasks each write their own slot; concatenated in order, the contacts
  // come sorted by (first, second) whatever thread ran which chunk.
  std::vector<std::vector<ContactPoint>> perChunk((tasks.size() + kTaskGrain - 1) / kTaskGrain);
  parallelFor(0, tasks.size(), kTaskGrain, [&](std::size_t begin, std::size_t end) {
    kernels::PairResults results(kBlock);
    std::vector<ContactPoint> out;  // filled locally: neighbouring slots share cache lines
    for (std::size_t t = begin; t < end; ++t)
      contactsOf(tasks[t], first, second, epsilon, solver, results, out);
    perChunk[begin / kTaskGrain] = std::move(out);
  });
  std::vector<ContactPoint> all;
  for (const std::vector<ContactPoint>& some : perChunk)
    all.insert(all.end(), some.begin(), some.end());
  return all;
}

std::vector<ContactPoint> contacts(const QueryMesh& first, const QueryMesh& second, double epsilon,
                                   kernels::Solver solver) {
  // In tree order the 64-triangle blocks are spatially compact whatever the file's triangle order
  // (a scattered order would leave every block box spanning the mesh); ids map back, then sort.
  const detail::QueryMeshData &a = first.data(), &b = second.data();
  std::vector<ContactPoint> found = contacts(a.sorted, b.sorted, epsilon, solver);
  for (ContactPoint& contact : found) {
    contact.first = a.order[contact.first];
    contact.second = b.order[contact.second];
  }
  std::sort(found.begin(), found.end(), [](const ContactPoint& x, const ContactPoint& y) {
    return x.first != y.first ? x.first < y.first : x.second < y.second;
  });
  if (!first.closed() || !second.closed()) return found;
  // x lies within ε of both surfaces, so the nearest-triangle searches stop within 2ε.
  const double limit = 4.0 * epsilon * epsilon;
  const auto inside = [limit](const QueryMesh& mesh, const Vec3& x) {
    const detail::Nearest nearest = detail::nearestTriangle(mesh.data(), x, limit);
    return nearest.found() && detail::insideAt(mesh.data(), x, nearest);
  };
  parallelFor(0, found.size(), kBlock, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      if (!found[i].overlap)
        found[i].overlap = inside(first, found[i].x) && inside(second, found[i].x);
  });
  return found;
}

}  // namespace delta::contactdetection
