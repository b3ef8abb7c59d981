#include "delta/query/query_mesh.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <span>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/mesh/mass_properties.h"

#include "detail/morton.h"
#include "detail/placement.h"
#include "detail/query_mesh_data.h"

namespace delta {
namespace {

/// The triangles being ordered: their centroids (the split key) and boxes (the split cost), and
/// the ids three times, each range of a node sorted by centroid along x, y and z.
struct TreeBuild {
  std::vector<Vec3> centroids;
  std::vector<Aabb> boxes;
  std::array<std::vector<std::uint32_t>, 3> sorted;
  std::vector<std::uint8_t> left;      ///< per id: on the left of the split being made
  std::vector<std::uint32_t> scratch;  ///< for the stable partitions, at the range's positions
};

/// Surface area heuristic: half a box's surface.
double halfArea(const Aabb& box) noexcept {
  const Vec3 e = box.extent();
  return e.x * e.y + e.y * e.z + e.z * e.x;
}

/// Orders the range [begin, end) so that every aligned run of `run` ids (the children of a node)
/// is spatially compact: binary splits at run boundaries, each at the axis and boundary of least
/// cost Σ area × triangles over its two sides (the surface area heuristic), until the ranges are
/// single runs. The three sorted lists are split alike (stable), so each stays sorted: O(n) a
/// split instead of a sort.
void splitIntoRuns(TreeBuild& build, std::size_t begin, std::size_t end, std::size_t run) {
  if (end - begin <= run) return;
  const std::size_t runs = (end - begin + run - 1) / run;
  double bestCost = std::numeric_limits<double>::infinity();
  std::size_t bestAxis = 0, bestRuns = (runs + 1) / 2;
  std::array<double, detail::kFanout + 1> leftArea{};
  std::array<Aabb, detail::kFanout> runBoxes;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const std::vector<std::uint32_t>& ids = build.sorted[axis];
    for (std::size_t k = 0; k < runs; ++k) {
      Aabb box;
      for (std::size_t t = begin + k * run; t < std::min(begin + (k + 1) * run, end); ++t)
        box.extend(build.boxes[ids[t]]);
      runBoxes[k] = box;
    }
    Aabb box;
    for (std::size_t k = 0; k + 1 < runs; ++k) {
      box.extend(runBoxes[k]);
      leftArea[k + 1] = halfArea(box);
    }
    box = Aabb{};
    for (std::size_t k = runs - 1; k >= 1; --k) {
      box.extend(runBoxes[k]);
      const double left = static_cast<double>(k * run);
      const double cost =
          leftArea[k] * left + halfArea(box) * (static_cast<double>(end - begin) - left);
      if (cost < bestCost) {
        bestCost = cost;
        bestAxis = axis;
        bestRuns = k;
      }
    }
  }
  const std::size_t middle = begin + bestRuns * run;
  for (std::size_t t = begin; t < end; ++t)
    build.left[build.sorted[bestAxis][t]] = t < middle;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    if (axis == bestAxis) continue;
    std::vector<std::uint32_t>& ids = build.sorted[axis];
    std::size_t l = begin, r = begin;
    for (std::size_t t = begin; t < end; ++t)
      if (build.left[ids[t]])
        ids[l++] = ids[t];
      else
        build.scratch[r++] = ids[t];
    std::copy(build.scratch.begin() + static_cast<std::ptrdiff_t>(begin),
              build.scratch.begin() + static_cast<std::ptrdiff_t>(r),
              ids.begin() + static_cast<std::ptrdiff_t>(l));
  }
  splitIntoRuns(build, begin, middle, run);
  splitIntoRuns(build, middle, end, run);
}

/// A subtree to order: the range [begin, end) of a node of `size` (a power of kFanout).
struct Subtree {
  std::size_t begin, end, size;
};

/// Orders the triangles of `node` into kFanout compact children, and each child likewise, down
/// to leaves of kFanout triangles; with `rest`, only down to subtrees of at most `most`
/// triangles, which it appends there unordered.
void buildOrder(TreeBuild& build, const Subtree& node, std::size_t most = 0,
                std::vector<Subtree>* rest = nullptr) {
  if (node.size <= detail::kFanout) return;
  if (rest && node.end - node.begin <= most) {
    rest->push_back(node);
    return;
  }
  const std::size_t child = node.size / detail::kFanout;
  splitIntoRuns(build, node.begin, node.end, child);
  for (std::size_t b = node.begin; b < node.end; b += child)
    buildOrder(build, {b, std::min(b + child, node.end), child}, most, rest);
}

