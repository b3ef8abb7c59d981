#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/mat3.h"
#include "delta/core/rotation.h"
#include "delta/core/triangle.h"

#include "query_mesh_data.h"

namespace delta::detail {

/// A leaf of each of two trees (indices into their levels[0]).
struct LeafPair {
  std::uint32_t first;
  std::uint32_t second;
};

/// A rigid motion as a matrix, applied exactly as Mesh::transform applies it (so a prepared
/// mesh moved by a pose meets another one at the same coordinates as the moved Mesh would).
struct MatrixMotion {
  Mat3 rotation;
  Vec3 translation;
  Vec3 apply(const Vec3& p) const noexcept { return rotation * p + translation; }
  Triangle apply(const Triangle& t) const noexcept { return {apply(t.a), apply(t.b), apply(t.c)}; }
};
MatrixMotion matrixMotion(const RigidTransform& motion);

/// How far the second of two prepared meshes has moved against the first since `rotation`,
/// `translation` placed it in the first's frame, where `now` places it: the smaller of how far
/// the second's points moved in the first's frame and how far the first's moved in the
/// second's (either bounds how much any distance between a point of one and a point of the
/// other has changed). The second bound is the one that counts for a small body against a
/// large one (a particle against a funnel: its turn swings the funnel's far corners round in its
/// frame). Rounding: a few ulps of the coordinates and of the translations.
double relativeMove(const QueryMeshData& first, const QueryMeshData& second,
                    const MatrixMotion& now, const Mat3& rotation,
                    const Vec3& translation) noexcept;

/// The largest coordinate of a pair of prepared meshes where the mesh–mesh kernels meet them:
/// the first's box (`first`) and the corners of the second's (`second`) carried by
/// `secondToFirst`.
double placedMagnitude(const Aabb& first, const Aabb& second,
                       const RigidTransform& secondToFirst) noexcept;

/// Eight boxes in double, structure of arrays (axis, then lane): an octet of a tree
/// (query_mesh_data.h) as another frame sees it. Empty slots have lower +∞, upper −∞.
struct MovedOctet {
  double lower[3][kFanout];
  double upper[3][kFanout];
};

/// The boxes of `count` (≤ kFanout) triangles grown by `slack`, side by side; the slots past
/// `count` empty (+∞, −∞: infinitely far).
MovedOctet boxesOf(const Triangle* triangles, std::size_t count, double slack) noexcept;

/// The world boxes of a leaf's triangles less a reference point, in single precision, side by
/// side (axis, then lane). Empty past the leaf's last triangle (+∞, −∞).
struct FloatOctet {
  float lower[3][kFanout];
  float upper[3][kFanout];
};

/// The boxes of leaf `leaf`'s triangles (of `lanes`, a mesh's single-precision copy) moved by
/// `motion` (nullptr: not moved), less `reference`: computed in single precision, eight at once,
/// and widened by every rounding, so that each holds its triangle's corners as the queries move
/// them (motion.apply in double, then less `reference`). Moved coordinates beyond about 2¹⁰⁰
/// give boxes without bounds (−∞, +∞).
FloatOctet movedLeafBoxes(const FloatTriangles& lanes, std::size_t leaf, std::size_t count,
                          const MatrixMotion* motion, const Vec3& reference) noexcept;

/// The lanes of `boxes` (bit i: lane i) that meet the box [lower, upper] (closed boxes; an empty
/// lane meets nothing, not even a box without bounds), all eight at once.
std::uint32_t lanesMeeting(const FloatOctet& boxes, const float lower[3],
                           const float upper[3]) noexcept;

/// Lane i of an octet's boxes along `axis`.
inline double lowerOf(const MovedOctet& boxes, std::size_t axis, std::size_t i) noexcept {
  return boxes.lower[axis][i];
}
inline double upperOf(const MovedOctet& boxes, std::size_t axis, std::size_t i) noexcept {
  return boxes.upper[axis][i];
}
inline float lowerOf(const BoxOctet& boxes, std::size_t axis, std::size_t i) noexcept {
  return axis == 0 ? boxes.lowerX[i] : axis == 1 ? boxes.lowerY[i] : boxes.lowerZ[i];
}
inline float upperOf(const BoxOctet& boxes, std::size_t axis, std::size_t i) noexcept {
  return axis == 0 ? boxes.upperX[i] : axis == 1 ? boxes.upperY[i] : boxes.upperZ[i];
}

/// The squared distances from `box` to the eight boxes of `boxes` (+∞ for an empty slot), as
/// distanceSquared(Aabb, Aabb) gives them one by one.
template <class Octet>
[[gnu::always_inline]] inline void distancesSquared(const Octet& boxes, const Aabb& box,
                                                    double (&out)[kFanout]) noexcept {
  for (std::size_t i = 0; i < kFanout; ++i) {
    double sum = 0.0;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      const double gap = std::max(std::max(double{lowerOf(boxes, axis, i)} - box.upper[axis],
                                           box.lower[axis] - double{upperOf(boxes, axis, i)}),
                                  0.0);
      sum += gap * gap;
    }
    out[i] = sum;
  }
}

