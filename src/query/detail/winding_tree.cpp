#include "winding_tree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "delta/core/parallel.h"
#include "delta/query/winding_number.h"

#include "query_mesh_data.h"

namespace delta::detail {
namespace {

constexpr double kFourPi = 4.0 * std::numbers::pi;

/// A node's radius is grown by this (relative) for the rounding of the centres and distances
/// it was made from.
constexpr double kRadiusGrowth = 1.0 + 0x1p-40;

/// The moments of the leaf holding sorted triangles [from, to).
WindingNode leafMoments(const QueryMeshData& mesh, std::size_t from, std::size_t to) noexcept {
  WindingNode node;
  Vec3 weighted{};
  Vec3 lower = mesh.triangle(from).a, upper = lower;
  for (std::size_t k = from; k < to; ++k) {
    const Triangle t = mesh.triangle(k);
    const Vec3 areaVector = t.areaVector() * 0.5;
    const double area = length(areaVector);
    node.normal += areaVector;
    node.area += area;
    weighted += t.centroid() * area;
    for (const Vec3& v : {t.a, t.b, t.c}) {
      lower = {std::min(lower.x, v.x), std::min(lower.y, v.y), std::min(lower.z, v.z)};
      upper = {std::max(upper.x, v.x), std::max(upper.y, v.y), std::max(upper.z, v.z)};
    }
  }
  // Every triangle degenerate: no moments (the node contributes 0), any centre.
  node.centre = node.area > 0.0 ? weighted / node.area : (lower + upper) * 0.5;
  for (std::size_t k = from; k < to; ++k) {
    const Triangle t = mesh.triangle(k);
    for (const Vec3& v : {t.a, t.b, t.c})
      node.radius = std::max(node.radius, length(v - node.centre));
    const Vec3 offset = t.centroid() - node.centre, areaVector = t.areaVector() * 0.5;
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t j = 0; j < 3; ++j)
        node.tensor[3 * i + j] += offset[i] * areaVector[j];
  }
  node.radius *= kRadiusGrowth;
  return node;
}

/// The moments of a parent from its children's: T about the parent's centre is Σ (T_c + (c_c −
/// c) ⊗ N_c), and every vertex lies within max(|c_c − c| + r_c) of c.
WindingNode parentMoments(const WindingNode* children, std::size_t count) noexcept {
  WindingNode node;
  Vec3 weighted{}, lower = children[0].centre, upper = lower;
  for (std::size_t c = 0; c < count; ++c) {
    node.normal += children[c].normal;
    node.area += children[c].area;
    weighted += children[c].centre * children[c].area;
    const Vec3& v = children[c].centre;
    lower = {std::min(lower.x, v.x), std::min(lower.y, v.y), std::min(lower.z, v.z)};
    upper = {std::max(upper.x, v.x), std::max(upper.y, v.y), std::max(upper.z, v.z)};
  }
  node.centre = node.area > 0.0 ? weighted / node.area : (lower + upper) * 0.5;
  for (std::size_t c = 0; c < count; ++c) {
    const Vec3 shift = children[c].centre - node.centre;
    node.radius = std::max(node.radius, length(shift) + children[c].radius);
    for (std::size_t i = 0; i < 3; ++i)
      for (std::size_t j = 0; j < 3; ++j)
        node.tensor[3 * i + j] += children[c].tensor[3 * i + j] + shift[i] * children[c].normal[j];
  }
  node.radius *= kRadiusGrowth;
  return node;
}

/// The sign of the mesh's signed volume about its box's centre, on coordinates scaled by a
/// power of two to about 1 (no product of degree 3 under- or overflows); +1 where it is 0.
double volumeSign(const QueryMeshData& mesh) noexcept {
  const Vec3 origin = mesh.bounds.center();
  const double size = std::max(maxAbs(mesh.bounds.extent()), 0x1p-1000);
  const double scale = std::ldexp(1.0, -std::ilogb(size));
  double sixTimesVolume = 0.0;
  for (std::size_t k = 0; k < mesh.size(); ++k) {
    const Triangle t = mesh.triangle(k);
    sixTimesVolume +=
        dot((t.a - origin) * scale, cross((t.b - origin) * scale, (t.c - origin) * scale));
  }
  return sixTimesVolume < 0.0 ? -1.0 : 1.0;
}

}  // namespace