/// Triangle ids in tree order: node i of level l (leaves l = 0) holds the aligned run
/// [i·8^(l+1), (i + 1)·8^(l+1)), split top-down by the surface area heuristic.
std::vector<std::uint32_t> treeOrder(const Mesh& mesh) {
  const std::size_t n = mesh.triangleCount();
  TreeBuild build;
  build.centroids.resize(n);
  build.boxes.resize(n);
  parallelFor(0, n, 1 << 14, [&build, &mesh](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Triangle t = mesh.triangle(i);
      build.centroids[i] = t.centroid();
      build.boxes[i] = t.bounds();
    }
  });
  // The ids along each axis in order of the centroids, by a radix sort of their 32-bit fixed-
  // point positions in the mesh's box (ties, centroids within 2⁻³² of the box apart, by id).
  const Aabb& box = mesh.bounds();
  parallelFor(0, 3, 1, [&build, &box, n](std::size_t first, std::size_t last) {
    std::vector<std::uint64_t> keys(n);
    for (std::size_t axis = first; axis < last; ++axis) {
      const double lower = box.lower[axis], extent = box.upper[axis] - box.lower[axis];
      for (std::size_t i = 0; i < n; ++i) {
        double unit = extent > 0.0 ? (build.centroids[i][axis] - lower) / extent : 0.0;
        if (!(unit > 0.0)) unit = 0.0;  // NaN where coordinates near overflow made extent ∞
        const auto code = static_cast<std::uint64_t>(std::min(unit, 1.0) * 0xffffffffp0);
        keys[i] = code << 32 | i;
      }
      build.sorted[axis] = detail::orderOfKeys(keys, 32);
    }
  });
  build.left.resize(n);
  build.scratch.resize(n);
  std::size_t size = detail::kFanout;
  while (size < n)
    size *= detail::kFanout;
  // The top splits on this thread, then the subtrees below them on all (they touch disjoint
  // ranges of the lists and of the scratch, and disjoint ids).
  std::vector<Subtree> subtrees;
  buildOrder(build, {0, n, size}, std::max<std::size_t>(n / 16, 4096), &subtrees);
  parallelFor(0, subtrees.size(), 1, [&build, &subtrees](std::size_t first, std::size_t last) {
    for (std::size_t s = first; s < last; ++s)
      buildOrder(build, subtrees[s]);
  });
  return std::move(build.sorted[0]);
}

/// Leaf boxes over the sorted triangles, then parents of kFanout children up to one root.
std::vector<std::vector<Aabb>> buildLevels(const detail::QueryMeshData& data) {
  std::vector<std::vector<Aabb>> levels(1);
  levels[0].resize((data.size() + detail::kFanout - 1) / detail::kFanout);
  for (std::size_t k = 0; k < data.size(); ++k)
    levels[0][k / detail::kFanout].extend(data.triangle(k).bounds());
  for (Aabb& leaf : levels[0])
    leaf = leaf.grown(data.slack);
  while (levels.back().size() > 1) {
    const std::vector<Aabb>& children = levels.back();
    std::vector<Aabb> parents((children.size() + detail::kFanout - 1) / detail::kFanout);
    for (std::size_t c = 0; c < children.size(); ++c)
      parents[c / detail::kFanout].extend(children[c]);
    levels.push_back(std::move(parents));
  }
  return levels;
}

/// The float one step from `f` (finite, or an infinity stepping inward) towards −∞ (`down`) or
/// +∞: std::nextafter's result, without its library call (the contact queries round a few
/// thousand moved boxes a query).
float stepped(float f, bool down) noexcept {
  if (f == 0.0f)
    return down ? -std::numeric_limits<float>::denorm_min()
                : std::numeric_limits<float>::denorm_min();
  const auto bits = std::bit_cast<std::uint32_t>(f);
  return std::bit_cast<float>((f > 0.0f) == down ? bits - 1 : bits + 1);
}

/// A double rounded to a float no larger (`down`) or no smaller than it.
float roundedOutward(double value, bool down) noexcept {
  const float f = static_cast<float>(value);
  if (down && static_cast<double>(f) > value) return stepped(f, true);
  if (!down && static_cast<double>(f) < value) return stepped(f, false);
  return f;
}

/// The point queries' copy of the tree (query_mesh_data.h): per inner node its children's
/// boxes, less the single-precision triangles' origin.
void buildOctets(detail::QueryMeshData& data) {
  data.childOctets.resize(data.levels.size() - 1);
  for (std::size_t l = 0; l + 1 < data.levels.size(); ++l) {
    data.childOctets[l].resize(data.levels[l + 1].size());
    for (std::size_t i = 0; i < data.levels[l + 1].size(); ++i)
      data.childOctets[l][i] =
          detail::octetOf(data.levels[l], i * detail::kFanout, data.lanes.origin);
  }
}

