#include "delta/query/contacts.h"

#include <algorithm>
#include <cmath>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/kernels/pair_results.h"

namespace delta::contactdetection {
namespace {

/// Triangles of the second mesh handed to the kernels at once, and pruned as one box.
constexpr std::size_t kBlock = 64;
/// Triangles of the first mesh per parallel chunk.
constexpr std::size_t kGrain = 4;

Aabb boxOf(const Triangle& t) noexcept {
  Aabb box;
  box.extend(t.a);
  box.extend(t.b);
  box.extend(t.c);
  return box;
}

/// Whether two boxes are at least `gap` apart along some axis (then every pair of their points
/// is at least `gap` apart).
bool apart(const Aabb& a, const Aabb& b, double gap) noexcept {
  for (std::size_t axis = 0; axis < 3; ++axis)
    if (a.lower[axis] - b.upper[axis] >= gap || b.lower[axis] - a.upper[axis] >= gap) return true;
  return false;
}

/// The boxes of consecutive blocks of kBlock triangles.
std::vector<Aabb> blockBoxes(const TriangleSoA& mesh) {
  std::vector<Aabb> boxes((mesh.size() + kBlock - 1) / kBlock);
  for (std::size_t i = 0; i < mesh.size(); ++i)
    boxes[i / kBlock].extend(boxOf(mesh.triangle(i)));
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

/// The contacts of triangle `i` of `first` with every triangle of `second`, in id order.
void contactsOf(std::size_t i, const TriangleSoA& first, const TriangleSoA& second,
                const std::vector<Aabb>& blocks, double epsilon, kernels::Solver solver,
                kernels::PairResults& results, std::vector<ContactPoint>& out) {
  const Triangle one = first.triangle(i);
  const Aabb box = boxOf(one);
  const double reach = 2.0 * epsilon;
  for (std::size_t block = 0; block < blocks.size(); ++block) {
    if (apart(box, blocks[block], reach)) continue;
    const std::size_t begin = block * kBlock;
    const std::size_t end = std::min(begin + kBlock, second.size());
    kernels::distances(solver, one, second, begin, end, results);
    for (std::size_t k = 0; k < results.size(); ++k)
      if (results.distanceSquared(k) < reach * reach)
        out.push_back(contactPoint(one, second.triangle(begin + k), results.p(k), results.q(k),
                                   results.intersect(k), i, begin + k));
  }
}

}  // namespace

std::vector<ContactPoint> contacts(const TriangleSoA& first, const TriangleSoA& second,
                                   double epsilon, kernels::Solver solver) {
  if (!std::isfinite(epsilon) || !(epsilon > 0.0))
    throw Error("contacts: epsilon = " + toString(epsilon) + " must be finite and positive");
  if (first.size() == 0 || second.size() == 0) throw Error("contacts: a mesh has no triangles");
  const std::vector<Aabb> blocks = blockBoxes(second);
  const Aabb firstBox = meshBox(blockBoxes(first));
  if (apart(firstBox, meshBox(blocks), 2.0 * epsilon)) return {};

  std::vector<std::vector<ContactPoint>> perTriangle(first.size());
  parallelFor(0, first.size(), kGrain, [&](std::size_t begin, std::size_t end) {
    kernels::PairResults results(kBlock);
    for (std::size_t i = begin; i < end; ++i)
      contactsOf(i, first, second, blocks, epsilon, solver, results, perTriangle[i]);
  });
  std::vector<ContactPoint> all;
  for (const std::vector<ContactPoint>& some : perTriangle)
    all.insert(all.end(), some.begin(), some.end());
  return all;
}

}  // namespace delta::contactdetection