WindingTree buildWindingTree(const QueryMeshData& mesh) {
  WindingTree tree;
  tree.orientation = mesh.closed ? mesh.orientation : volumeSign(mesh);
  tree.levels.resize(mesh.levels.size());
  tree.levels[0].resize(mesh.levels[0].size());
  parallelFor(0, tree.levels[0].size(), 256, [&](std::size_t begin, std::size_t end) {
    for (std::size_t leaf = begin; leaf < end; ++leaf)
      tree.levels[0][leaf] =
          leafMoments(mesh, leaf * kFanout, std::min((leaf + 1) * kFanout, mesh.size()));
  });
  for (std::size_t l = 1; l < tree.levels.size(); ++l) {
    const std::vector<WindingNode>& children = tree.levels[l - 1];
    std::vector<WindingNode>& parents = tree.levels[l];
    parents.resize(mesh.levels[l].size());
    parallelFor(0, parents.size(), 256, [&](std::size_t begin, std::size_t end) {
      for (std::size_t i = begin; i < end; ++i) {
        const std::size_t first = i * kFanout;
        parents[i] =
            parentMoments(&children[first], std::min(first + kFanout, children.size()) - first);
      }
    });
  }
  return tree;
}

double hierarchicalWindingNumber(const QueryMeshData& mesh, const WindingTree& tree,
                                 const Vec3& point, double beta, double& errorBound) noexcept {
  // Solid angles (times 4π) summed in a fixed order: the same answer on any thread.
  double solidAngles = 0.0, bound = 0.0;
  struct Entry {
    std::uint32_t level, index;
  };
  std::array<Entry, 64 * kFanout> stack;
  std::size_t top = 0;
  stack[top++] = {static_cast<std::uint32_t>(tree.levels.size() - 1), 0};
  while (top > 0) {
    const Entry entry = stack[--top];
    const WindingNode& node = tree.levels[entry.level][entry.index];
    if (!(node.area > 0.0)) continue;  // degenerate triangles contribute 0
    const Vec3 u = node.centre - point;
    const double d = length(u);
    if (d > beta * node.radius) {
      const Vec3 unit = u / d;
      const double* t = node.tensor;
      const double trace = t[0] + t[4] + t[8];
      const double quadratic = unit.x * (t[0] * unit.x + t[1] * unit.y + t[2] * unit.z) +
                               unit.y * (t[3] * unit.x + t[4] * unit.y + t[5] * unit.z) +
                               unit.z * (t[6] * unit.x + t[7] * unit.y + t[8] * unit.z);
      solidAngles += dot(unit, node.normal) / (d * d) + (trace - 3.0 * quadratic) / (d * d * d);
      const double gap = d - node.radius, ratio = node.radius / gap;
      bound += 3.0 * (node.area / (gap * gap)) * (ratio * ratio);
      continue;
    }
    const std::size_t first = std::size_t{entry.index} * kFanout;
    if (entry.level == 0) {
      for (std::size_t k = first; k < std::min(first + kFanout, mesh.size()); ++k)
        solidAngles += solidAngle(mesh.triangle(k), point);
      continue;
    }
    const std::size_t last = std::min(first + kFanout, tree.levels[entry.level - 1].size());
    // Children pushed last first: popped in index order (a fixed order of the sum).
    for (std::size_t c = last; c-- > first;)
      stack[top++] = {entry.level - 1, static_cast<std::uint32_t>(c)};
  }
  errorBound = bound / kFourPi;
  return solidAngles / kFourPi;
}

double exactWindingNumber(const QueryMeshData& mesh, const Vec3& point) noexcept {
  return windingNumber(
      mesh.size(), [&mesh](std::size_t k) { return mesh.triangle(k); }, point);
}

WindingSign windingSign(const QueryMeshData& mesh, const Vec3& point, double tolerance) noexcept {
  const WindingTree& tree = mesh.windingTree();
  // A sum of a few thousand solid angles rounds by far less than this (in winding units).
  constexpr double kRounding = 1e-9;
  WindingSign sign;
  for (const double beta : {4.0, 10.0}) {
    double errorBound = 0.0;
    sign.winding =
        hierarchicalWindingNumber(mesh, tree, point, beta, errorBound) * tree.orientation;
    const double off = std::abs(sign.winding - 0.5), slack = errorBound + kRounding;
    if (off > tolerance + slack) {
      sign.inside = sign.winding > 0.5;
      return sign;
    }
    // Within the tolerance for certain, and on a certain side of ½: ambiguous, decided without
    // the exact sum (beside an open sheet every point of one side is; the O(n) sum for each made
    // a grid around a sheet of 33,000 triangles take 49 s).
    if (off > slack && off + slack < tolerance) {
      sign.inside = sign.winding > 0.5;
      sign.ambiguous = true;
      return sign;
    }
  }
  sign.winding = exactWindingNumber(mesh, point) * tree.orientation;
  sign.inside = sign.winding > 0.5;
  sign.ambiguous = std::abs(sign.winding - 0.5) <= tolerance;
  return sign;
}

}  // namespace delta::detail