/// A leaf's cylinder or cone about an axis through `centre` (query_mesh_data.h's CylinderOctet,
/// before the slack): the axis in single precision, the range [low, high] of h = n·w, and the
/// radius at h = 0 and its taper, radius + taper·h bounding the distance from the axis over its
/// triangles' vertices (w = vertex − origin − centre).
struct LeafCylinder {
  float axis[3] = {0.0f, 0.0f, 0.0f};
  float taper = 0.0f;
  double low = 0.0, high = 0.0, radius = 0.0;

  /// The cylinder's or cone's surface (2πr̄·length + 2πr̄², r̄ its mean radius, without the 2π):
  /// what it adds to the volume around it that a search's bound admits.
  double surface() const noexcept {
    const double s =
        double{axis[0]} * axis[0] + double{axis[1]} * axis[1] + double{axis[2]} * axis[2];
    const double mean = radius + double{taper} * (low + high) * 0.5;
    return mean * ((high - low) / std::sqrt(s) + mean);
  }
};

/// The largest taper a cone may have (k = taper·|n| ≤ 1: query_mesh_data.h's bound on a misplaced
/// minimum holds there).
constexpr double kMostTaper = 1.0;

/// The taper of the cone of least mean radius over [low, high] around points (h, l) (heights and
/// distances from the axis, sorted by h): the slope of their upper hull where it passes the
/// middle height, within ±kMostTaper (0 for points at one height).
double leastMeanTaper(std::span<const std::array<double, 2>> points, double middle) noexcept {
  std::array<std::array<double, 2>, 3 * detail::kFanout> hull;
  std::size_t size = 0;
  for (const auto& point : points) {
    // Andrew's monotone chain, upper hull: drop the last point while it lies on or below the
    // segment from the one before it to this one.
    while (size >= 2) {
      const auto& [h0, l0] = hull[size - 2];
      const auto& [h1, l1] = hull[size - 1];
      if ((h1 - h0) * (point[1] - l0) - (l1 - l0) * (point[0] - h0) < 0.0) break;
      --size;
    }
    hull[size++] = point;
  }
  for (std::size_t k = 0; k + 1 < size; ++k)
    if (hull[k + 1][0] >= middle && hull[k + 1][0] > hull[k][0])
      return std::clamp((hull[k + 1][1] - hull[k][1]) / (hull[k + 1][0] - hull[k][0]), -kMostTaper,
                        kMostTaper);
  return 0.0;
}

/// The leaf's cylinder about `direction` through `centre`, or (`tapered`) its cone of least mean
/// radius.
LeafCylinder cylinderAbout(const detail::QueryMeshData& data, const Vec3& direction,
                           const Vec3& centre, std::size_t from, std::size_t to, bool tapered) {
  LeafCylinder cylinder;
  cylinder.axis[0] = static_cast<float>(direction.x);
  cylinder.axis[1] = static_cast<float>(direction.y);
  cylinder.axis[2] = static_cast<float>(direction.z);
  const Vec3 axis{cylinder.axis[0], cylinder.axis[1], cylinder.axis[2]};
  const double inverse = 1.0 / dot(axis, axis);
  cylinder.low = std::numeric_limits<double>::infinity();
  cylinder.high = -cylinder.low;
  std::array<std::array<double, 2>, 3 * detail::kFanout> points;  // (h, distance from the axis)
  std::size_t count = 0;
  for (std::size_t k = from; k < to; ++k) {
    const Triangle t = data.triangle(k);
    for (const Vec3& v : {t.a, t.b, t.c}) {
      const Vec3 w = (v - data.lanes.origin) - centre;
      const double h = dot(axis, w);
      cylinder.low = std::min(cylinder.low, h);
      cylinder.high = std::max(cylinder.high, h);
      points[count++] = {h, length(w - axis * (h * inverse))};
    }
  }
  const std::span<std::array<double, 2>> measured(points.data(), count);
  if (tapered) {
    std::sort(measured.begin(), measured.end());
    cylinder.taper =
        static_cast<float>(leastMeanTaper(measured, (cylinder.low + cylinder.high) * 0.5));
  }
  // The radius at h = 0 for the taper as stored.
  for (const auto& [h, l] : measured)
    cylinder.radius = std::max(cylinder.radius, l - double{cylinder.taper} * h);
  return cylinder;
}