/// Bit i set where box i of `boxes` is not `gap` apart from `box` along any axis (!apart() for
/// eight boxes at once; never for an empty slot). Without branches: a branch per test
/// mispredicted often enough to take a quarter of a contact query.
template <class Octet>
[[gnu::always_inline]] inline unsigned notApartMask(const Octet& boxes, const Aabb& box,
                                                    double gap) noexcept {
  unsigned mask = 0;
  for (std::size_t i = 0; i < kFanout; ++i) {
    int near = 1;
    for (std::size_t axis = 0; axis < 3; ++axis)
      near &= static_cast<int>(double{lowerOf(boxes, axis, i)} - box.upper[axis] < gap) &
              static_cast<int>(box.lower[axis] - double{upperOf(boxes, axis, i)} < gap);
    mask |= static_cast<unsigned>(near) << i;
  }
  return mask;
}

/// A tree's node boxes as seen from another frame, moved on demand: a query that visits a few
/// nodes of a large tree (a particle near a big obstacle) pays for those, not for the whole tree.
/// A moved box is the box of the moved box (centre moved, half extents through |R|), so it
/// contains every moved point of the original; the rounding of the moved centre is a few ulps of
/// the coordinates, covered by the boxes' slack (query_mesh_data.h). Without a motion the boxes
/// are the tree's own.
class MovedTree {
 public:
  MovedTree(const std::vector<std::vector<Aabb>>& levels, const MatrixMotion* motion) noexcept;

  Aabb box(std::size_t level, std::size_t node) const noexcept {
    const Aabb& box = levels_[level][node];
    if (!motion_) return box;
    const Vec3 centre = motion_->apply(box.center());
    const Vec3 half = magnitude_ * (box.extent() * 0.5);
    return {centre - half, centre + half};
  }
  /// The eight boxes of an octet of this tree's children, which lie less `origin`
  /// (QueryMeshData::childOctets), put back at the origin and moved as box() moves one, eight at
  /// once. (Putting back rounds by half an ulp of the coordinates: the slack covers it.)
  MovedOctet moved(const BoxOctet& octet, const Vec3& origin) const noexcept {
    MovedOctet out;
    const float* lower[3] = {octet.lowerX, octet.lowerY, octet.lowerZ};
    const float* upper[3] = {octet.upperX, octet.upperY, octet.upperZ};
    if (!motion_) {
      for (std::size_t axis = 0; axis < 3; ++axis)
        for (std::size_t i = 0; i < kFanout; ++i) {
          out.lower[axis][i] = lower[axis][i] + origin[axis];  // ±∞ where empty
          out.upper[axis][i] = upper[axis][i] + origin[axis];
        }
      return out;
    }
    double centre[3][kFanout], half[3][kFanout];
    for (std::size_t axis = 0; axis < 3; ++axis)
      for (std::size_t i = 0; i < kFanout; ++i) {
        const double low = lower[axis][i], high = upper[axis][i];
        centre[axis][i] = (low + high) * 0.5 + origin[axis];
        half[axis][i] = (high - low) * 0.5;
      }
    // Rows of the motion, like MatrixMotion::apply and Mat3 * Vec3 (the same operation order).
    for (int row = 0; row < 3; ++row)
      for (std::size_t i = 0; i < kFanout; ++i) {
        const Vec3 c{centre[0][i], centre[1][i], centre[2][i]};
        const Vec3 h{half[0][i], half[1][i], half[2][i]};
        const double movedCentre = dot(motion_->rotation.row(row), c) +
                                   motion_->translation[static_cast<std::size_t>(row)];
        const double movedHalf = dot(magnitude_.row(row), h);
        const bool present = lower[0][i] <= upper[0][i];
        out.lower[row][i] =
            present ? movedCentre - movedHalf : std::numeric_limits<double>::infinity();
        out.upper[row][i] =
            present ? movedCentre + movedHalf : -std::numeric_limits<double>::infinity();
      }
    return out;
  }
  /// A slab of this tree (query_mesh_data.h) as seen from the other frame: its normal turned, its
  /// extent shifted by the translation along it and widened by the rounding of that shift.
  NodeSlab moved(const NodeSlab& slab) const noexcept {
    if (!motion_) return slab;
    const Vec3 normal = motion_->rotation * slab.normal;
    const double shift = dot(normal, motion_->translation);
    const double rounding = 0x1p-40 * (std::abs(shift) + maxAbs(motion_->translation));
    return {normal, slab.low + shift - rounding, slab.high + shift + rounding};
  }
  std::size_t levelCount() const noexcept { return levels_.size(); }
  std::size_t nodeCount(std::size_t level) const noexcept { return levels_[level].size(); }

 private:
  const std::vector<std::vector<Aabb>>& levels_;
  const MatrixMotion* motion_;
  Mat3 magnitude_;  ///< |R| entry by entry
};