/// The vertex every triangle of [from, to) has (by its coordinates), if there is one.
std::optional<Vec3> commonVertex(const detail::QueryMeshData& data, std::size_t from,
                                 std::size_t to) {
  const Triangle first = data.triangle(from);
  for (const Vec3& v : {first.a, first.b, first.c}) {
    bool everywhere = true;
    for (std::size_t k = from + 1; k < to && everywhere; ++k) {
      const Triangle t = data.triangle(k);
      everywhere = t.a == v || t.b == v || t.c == v;
    }
    if (everywhere) return v;
  }
  return std::nullopt;
}

/// The cylinders of the leaves of node `node` of level 1 (query_mesh_data.h), each about an axis
/// through the centre of the leaf's box in the node's octet (less the origin, as the octet is):
/// the leaf's slab's normal, a flat disc around a patch of a surface; or, where its surface is
/// less than half the disc's, the leaf's long direction (from the vertex farthest from the
/// centre to the vertex farthest from that one), a thin rod around a strip of slivers; or, where
/// the leaf's triangles meet in one vertex (a wedge of a fan) and its surface is less than half
/// the disc's, the cone from the centre towards that vertex, its tip there. A cap of a cylinder
/// triangulated as a fan from its centre puts every leaf's triangles from the centre to the rim:
/// a point above the cap lay within the box and the disc of a fifth of the leaves, and a search
/// took 97 µs on a fan of 16,384 slivers where it took 1.4 µs on one of 1,024; rods kept most of
/// them out, but a point near the centre lay within the rod of every wedge (as wide at the
/// centre as at the rim), which the cones, as thin as the wedges at every height, are not.
detail::CylinderOctet cylinderOctet(const detail::QueryMeshData& data, std::size_t node) {
  const detail::BoxOctet& boxes = data.childOctets[0][node];
  detail::CylinderOctet cylinders{};  // empty slots: zeros (their boxes' centres are NaN)
  for (std::size_t i = 0; i < detail::kFanout; ++i) {
    const std::size_t leaf = node * detail::kFanout + i;
    const std::size_t from = leaf * detail::kFanout;
    const std::size_t to = std::min(from + detail::kFanout, data.size());
    if (from >= to) break;
    const Vec3 centre{(double{boxes.lowerX[i]} + double{boxes.upperX[i]}) * 0.5,
                      (double{boxes.lowerY[i]} + double{boxes.upperY[i]}) * 0.5,
                      (double{boxes.lowerZ[i]} + double{boxes.upperZ[i]}) * 0.5};
    LeafCylinder cylinder =
        cylinderAbout(data, data.slabs[0][leaf].normal, centre, from, to, false);
    // The long direction: the two vertices farthest apart, nearly.
    const auto farthestFrom = [&](const Vec3& point) {
      Vec3 farthest = point;
      double most = 0.0;
      for (std::size_t k = from; k < to; ++k) {
        const Triangle t = data.triangle(k);
        for (const Vec3& v : {t.a, t.b, t.c})
          if (const double d = lengthSquared((v - data.lanes.origin) - point); d > most) {
            most = d;
            farthest = v - data.lanes.origin;
          }
      }
      return farthest;
    };
    const Vec3 end = farthestFrom(centre), start = farthestFrom(end);
    const Vec3 along = end - start;
    const LeafCylinder disc = cylinder;
    if (const double size = length(along); size > 0.0 && std::isfinite(size)) {
      const LeafCylinder rod = cylinderAbout(data, along / size, centre, from, to, false);
      if (rod.surface() < 0.5 * disc.surface()) cylinder = rod;
    }
    // A wedge of a fan (its triangles meet in one vertex): a cone from the centre towards it,
    // whose tip lies there.
    if (const std::optional<Vec3> tip = commonVertex(data, from, to)) {
      const Vec3 towards = (*tip - data.lanes.origin) - centre;
      if (const double size = length(towards); size > 0.0 && std::isfinite(size)) {
        const LeafCylinder cone = cylinderAbout(data, towards / size, centre, from, to, true);
        if (cone.surface() < 0.5 * disc.surface()) cylinder = cone;
      }
    }
    // The slack covers this rounding and the queries' (far above a few ulps of the box).
    cylinders.normalX[i] = cylinder.axis[0];
    cylinders.normalY[i] = cylinder.axis[1];
    cylinders.normalZ[i] = cylinder.axis[2];
    cylinders.low[i] = roundedOutward(cylinder.low - data.slack, true);
    cylinders.high[i] = roundedOutward(cylinder.high + data.slack, false);
    cylinders.radius[i] = roundedOutward(cylinder.radius + data.slack, false);
    cylinders.taper[i] = cylinder.taper;
    // The offset of the least bound's height per unit of gap (query_mesh_data.h), to the
    // nearest float: its rounding is covered there.
    const double axisSquared = double{cylinder.axis[0]} * cylinder.axis[0] +
                               double{cylinder.axis[1]} * cylinder.axis[1] +
                               double{cylinder.axis[2]} * cylinder.axis[2];
    const double taper = cylinder.taper;
    cylinders.step[i] = static_cast<float>(taper / (1.0 / axisSquared + taper * taper));
  }
  return cylinders;
}