/// A lower bound of the distance between the triangles of two nodes, each given by its slab and
/// box in one frame, less `margin` (the rounding of these projections, a few ulps of the
/// coordinates: the caller passes the meshes' slack). Along a's normal, b's points lie in
///   (n_a·n_b)·[b.low, b.high] + w·c_b ± |w|·h_b,  w = n_a − (n_a·n_b)·n_b
/// (b's slab bounds the part along n_b, b's box the rest), and a's in [a.low, a.high]; the gap
/// between the two intervals bounds the distance, and likewise along b's normal. For nearly
/// parallel patches facing each other, whose boxes overlap, w is small and the bound is the gap.
inline double slabGap(const NodeSlab& a, const Aabb& boxA, const NodeSlab& b, const Aabb& boxB,
                      double margin) noexcept {
  const double cosine = dot(a.normal, b.normal);
  // The interval of n·x over the points x of a node with slab `slab` and box `box`.
  const auto along = [cosine](const Vec3& normal, const NodeSlab& slab, const Aabb& box) {
    const Vec3 w = normal - slab.normal * cosine;
    const Vec3 centre = box.center(), half = box.extent() * 0.5;
    const double middle = dot(w, centre);
    const double radius = std::abs(w.x) * half.x + std::abs(w.y) * half.y + std::abs(w.z) * half.z;
    const double p = cosine * slab.low, q = cosine * slab.high;
    return std::pair{std::min(p, q) + middle - radius, std::max(p, q) + middle + radius};
  };
  const auto [lowB, highB] = along(a.normal, b, boxB);
  const auto [lowA, highA] = along(b.normal, a, boxA);
  const double gap = std::max({lowB - a.high, a.low - highB, lowA - b.high, b.low - highA});
  return gap - margin;
}

/// A triangle's plane, for the mesh–mesh queries' cheapest exact early-out: a triangle whose three
/// vertices lie on one side of it, all farther than the reach, is farther than the reach from
/// the plane's triangle (the box tests cannot see this for nearly touching surfaces, whose
/// triangles' boxes overlap by the thousand). Not usable for a sliver or a zero-area triangle
/// (angle at a below 2⁻¹⁰), whose plain normal's direction is off by ε / sin α.
struct SeparatingPlane {
  Vec3 normal;  ///< unit
  Vec3 origin;  ///< the triangle's first vertex
  /// The triangle's largest absolute coordinate, the scale of the rounding of a signed distance
  /// to its plane, or of one of its vertices to another plane.
  double magnitude = 0.0;
  double size = 0.0;  ///< its longest edge from the origin
  bool usable = false;
};

inline SeparatingPlane separatingPlane(const Triangle& t) noexcept {
  const Vec3 u = t.b - t.a, v = t.c - t.a, n = cross(u, v);
  const double nn = lengthSquared(n);
  SeparatingPlane plane;
  plane.magnitude =
      std::max({std::abs(t.a.x), std::abs(t.a.y), std::abs(t.a.z), std::abs(t.b.x), std::abs(t.b.y),
                std::abs(t.b.z), std::abs(t.c.x), std::abs(t.c.y), std::abs(t.c.z)});
  plane.usable = nn > 0x1p-20 * lengthSquared(u) * lengthSquared(v);
  if (!plane.usable) return plane;
  plane.normal = n * (1.0 / std::sqrt(nn));
  plane.origin = t.a;
  plane.size = std::sqrt(std::max(lengthSquared(u), lengthSquared(v)));
  return plane;
}

/// Whether every vertex of `t` (whose largest absolute coordinate is `magnitude`) lies farther
/// than `reach` from the plane, all on one side; with a margin of 2⁻³⁰ of the coordinates'
/// magnitude, thousands of times the rounding of the signed distances (a few ε of the
/// coordinates, and 2¹⁰·ε of the distance for the normal), so a pair within reach is never taken
/// for separated.
inline bool separated(const SeparatingPlane& plane, const Triangle& t, double magnitude,
                      double reach) noexcept {
  if (!plane.usable) return false;
  const double beyond = reach + 0x1p-30 * (plane.magnitude + plane.size + magnitude);
  const double a = dot(plane.normal, t.a - plane.origin), b = dot(plane.normal, t.b - plane.origin),
               c = dot(plane.normal, t.c - plane.origin);
  // Without branches: which side each vertex lies on is a coin toss to the predictor.
  const int above =
      static_cast<int>(a > beyond) & static_cast<int>(b > beyond) & static_cast<int>(c > beyond);
  const int below =
      static_cast<int>(a < -beyond) & static_cast<int>(b < -beyond) & static_cast<int>(c < -beyond);
  return (above | below) != 0;
}

/// Every pair of leaves, one of each tree, whose boxes are not `reach` apart along any axis, by a
/// simultaneous descent of both trees that splits the larger node. `second` is the second tree
/// seen from the first's frame. In no particular order; each pair once. (Its children's boxes
/// taken from the octets, the second's moved eight at once, measured no faster: a moved box is
/// needed per child either way.)
/// The pairs go into `pairs`, emptied first and its capacity kept (a DEM step makes hundreds of
/// small queries, each of which grew a fresh vector).
void leafPairsWithin(const QueryMeshData& firstMesh, const QueryMeshData& secondMesh,
                     const MovedTree& second, double reach, std::vector<LeafPair>& pairs);

}  // namespace delta::detail