/// The leaves' cylinders, after the octets and the slabs.
void buildCylinders(detail::QueryMeshData& data) {
  if (data.childOctets.empty()) return;  // one leaf: no descent
  data.leafCylinders.resize(data.childOctets[0].size());
  parallelFor(0, data.leafCylinders.size(), 64, [&data](std::size_t begin, std::size_t end) {
    for (std::size_t node = begin; node < end; ++node)
      data.leafCylinders[node] = cylinderOctet(data, node);
  });
}

/// Every node's oriented slab (query_mesh_data.h): a node of level l holds the sorted triangles
/// [i·8^(l+1), (i+1)·8^(l+1)), so each level is one pass over the triangles.
std::vector<std::vector<detail::NodeSlab>> buildSlabs(const detail::QueryMeshData& data) {
  std::vector<std::vector<detail::NodeSlab>> slabs(data.levels.size());
  const std::size_t size = data.size();
  std::size_t span = detail::kFanout;
  for (std::size_t l = 0; l < data.levels.size(); ++l, span *= detail::kFanout) {
    slabs[l].resize(data.levels[l].size());
    parallelFor(0, slabs[l].size(), std::max<std::size_t>(1, 4096 / span),
                [&](std::size_t begin, std::size_t end) {
                  for (std::size_t i = begin; i < end; ++i) {
                    const std::size_t from = i * span;
                    const std::size_t to = std::min(from + span, size);
                    Vec3 area{};
                    for (std::size_t k = from; k < to; ++k)
                      area = area + data.triangle(k).areaVector();
                    detail::NodeSlab& slab = slabs[l][i];
                    if (lengthSquared(area) > 0.0) slab.normal = normalized(area);
                    double low = std::numeric_limits<double>::infinity(), high = -low;
                    for (std::size_t k = from; k < to; ++k) {
                      const Triangle t = data.triangle(k);
                      for (const Vec3& v : {t.a, t.b, t.c}) {
                        const double along = dot(slab.normal, v);
                        low = std::min(low, along);
                        high = std::max(high, along);
                      }
                    }
                    slab.low = low - data.slack;
                    slab.high = high + data.slack;
                  }
                });
  }
  return slabs;
}

/// The angle of a triangle at corner `from`, between the edges to `next` and `previous`.
double cornerAngle(const Vec3& from, const Vec3& next, const Vec3& previous) noexcept {
  const Vec3 e1 = next - from, e2 = previous - from;
  return std::atan2(length(cross(e1, e2)), dot(e1, e2));
}

/// The ids [0, count) grouped by key (`keyOf(id)` < keys), in id order within a key: first[k] is
/// where key k's ids start in `ids`, first[keys] = count (a counting sort).
struct Buckets {
  std::vector<std::uint32_t> first;
  std::vector<std::uint32_t> ids;
};

template <typename KeyOf>
Buckets bucketsOf(std::size_t count, std::size_t keys, const KeyOf& keyOf) {
  Buckets buckets;
  buckets.first.assign(keys + 1, 0);
  for (std::size_t id = 0; id < count; ++id)
    ++buckets.first[keyOf(id) + 1];
  for (std::size_t k = 0; k < keys; ++k)
    buckets.first[k + 1] += buckets.first[k];
  std::vector<std::uint32_t> next(buckets.first.begin(), buckets.first.end() - 1);
  buckets.ids.resize(count);
  for (std::size_t id = 0; id < count; ++id)
    buckets.ids[next[keyOf(id)]++] = static_cast<std::uint32_t>(id);
  return buckets;
}

/// Angle-weighted vertex pseudonormals, and per triangle the triangles across its edges: for a
/// closed, consistently oriented mesh every edge of a triangle with three distinct corners has
/// exactly one partner. Each vertex sums its corners in the mesh's triangle order (the same sums
/// on any number of threads); the edges meet in buckets of their lower vertex.
detail::Pseudonormals pseudonormals(const detail::QueryMeshData& data) {
  const std::size_t n = data.size();
  detail::Pseudonormals result;
  result.vertices.assign(data.vertices.size(), Vec3{});
  result.across.assign(n, {detail::Pseudonormals::kNone, detail::Pseudonormals::kNone,
                           detail::Pseudonormals::kNone});
  // Corner 3t + c: corner c of mesh triangle t, its vertex and weighted normal, on all threads
  // (read in tree order, where neighbours share vertices: the mesh's order may be scattered).
  std::vector<Vec3> weighted(3 * n);
  std::vector<std::uint32_t> vertexOf(3 * n);
  parallelFor(0, n, 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const Triangle triangle = data.triangle(k);
      const Vec3 faceNormal = normalized(triangle.areaVector());
      const Vec3 corners[3] = {triangle.a, triangle.b, triangle.c};
      const std::size_t t = data.order[k];
      for (std::size_t c = 0; c < 3; ++c) {
        weighted[3 * t + c] =
            cornerAngle(corners[c], corners[(c + 1) % 3], corners[(c + 2) % 3]) * faceNormal;
        vertexOf[3 * t + c] = data.corners[k][c];
      }
    }
  });
  const Buckets cornersOf = bucketsOf(3 * n, data.vertices.size(),
                                      [&vertexOf](std::size_t corner) { return vertexOf[corner]; });
  parallelFor(0, data.vertices.size(), 4096, [&](std::size_t begin, std::size_t end) {
    for (std::size_t v = begin; v < end; ++v)
      for (std::uint32_t i = cornersOf.first[v]; i < cornersOf.first[v + 1]; ++i)
        result.vertices[v] += weighted[cornersOf.ids[i]];
  });
  // Edge 3k + slot: from corner slot of sorted triangle k to the next (none for a fold, whose
  // edges have no partner: topology.h). Each bucket of a lower vertex pairs its edges by upper
  // vertex, in order of (triangle, slot).
  const auto folded = [&data](std::size_t k) {
    const TriangleIndices& v = data.corners[k];
    return v[0] == v[1] || v[1] == v[2] || v[2] == v[0];
  };
  const auto ends = [&data](std::size_t edge) {
    const TriangleIndices& v = data.corners[edge / 3];
    const std::uint32_t from = v[edge % 3], to = v[(edge + 1) % 3];
    return std::pair{std::min(from, to), std::max(from, to)};
  };
  const Buckets edgesOf = bucketsOf(3 * n, data.vertices.size(),
                                    [&ends](std::size_t edge) { return ends(edge).first; });
  parallelFor(0, data.vertices.size(), 4096, [&](std::size_t begin, std::size_t end) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> bucket;  // (upper vertex, edge)
    for (std::size_t v = begin; v < end; ++v) {
      bucket.clear();
      for (std::uint32_t i = edgesOf.first[v]; i < edgesOf.first[v + 1]; ++i)
        if (!folded(edgesOf.ids[i] / 3))
          bucket.push_back({ends(edgesOf.ids[i]).second, edgesOf.ids[i]});
      std::sort(bucket.begin(), bucket.end());
      for (std::size_t e = 0; e + 1 < bucket.size(); ++e) {
        if (bucket[e].first != bucket[e + 1].first) continue;
        const std::uint32_t one = bucket[e].second, other = bucket[e + 1].second;
        result.across[one / 3][one % 3] = other / 3;
        result.across[other / 3][other % 3] = one / 3;
        ++e;
      }
    }
  });
  return result;
}

}  // namespace

namespace detail {

const TriangleSoA& QueryMeshData::meshOrder() const {
  std::call_once(meshOrderOnce_, [this] {
    std::vector<Triangle> inMeshOrder(size());
    for (std::size_t k = 0; k < size(); ++k)
      inMeshOrder[order[k]] = triangle(k);
    meshOrder_.assign(inMeshOrder);
    meshOrderMade_.store(true, std::memory_order_release);
  });
  return meshOrder_;
}

const Pseudonormals& QueryMeshData::makePseudonormals() const {
  std::call_once(pseudonormalsOnce_, [this] {
    pseudonormals_ = delta::pseudonormals(*this);
    pseudonormalsMade_.store(true, std::memory_order_release);
  });
  return pseudonormals_;
}

const WindingTree& QueryMeshData::windingTree() const {
  std::call_once(windingTreeOnce_, [this] {
    windingTree_ = buildWindingTree(*this);
    windingTreeMade_.store(true, std::memory_order_release);
  });
  return windingTree_;
}

Vec3 QueryMeshData::pseudonormal(std::uint32_t sorted, std::size_t slot) const {
  const Pseudonormals& normals = pseudonormals();
  if (slot < 3) return normals.vertices[corners[sorted][slot]];
  // The sum of the two faces' unit normals (an edge's two angles are both π).
  const std::uint32_t other = normals.across[sorted][slot - 3];
  if (other == Pseudonormals::kNone) return {};
  return normalized(triangle(sorted).areaVector()) + normalized(triangle(other).areaVector());
}

BoxOctet octetOf(const std::vector<Aabb>& boxes, std::size_t first, const Vec3& origin) noexcept {
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  BoxOctet octet;
  for (std::size_t i = 0; i < kFanout; ++i) {
    const bool present = first + i < boxes.size() && !boxes[first + i].empty();
    // The differences round by half an ulp of the box's extent at most: the slack covers it.
    const Aabb box =
        present ? Aabb{boxes[first + i].lower - origin, boxes[first + i].upper - origin} : Aabb{};
    octet.lowerX[i] = present ? roundedOutward(box.lower.x, true) : kInfinity;
    octet.lowerY[i] = present ? roundedOutward(box.lower.y, true) : kInfinity;
    octet.lowerZ[i] = present ? roundedOutward(box.lower.z, true) : kInfinity;
    octet.upperX[i] = present ? roundedOutward(box.upper.x, false) : -kInfinity;
    octet.upperY[i] = present ? roundedOutward(box.upper.y, false) : -kInfinity;
    octet.upperZ[i] = present ? roundedOutward(box.upper.z, false) : -kInfinity;
  }
  return octet;
}

}  // namespace detail

QueryMesh::QueryMesh(const Mesh& mesh) {
  if (mesh.triangleCount() == 0) throw Error("QueryMesh: the mesh has no triangles");
  if (mesh.triangleCount() >= std::numeric_limits<std::uint32_t>::max())
    throw Error("QueryMesh: more triangles than 32-bit ids can name");
  checkMeshScale(mesh.bounds(), "QueryMesh: the mesh");
  auto data = std::make_shared<detail::QueryMeshData>();
  // The first triangle the mesh–mesh queries refuse (checkTriangleExtent), if any.
  for (std::size_t t = 0; t < mesh.triangleCount() && !data->tinyTriangle; ++t)
    if (const double extent = triangleExtent(mesh.triangle(t));
        extent > 0.0 && extent < kSmallestTriangleExtent)
      data->tinyTriangle = std::pair{t, mesh.triangle(t)};
  data->bounds = mesh.bounds();
  data->order = treeOrder(mesh);
  // The corners in tree order, the vertices renumbered in the order they first appear there.
  constexpr std::uint32_t kUnseen = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> renumbered(mesh.vertexCount(), kUnseen);
  data->corners.resize(mesh.triangleCount());
  for (std::size_t k = 0; k < data->corners.size(); ++k)
    for (std::size_t c = 0; c < 3; ++c) {
      const std::uint32_t v = mesh.triangles()[data->order[k]][c];
      if (renumbered[v] == kUnseen) {
        renumbered[v] = static_cast<std::uint32_t>(data->vertices.size());
        data->vertices.push_back(mesh.vertices()[v]);
      }
      data->corners[k][c] = renumbered[v];
    }
  data->vertices.shrink_to_fit();
  const Vec3 centre = data->bounds.center();
  double farthest = 0.0;
  for (const Vec3& vertex : data->vertices)
    farthest = std::max(farthest, distanceSquared(vertex, centre));
  data->radius = std::sqrt(farthest) * (1.0 + 0x1p-40);  // above the rounding of |v − c|
  const auto triangleAt = [&data = *data](std::size_t k) { return data.triangle(k); };
  data->lanes = detail::floatTriangles(data->size(), triangleAt, data->bounds.center());
  // Boxes grow by far more than the rounding of a box distance or a point–triangle distance
  // (a few ulps of the coordinates and the distance), so pruning by box never drops a triangle
  // whose computed distance would win.
  data->slack = 0x1p-36 * (std::max(maxAbs(data->bounds.lower), maxAbs(data->bounds.upper)) +
                           data->bounds.diagonal());
  data->levels = buildLevels(*data);
  buildOctets(*data);
  data->slabs = buildSlabs(*data);
  buildCylinders(*data);
  {  // the grid reads plain triangles: a copy for its build only
    std::vector<Triangle> sorted(data->size());
    for (std::size_t k = 0; k < sorted.size(); ++k)
      sorted[k] = data->triangle(k);
    TriangleSoA soa;
    soa.assign(sorted);
    data->boundGrid = detail::BoundGrid(soa, data->bounds);
  }
  data->topology = analyzeTopology(mesh);
  data->closed = data->topology.closed && data->topology.consistentlyOriented;
  if (data->closed) {
    // The exact sign (a float sum where its rounding bound decides it): a thin closed mesh whose
    // float volume rounds to the wrong sign would be taken inside out, every sign turned.
    std::vector<std::uint32_t> all(data->size());
    std::iota(all.begin(), all.end(), std::uint32_t{0});
    const std::optional<int> sign = detail::volumeSign(*data, all);
    data->exactVolumeSign = sign;
    data->orientation = sign ? (*sign < 0 ? -1.0 : 1.0) : (signedVolume(mesh) < 0.0 ? -1.0 : 1.0);
  }
  data_ = std::move(data);
}

namespace {

/// `motion` with its rotation renormalised, or where `keepUnit` and it is a unit quaternion to
/// within 8ε (|q|² − 1), kept bit for bit (normalising a unit quaternion again changes its last
/// bits in some 2.5% of cases: a pickled QueryMesh at 1e6 answered 1.1e-10 differently);
/// delta::Error naming `what` for a translation that is not finite
/// (Quaternion::fromComponents rejects a bad rotation).
RigidTransform checkedMotion(const RigidTransform& motion, const char* what, bool keepUnit) {
  if (!isFinite(motion.translation))
    throw Error(std::string("QueryMesh::") + what + ": translation " +
                toString(motion.translation) + " is not finite");
  const Quaternion& q = motion.rotation;
  const double normSquared = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
  if (keepUnit && std::abs(normSquared - 1.0) <= 8.0 * std::numeric_limits<double>::epsilon())
    return motion;
  return {Quaternion::fromComponents(q.w, q.x, q.y, q.z), motion.translation};
}

}  // namespace

QueryMesh& QueryMesh::transform(const RigidTransform& motion) {
  return place(checkedMotion(motion, "transform", false) * pose_, "transform");
}

QueryMesh& QueryMesh::setPose(const RigidTransform& pose) {
  return place(checkedMotion(pose, "setPose", true), "setPose");
}

QueryMesh& QueryMesh::place(const RigidTransform& pose, const char* what) {
  // Composed, two finite motions of 1.5e308 gave a translation of +∞ and an inverse of NaN. A
  // pose beyond the coordinate range is kept: the queries refuse the mesh there.
  const RigidTransform inverse = pose.inverse();
  if (!isFinite(pose.translation) || !isFinite(inverse.translation))
    throw Error(std::string("QueryMesh::") + what + ": the pose's translation " +
                toString(pose.translation) + " overflows a double");
  pose_ = pose;
  inversePose_ = inverse;
  moved_ = true;
  placedSurelyInRange_ = detail::surelyInRange(data_->bounds, pose_);
  return *this;
}

Mesh QueryMesh::mesh() const {
  std::vector<TriangleIndices> triangles(data_->corners.size());
  for (std::size_t sorted = 0; sorted < triangles.size(); ++sorted)
    triangles[data_->order[sorted]] = data_->corners[sorted];
  return Mesh(data_->vertices, std::move(triangles));
}

std::size_t QueryMesh::size() const noexcept {
  return data_->size();
}
const TriangleSoA& QueryMesh::triangles() const {
  return data_->meshOrder();
}
const Topology& QueryMesh::topology() const noexcept {
  return data_->topology;
}
bool QueryMesh::closed() const noexcept {
  return data_->closed;
}
const Aabb& QueryMesh::bounds() const noexcept {
  return data_->bounds;
}

std::size_t QueryMesh::memoryBytes() const noexcept {
  const detail::QueryMeshData& data = *data_;
  std::size_t bytes = (data.meshOrderMade() ? data.meshOrder().memoryBytes() : 0) +
                      (data.pseudonormalsMade() ? data.pseudonormals().memoryBytes() : 0) +
                      (data.componentsMade() ? data.components().memoryBytes() : 0) +
                      (data.windingTreeMade() ? data.windingTree().memoryBytes() : 0) +
                      data.vertices.capacity() * sizeof(Vec3) +
                      data.corners.capacity() * sizeof(TriangleIndices) +
                      data.order.capacity() * sizeof(std::uint32_t) + data.lanes.memoryBytes();
  for (const std::vector<Aabb>& level : data.levels)
    bytes += level.capacity() * sizeof(Aabb);
  bytes += data.leafCylinders.capacity() * sizeof(detail::CylinderOctet);
  for (const detail::BoxOctets& level : data.childOctets)
    bytes += level.capacity() * sizeof(detail::BoxOctet);
  for (const std::vector<detail::NodeSlab>& level : data.slabs)
    bytes += level.capacity() * sizeof(detail::NodeSlab);
  return bytes + data.boundGrid.memoryBytes();
}

}  // namespace delta
