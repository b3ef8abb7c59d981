#include "delta/query/overlap.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/query/part_nesting.h"
#include "delta/query/self_intersections.h"

#include "../kernels/detail/exact_predicates.h"
#include "../kernels/detail/robust_geometry.h"
#include "../mesh/detail/union_find.h"
#include "../mesh/detail/vertex_parts.h"
#include "detail/dual_traversal.h"
#include "detail/placement.h"
#include "detail/query_mesh_data.h"

namespace delta::contactdetection {
namespace {

using detail::QueryMeshData;

constexpr std::int32_t kAbsent = -1;

/// A vector of this thread's, emptied, keeping its capacity from one query to the next (a DEM
/// step makes thousands of small queries; allocating their buffers each time took a third of
/// one). `Tag` tells apart the uses; `which` the two sides. Queries never nest in a thread.
template <class T, int Tag>
std::vector<T>& recycled(std::size_t which = 0) {
  thread_local std::vector<T> buffers[2];
  std::vector<T>& buffer = buffers[which];
  buffer.clear();
  return buffer;
}

/// Where an intersection curve passes from one segment to the next: an edge of one mesh (its
/// vertex ids, smaller first) through a triangle of the other (sorted id). `ofA`: the edge is
/// the first mesh's.
struct EndKey {
  std::uint64_t edge = 0;
  std::uint64_t triangle = 0;
  bool operator==(const EndKey&) const noexcept = default;
};

EndKey endKey(bool ofA, std::uint32_t v0, std::uint32_t v1, std::uint32_t triangle) noexcept {
  const auto [low, high] = std::minmax(v0, v1);
  return {(std::uint64_t{low} << 32) | high, (std::uint64_t{ofA} << 32) | triangle};
}

/// Where a triangle of A crosses one of B, oriented along n_A × n_B (relative to the reference
/// point), and the faces (Face) it bounds on each.
struct Segment {
  Vec3 start, end;
  EndKey startKey, endKey;
  std::uint32_t sortedA = 0, sortedB = 0;
  std::int32_t pieceA = kAbsent, pieceB = kAbsent;
  std::size_t faceA = 0, faceB = 0;
};

/// Integrals over a part of the boundary of A ∩ B, from its boundary chain: each oriented piece
/// (p → q) of the chain of a planar face adds the fan triangle (o, p, q) from a point o of the
/// face's plane (Green's theorem: the sums depend on the chain only, not on o). In coordinates
/// relative to the query's reference point c (so that they keep their accuracy far from the
/// world's origin), with a = ½(p − o) × (q − o):
///   area += a;  areaMoment += g × a, g = (o + p + q)/3;
///   volume += o·a / 3  (the tetrahedron (c, o, p, q));  volumeMoment += that·(o + p + q)/4.
struct Integrals {
  Vec3 area, areaMoment, volumeMoment;
  double volume = 0.0;
  /// The scale of the volume's rounding (reportRegions): per face, Σ|a|₁ over its terms plus
  /// Σ|q − p|₁·|p|₁ over its boundary's pieces (their length times their distance from the
  /// reference point), times the magnitude its points round at (closeFace). A point rounds to
  /// ulps of its coordinates: a closed surface's volume moves by at most its area times the
  /// points' move; and where the pieces on the two meshes that should close it are bounded by
  /// different points of one line (faces lying on one another, an edge along the other mesh's
  /// edge), one came out ulps wide (its area vector any direction the rounding gave it) and the
  /// other of no area: it leaks a strip along the boundary, whose term is at most its area times
  /// its distance. (Measured by Σ|o·a|/3, as it was, a face whose plane passes near the
  /// reference point had a scale near 0 but not its rounding: two cubes turned alike and
  /// touching face to face, or edge to edge, gave regions of 1e-19 to 1e-17, one with the
  /// faces' whole area vector.)
  double volumeScale = 0.0;
  double areaScale = 0.0;  ///< Σ|a|₁ + Σ|q − p|₁·|p|₁ since the last closeFace

  void add(const Vec3& origin, const Vec3& p, const Vec3& q) noexcept {
    const Vec3 u = p - origin, v = q - origin;
    const Vec3 a = cross(u, v) * 0.5;
    const Vec3 g = origin + (u + v) * (1.0 / 3.0);
    area += a;
    areaMoment += cross(g, a);
    const double tetrahedron = dot(origin, a) * (1.0 / 3.0);
    volume += tetrahedron;
    const Vec3 along = v - u;  // q − p
    areaScale += std::abs(a.x) + std::abs(a.y) + std::abs(a.z) +
                 (std::abs(along.x) + std::abs(along.y) + std::abs(along.z)) *
                     (std::abs(p.x) + std::abs(p.y) + std::abs(p.z));
    volumeMoment += (origin * 3.0 + u + v) * (tetrahedron * 0.25);
  }
  void add(const Integrals& other) noexcept {
    area += other.area;
    areaMoment += other.areaMoment;
    volumeMoment += other.volumeMoment;
    volume += other.volume;
    volumeScale += other.volumeScale;
    areaScale += other.areaScale;
  }
  /// Ends a face whose points round at most at ulps of `magnitude`.
  void closeFace(double magnitude) noexcept {
    volumeScale += areaScale * magnitude;
    areaScale = 0.0;
  }
};

/// What the query learns of one triangle that crosses the other mesh or has a vertex inside it.
struct Piece {
  std::uint32_t sorted = 0;
  std::array<int, 3> parity{};     ///< per edge (corner i → i + 1): Σ σ of its crossings
  std::array<int, 3> crossings{};  ///< per edge: how many
};

/// Where an edge of a triangle crosses the other mesh: through the other's triangle that `key`
/// names, entering the other mesh (σ = +1) or leaving it (−1).
struct EdgeCrossing {
  std::int32_t piece = kAbsent;
  std::uint8_t edge = 0;
  std::int8_t sigma = 0;
  EndKey key;
  Vec3 point;  ///< relative to the reference point
  /// The other mesh's sorted triangle it passes through.
  std::uint32_t through() const noexcept { return static_cast<std::uint32_t>(key.triangle); }
};

/// Per vertex of a side that the query reaches.
struct VertexState {
  Vec3 world;
  Vec3 local;               ///< world − the query's reference point
  std::int8_t inside = -1;  ///< −1 unknown, 0 outside the other mesh, 1 inside
};

/// A triangle where it is: its world corners and their vertex slots, its box, and its plane as
/// the orientation filter needs it (the 2×2 minors of its edges from corner 0, and their
/// absolute terms for the error bound), so that a side test costs a dot product.
struct PlacedTriangle {
  std::array<Vec3, 3> p;
  std::array<std::int32_t, 3> slots;
  bool visited = false;       ///< reached by the inside/outside propagation (classify)
  std::array<Vec3, 3> local;  ///< p less the query's reference point
  Aabb box;
  Vec3 minors;     ///< (p1 − p0) × (p2 − p0), rounded
  Vec3 permanent;  ///< per component, the sum of the absolute products of its minor
};

/// Every member given (none left to be zeroed first: a query places a few dozen of these).
PlacedTriangle placedTriangle(const std::array<Vec3, 3>& p,
                              const std::array<std::int32_t, 3>& slots,
                              const std::array<Vec3, 3>& local) noexcept {
  const Aabb box{min(min(p[0], p[1]), p[2]), max(max(p[0], p[1]), p[2])};
  const Vec3 u = p[1] - p[0], v = p[2] - p[0];
  const double a = u.y * v.z, b = u.z * v.y, c = u.z * v.x, d = u.x * v.z, e = u.x * v.y,
               f = u.y * v.x;
  return {p,
          slots,
          false,
          local,
          box,
          {a - b, c - d, e - f},
          {std::abs(a) + std::abs(b), std::abs(c) + std::abs(d), std::abs(e) + std::abs(f)}};
}

/// The sign of orient(p0, p1, p2, s) where the filter decides it (Shewchuk's bound for the
/// 3×3 determinant of differences, as orientSign), 0 where it cannot.
inline int filteredSide(const PlacedTriangle& t, const Vec3& s) noexcept {
  const Vec3 w = s - t.p[0];
  const double det = dot(w, t.minors);
  const double permanent =
      std::abs(w.x) * t.permanent.x + std::abs(w.y) * t.permanent.y + std::abs(w.z) * t.permanent.z;
  const double bound = detail::kOrientErrorBound * permanent;
  // Without branches: the signs of a triangle pair's corners are a coin toss to the predictor.
  return static_cast<int>(det > bound) - static_cast<int>(-det > bound);
}

/// The side of triangle t of B on which vertex s of A lies (B perturbed).
inline int sideOfAVertex(const PlacedTriangle& t, const Vec3& s) {
  const int sign = filteredSide(t, s);
  return sign != 0 ? sign : detail::sideOfAVertex(t.p[0], t.p[1], t.p[2], s);
}

/// The side of triangle t of A on which vertex s of B lies (B perturbed).
inline int sideOfBVertex(const PlacedTriangle& t, const Vec3& s) {
  const int sign = filteredSide(t, s);
  return sign != 0 ? sign : detail::sideOfBVertex(t.p[0], t.p[1], t.p[2], s);
}

/// A map from the ids of a mesh's vertices or triangles to the query's slots for them, dense for
/// O(1) look-ups but kept from one query to the next by the thread (the slots used are reset
/// when the query ends): a DEM step compares small particles with a large obstacle many times,
/// and should not pay for the obstacle's size each time.
class SlotMap {
 public:
  /// The map of this thread for side `which` (0 or 1) and kind `kind` (0–3), sized for `count`
  /// ids. At most one query per thread at a time uses it (queries never nest).
  static SlotMap& of(std::size_t which, std::size_t kind, std::size_t count) {
    thread_local SlotMap maps[2][4];
    SlotMap& map = maps[which][kind];
    if (map.slots_.size() < count) map.slots_.resize(count, kAbsent);
    return map;
  }
  std::int32_t& operator[](std::size_t id) noexcept { return slots_[id]; }
  std::int32_t operator[](std::size_t id) const noexcept { return slots_[id]; }
  /// Marks `id` as given a slot (so that reset() clears it).
  void used(std::size_t id) { used_.push_back(id); }
  void reset() noexcept {
    for (const std::size_t id : used_)
      slots_[id] = kAbsent;
    used_.clear();
  }

 private:
  std::vector<std::int32_t> slots_;
  std::vector<std::size_t> used_;
};

/// The box of `box` moved by `motion`: its centre moved, its half extents through |R| (as the
/// trees move their boxes, dual_traversal.h). Contains every moved point of `box` up to the
/// rounding of these few operations, a few ulps of the coordinates, which the callers' margins
/// (2⁻⁴⁰ of them) cover. Nine multiply–adds where the eight moved corners took eight rotations.
Aabb movedBox(const Aabb& box, const detail::MatrixMotion& motion) noexcept {
  const Vec3 centre = motion.apply(box.center());
  const Vec3 half = box.extent() * 0.5;
  Vec3 reach;
  for (int row = 0; row < 3; ++row) {
    const Vec3 r = motion.rotation.row(row);
    reach[static_cast<std::size_t>(row)] =
        std::abs(r.x) * half.x + std::abs(r.y) * half.y + std::abs(r.z) * half.z;
  }
  return {centre - reach, centre + reach};
}

/// A float no greater than `x` (a lower bound's: −∞ below single precision's range, its largest
/// float above it), or no less (floatAbove): `x` widened by 2⁻²² of itself, more than the
/// conversion rounds, and by 2⁻¹⁴⁰, more than a subnormal's rounding.
float floatBelow(double x) noexcept {
  constexpr double kLargest = std::numeric_limits<float>::max();
  x -= 0x1p-22 * std::abs(x) + 0x1p-140;
  return x < -kLargest ? -std::numeric_limits<float>::infinity()
                       : static_cast<float>(std::min(x, kLargest));
}
float floatAbove(double x) noexcept {
  return -floatBelow(-x);
}

/// A leaf's triangles' world boxes (less the reference point, single precision, conservative)
/// and which of them meet the other mesh's box.
struct LeafBoxes {
  detail::FloatOctet boxes;
  std::uint32_t nearOther = 0;
};

/// One mesh's part of the query: its data, where it is, and what the query has learnt of it.
/// Sparse: only the vertices and triangles the query reaches get a slot (a DEM step compares a
/// small particle with a large obstacle many times).
class Side {
 public:
  Side(const QueryMesh& mesh, bool isA)
      : data_(mesh.data()),
        pose_(mesh.pose()),
        inverse_(mesh.inversePose()),
        motion_(detail::matrixMotion(mesh.pose())),
        inverseMotion_(detail::matrixMotion(mesh.inversePose())),
        moved_(mesh.moved()),
        isA_(isA),
        flip_(mesh.data().orientation < 0.0),
        vertexSlot_(SlotMap::of(isA ? 0 : 1, 0, data_.vertices.size())),
        pieceSlot_(SlotMap::of(isA ? 0 : 1, 1, data_.size())),
        triangleSlot_(SlotMap::of(isA ? 0 : 1, 2, data_.size())),
        vertices_(recycled<VertexState, 0>(isA ? 0 : 1)),
        triangles_(recycled<PlacedTriangle, 0>(isA ? 0 : 1)),
        pieces_(recycled<Piece, 0>(isA ? 0 : 1)),
        crossings_(recycled<EdgeCrossing, 0>(isA ? 0 : 1)),
        leafSlot_(SlotMap::of(isA ? 0 : 1, 3, data_.levels[0].size())),
        leafBoxes_(recycled<LeafBoxes, 0>(isA ? 0 : 1)),
        planes_(recycled<detail::SeparatingPlane, 0>(isA ? 0 : 1)) {
    // Conservative world box: the prepared box moved, grown by the motion's rounding.
    const Aabb moved = moved_ ? movedBox(data_.bounds, motion_) : data_.bounds;
    margin_ = 0x1p-40 * (maxAbs(moved.lower) + maxAbs(moved.upper) + maxAbs(pose_.translation));
    box_ = moved.grown(margin_ + data_.slack);
  }
  ~Side() {
    vertexSlot_.reset();
    pieceSlot_.reset();
    triangleSlot_.reset();
    leafSlot_.reset();
  }
  Side(const Side&) = delete;
  Side& operator=(const Side&) = delete;

  const QueryMeshData& data() const noexcept { return data_; }
  bool isA() const noexcept { return isA_; }
  const Aabb& box() const noexcept { return box_; }
  double margin() const noexcept { return margin_; }
  const RigidTransform& inversePose() const noexcept { return inverse_; }
  /// The point that the numbers are relative to, and the other mesh's world box; set before any
  /// vertex is placed.
  void setReference(const Vec3& reference, const Aabb& otherBox) noexcept {
    reference_ = reference;
    otherBox_ = otherBox;
  }

  /// Corner i of sorted triangle k, in the order that makes its normal point out of the solid
  /// (an inside-out mesh's triangles are read reversed: 0, 2, 1).
  std::uint32_t corner(std::uint32_t k, std::size_t i) const noexcept {
    return data_.corners[k][flip_ ? kReversed[i] : i];
  }
  /// The sorted triangle across edge i (corner i to corner i + 1) of sorted triangle k.
  std::uint32_t across(std::uint32_t k, std::size_t i) const {
    return data_.pseudonormals().across[k][flip_ ? 2 - i : i];
  }

  /// A world box carried into this mesh's prepared frame, conservatively.
  Aabb toPrepared(const Aabb& world) const noexcept {
    const Aabb box = moved_ ? movedBox(world, inverseMotion_) : world;
    return box.grown(0x1p-40 * (maxAbs(box.lower) + maxAbs(box.upper)) + margin_);
  }
  // A placed vertex must hold detail::predicatesExactAt: below 2⁻²⁵⁰ the query gave
  // "inconsistent crossing (internal error)" or called a closed mesh open.
  [[noreturn, gnu::cold]] void throwCoordinateTooSmall(const Vec3& p) const {
    throw Error(std::string("overlap: a vertex of the ") + (isA_ ? "first" : "second") +
                " mesh lies at " + toString(p) + (moved_ ? " (where its pose puts it)" : "") +
                ", with a coordinate below 2^-250 but not 0, where the exact predicates' products "
                "underflow; round such coordinates to 0");
  }

  /// The slot of vertex `v`, made with its world position on first use (moved as
  /// Mesh::transform moves a vertex).
  std::int32_t vertex(std::uint32_t v) {
    std::int32_t& slot = vertexSlot_[v];
    if (slot == kAbsent) {
      vertexSlot_.used(v);
      slot = static_cast<std::int32_t>(vertices_.size());
      const Vec3 world = moved_ ? motion_.apply(data_.vertices[v]) : data_.vertices[v];
      if (!detail::predicatesExactAt(world)) [[unlikely]]
        throwCoordinateTooSmall(world);
      vertices_.push_back({world, world - reference_, -1});
    }
    return slot;
  }
  VertexState& state(std::int32_t slot) noexcept {
    return vertices_[static_cast<std::size_t>(slot)];
  }

  /// Sorted triangle k where it is, made on first use. The reference holds until the next call.
  /// The look-up is inlined, the placing is not: a query looks a triangle up once a pair it is
  /// in, and the call to both was 4–6% of a volume-law DEM step.
  [[gnu::always_inline]] const PlacedTriangle& triangle(std::uint32_t k) {
    const std::int32_t slot = triangleSlot_[k];
    if (slot != kAbsent) [[likely]]
      return triangles_[static_cast<std::size_t>(slot)];
    return place(k);
  }

  /// The separating plane of sorted triangle k where it is (placed first), made on first use:
  /// for making an OverlapCache only.
  const detail::SeparatingPlane& plane(std::uint32_t k) {
    const std::array<Vec3, 3>& p = triangle(k).p;
    const auto slot = static_cast<std::size_t>(triangleSlot_[k]);
    if (planes_.size() <= slot) planes_.resize(triangles_.size(), kNoPlane);
    detail::SeparatingPlane& plane = planes_[slot];
    if (plane.magnitude < 0.0) plane = detail::separatingPlane(Triangle{p[0], p[1], p[2]});
    return plane;
  }

  /// Sorted triangle k's placed copy, by slot (stable while triangles are placed).
  PlacedTriangle& placed(std::uint32_t k) {
    triangle(k);
    return triangles_[static_cast<std::size_t>(triangleSlot_[k])];
  }
  /// The world box of `prepared`, a box in this mesh's prepared frame, conservatively.
  Aabb toWorld(const Aabb& prepared) const noexcept {
    const Aabb box = moved_ ? movedBox(prepared, motion_) : prepared;
    return box.grown(0x1p-40 * (maxAbs(box.lower) + maxAbs(box.upper)) + margin_);
  }

  /// The world boxes of leaf `leaf`'s triangles, made on first use (a leaf meets several of the
  /// other's): from the single-precision copy, moved in single precision, so that the triangles
  /// of a leaf pair are matched before any is placed. The reference holds until the next call.
  const LeafBoxes& leafBoxes(std::size_t leaf) {
    std::int32_t& slot = leafSlot_[leaf];
    if (slot != kAbsent) return leafBoxes_[static_cast<std::size_t>(slot)];
    leafSlot_.used(leaf);
    slot = static_cast<std::int32_t>(leafBoxes_.size());
    LeafBoxes& made = leafBoxes_.emplace_back();
    const std::size_t count = std::min(detail::kFanout, data_.size() - leaf * detail::kFanout);
    made.boxes =
        detail::movedLeafBoxes(data_.lanes, leaf, count, moved_ ? &motion_ : nullptr, reference_);
    // The lanes that meet the other mesh's box (the padding's are empty).
    float lower[3], upper[3];
    for (std::size_t axis = 0; axis < 3; ++axis) {
      lower[axis] = floatBelow(otherBox_.lower[axis] - reference_[axis]);
      upper[axis] = floatAbove(otherBox_.upper[axis] - reference_[axis]);
    }
    made.nearOther = detail::lanesMeeting(made.boxes, lower, upper) & ((1u << count) - 1);
    return made;
  }

  /// The piece of sorted triangle k, made on first use.
  Piece& piece(std::uint32_t k) {
    std::int32_t& slot = pieceSlot_[k];
    if (slot == kAbsent) {
      pieceSlot_.used(k);
      slot = static_cast<std::int32_t>(pieces_.size());
      Piece made;
      made.sorted = k;
      pieces_.push_back(made);
    }
    return pieces_[static_cast<std::size_t>(slot)];
  }
  std::int32_t pieceSlot(std::uint32_t k) const noexcept { return pieceSlot_[k]; }
  std::vector<Piece>& pieces() noexcept { return pieces_; }
  std::vector<EdgeCrossing>& crossings() noexcept { return crossings_; }

 private:
  /// Sorted triangle k placed in a new slot (triangle()'s first use).
  [[gnu::noinline]] const PlacedTriangle& place(std::uint32_t k) {
    triangleSlot_.used(k);
    std::array<Vec3, 3> points, local;
    std::array<std::int32_t, 3> slots;
    for (std::size_t i = 0; i < 3; ++i) {
      slots[i] = vertex(corner(k, i));
      const VertexState& state = vertices_[static_cast<std::size_t>(slots[i])];
      points[i] = state.world;
      local[i] = state.local;
    }
    const auto slot = static_cast<std::int32_t>(triangles_.size());
    triangles_.push_back(placedTriangle(points, slots, local));
    triangleSlot_[k] = slot;
    return triangles_.back();
  }

  const QueryMeshData& data_;
  RigidTransform pose_, inverse_;
  detail::MatrixMotion motion_, inverseMotion_;
  bool moved_;
  bool isA_;
  bool flip_;
  static constexpr std::size_t kReversed[3] = {0, 2, 1};
  Aabb box_;
  double margin_ = 0.0;
  Vec3 reference_;
  SlotMap &vertexSlot_, &pieceSlot_, &triangleSlot_;
  std::vector<VertexState>& vertices_;
  std::vector<PlacedTriangle>& triangles_;
  std::vector<Piece>& pieces_;
  std::vector<EdgeCrossing>& crossings_;
  SlotMap& leafSlot_;
  std::vector<LeafBoxes>& leafBoxes_;
  Aabb otherBox_;
  /// plane()'s, by triangle slot (magnitude −1: not made yet).
  std::vector<detail::SeparatingPlane>& planes_;
  static constexpr detail::SeparatingPlane kNoPlane{{}, {}, -1.0, 0.0, false};
};

/// Closed boxes that share a point.
bool meet(const Aabb& a, const Aabb& b) noexcept {
  for (std::size_t axis = 0; axis < 3; ++axis)
    if (a.lower[axis] > b.upper[axis] || b.lower[axis] > a.upper[axis]) return false;
  return true;
}

/// Every sorted triangle of `side`'s tree whose leaf box meets `worldBox` (carried into the
/// prepared frame, conservatively).
template <class Visit>
void trianglesNear(Side& side, const Aabb& worldBox, const Visit& visit) {
  const QueryMeshData& data = side.data();
  const Aabb box = side.toPrepared(worldBox);
  // The stack's capacity kept: no allocation a call.
  detail::forTrianglesMeeting(data, box, recycled<detail::TreeEntry, 0>(), [&](std::uint32_t k) {
    visit(k);
    return true;
  });
}

/// Where the segment p0 → p1 (an edge, given in the order of its vertex ids so that both
/// triangles of the edge compute the same point) crosses the plane of triangle t. Local
/// coordinates: the rounding is that of the numbers near the overlap. Only a number: where the
/// edge lies in the plane to its rounding (faces coplanar but for the rounding of their turned
/// corners) the point is anywhere along it, and crossings are ordered by crossingOrder.
Vec3 crossingPoint(const Vec3& p0, const Vec3& p1, const std::array<Vec3, 3>& t) noexcept {
  const Vec3 normal = detail::accurateNormal(t[0], t[1], t[2]);
  const double d0 = dot(p0 - t[0], normal), d1 = dot(p1 - t[0], normal);
  double lambda = 0.5;
  if (d0 != d1) lambda = std::clamp(d0 / (d0 - d1), 0.0, 1.0);
  if (!std::isfinite(lambda)) lambda = 0.5;
  return lambda == 1.0 ? p1 : p0 + (p1 - p0) * lambda;
}

/// The query's state: both sides, the reference point, the segments found.
struct Query {
  Side a, b;
  Vec3 reference;
  std::vector<Segment>& segments;
  std::size_t coplanar = 0;  ///< pairs of triangles in one plane crossed (Overlap::coplanar)

  Query(const QueryMesh& first, const QueryMesh& second)
      : a(first, true), b(second, false), segments(recycled<Segment, 0>()) {}
};

/// One end of the segment where two triangles cross: an edge of one through the other.
struct End {
  Vec3 point;
  EndKey key;
  bool start = false;
};

/// detail::edgeSign(a[i], a[i + 1], b[j], b[j + 1]) into out[i][j] for the nine pairs of edges
/// of two triangles, each of which crosses the other's plane: orientSign's filter on all nine in
/// straight-line code (the differences from each corner of `a` shared), the exact evaluation
/// only where it cannot decide. (Called one at a time, the predicate was a seventh of a
/// volume-law DEM step.)
void edgeSigns(const std::array<Vec3, 3>& a, const std::array<Vec3, 3>& b, int (&out)[3][3]) {
  int filtered[3][3];
  for (std::size_t i = 0; i < 3; ++i) {
    const Vec3& p = a[i];
    const Vec3 u = a[(i + 1) % 3] - p;
    const Vec3 d[3] = {b[0] - p, b[1] - p, b[2] - p};
    for (std::size_t j = 0; j < 3; ++j)
      filtered[i][j] = detail::filteredOrientSign(u, d[j], d[(j + 1) % 3]);
  }
  for (std::size_t i = 0; i < 3; ++i)
    for (std::size_t j = 0; j < 3; ++j)
      out[i][j] = filtered[i][j] != 0
                      ? filtered[i][j]
                      : detail::edgeSign(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
}

/// Whether triangles `a` and `b` lie apart along a direction within a's plane (a's normal
/// crossed with each edge of either): the gap between their projections exceeds the
/// projections' rounding, so that they share no point, displaced or not, and cross nowhere.
/// Asked only where the filter leaves a corner's side in doubt: faces coplanar but for the
/// rounding of their turned corners, whose boxes meet where the triangles do not, and every one
/// of whose sides and edge signs would take the exact predicates (two fans of slivers in the caps
/// of cylinders turned alike: most of their pairs).
///
/// Rounding: each projection is d·y of y = fl(x − reference), the point's local coordinates, off
/// by at most u|x − reference| per component (u = 2⁻⁵³), and the dot product by γ₃|d|·|y|; in
/// all below 5u·|d|·|y| ≤ 5u·m, m the largest |d|·|y| of the six corners. Any d serves (its own
/// rounding changes only which direction is tried), and 2⁻¹⁰⁰⁰ covers products that underflow.
bool apartInPlane(const PlacedTriangle& a, const PlacedTriangle& b) noexcept {
  const std::array<Vec3, 3>&la = a.local, &lb = b.local;
  const Vec3 edges[6] = {la[1] - la[0], la[2] - la[1], la[0] - la[2],
                         lb[1] - lb[0], lb[2] - lb[1], lb[0] - lb[2]};
  const auto magnitude = [](const Vec3& v) {
    return Vec3{std::abs(v.x), std::abs(v.y), std::abs(v.z)};
  };
  Vec3 largest = max(max(magnitude(la[0]), magnitude(la[1])), magnitude(la[2]));
  largest = max(largest, max(max(magnitude(lb[0]), magnitude(lb[1])), magnitude(lb[2])));
  for (const Vec3& edge : edges) {
    const Vec3 d = cross(a.minors, edge);
    const double a0 = dot(d, la[0]), a1 = dot(d, la[1]), a2 = dot(d, la[2]);
    const double b0 = dot(d, lb[0]), b1 = dot(d, lb[1]), b2 = dot(d, lb[2]);
    const double margin = 10.0 * 0x1p-53 * dot(magnitude(d), largest) + 0x1p-1000;
    if (std::min({b0, b1, b2}) - std::max({a0, a1, a2}) > margin ||
        std::min({a0, a1, a2}) - std::max({b0, b1, b2}) > margin)
      return true;
  }
  return false;
}

/// The crossing of triangle ta of A with triangle tb of B: at most one segment, and the crossings
/// of each one's edges with the other, added to both triangles' pieces.
void crossPair(Query& query, std::uint32_t ta, std::uint32_t tb, const PlacedTriangle& placedA,
               const PlacedTriangle& placedB) {
  const std::array<Vec3, 3>&a = placedA.p, &b = placedB.p;
  const std::array<Vec3, 3>&la = placedA.local, &lb = placedB.local;
  // Sides of each one's vertices against the other's plane (B perturbed: never 0 unless the
  // plane's triangle has zero area): the filter's, then, where it leaves one in doubt, the
  // exact predicates' unless the triangles lie apart within the plane (apartInPlane).
  bool apartTested = false;
  const auto apart = [&] {
    if (apartTested) return false;
    apartTested = true;
    return apartInPlane(placedA, placedB);
  };
  int sideA[3], sideB[3];
  for (std::size_t i = 0; i < 3; ++i)
    sideA[i] = filteredSide(placedB, a[i]);
  if (sideA[0] == 0 || sideA[1] == 0 || sideA[2] == 0) {
    if (apart()) return;
    // As detail::sideOfAVertex, counting the corners in B's plane: three make a coplanar pair,
    // whose sides the displacement alone decides (Overlap::coplanar).
    int inPlane = 0;
    for (std::size_t i = 0; i < 3; ++i)
      if (sideA[i] == 0) {
        sideA[i] = detail::orientSign(b[0], b[1], b[2], a[i]);
        if (sideA[i] == 0) {
          ++inPlane;
          sideA[i] = -detail::exactCrossLeadingSign(b[0], b[1], b[0], b[2]);
        }
      }
    if (inPlane == 3 && sideA[0] != 0) ++query.coplanar;
  }
  const bool flatB = sideA[0] == 0;  // then all three are 0
  if (!flatB && sideA[0] == sideA[1] && sideA[1] == sideA[2]) return;
  for (std::size_t j = 0; j < 3; ++j)
    sideB[j] = filteredSide(placedA, b[j]);
  if (sideB[0] == 0 || sideB[1] == 0 || sideB[2] == 0) {
    if (apart()) return;
    for (std::size_t j = 0; j < 3; ++j)
      if (sideB[j] == 0) sideB[j] = detail::sideOfBVertex(a[0], a[1], a[2], b[j]);
  }
  const bool flatA = sideB[0] == 0;
  if (flatA && flatB) return;
  if (!flatA && sideB[0] == sideB[1] && sideB[1] == sideB[2]) return;

  // edgeSign(A edge i, B edge j): all nine at once where neither triangle is flat, else each
  // when first asked (0 until then).
  int edge[3][3] = {};
  if (!flatA && !flatB) edgeSigns(a, b, edge);
  // Inlined: out of line, the call cost 1% of a volume-law DEM step.
  const auto edgeSign = [&](std::size_t i, std::size_t j) __attribute__((always_inline)) {
    if (edge[i][j] == 0) edge[i][j] = detail::edgeSign(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
    return edge[i][j];
  };
  std::array<End, 2> ends;
  std::size_t found = 0;
  const auto addEnd = [&](const End& end) {
    if (found == 2) throw Error("overlap: inconsistent crossing (internal error)");
    ends[found++] = end;
  };
  // A's edges through B's triangle.
  if (!flatB)
    for (std::size_t i = 0; i < 3; ++i) {
      const std::size_t i1 = (i + 1) % 3;
      if (sideA[i] == sideA[i1]) continue;
      const int s = edgeSign(i, 0);
      if (edgeSign(i, 1) != s || edgeSign(i, 2) != s) continue;
      const std::uint32_t v0 = query.a.corner(ta, i), v1 = query.a.corner(ta, i1);
      const Vec3 point =
          v0 < v1 ? crossingPoint(la[i], la[i1], lb) : crossingPoint(la[i1], la[i], lb);
      const EndKey key = endKey(true, v0, v1, tb);
      addEnd({point, key, sideA[i] < 0});
      Piece& piece = query.a.piece(ta);
      const int sigma = sideA[i] > 0 ? 1 : -1;  // entering B: from above its face to below
      piece.parity[i] += sigma;
      ++piece.crossings[i];
      query.a.crossings().push_back({query.a.pieceSlot(ta), static_cast<std::uint8_t>(i),
                                     static_cast<std::int8_t>(sigma), key, point});
    }
  // B's edges through A's triangle.
  if (!flatA)
    for (std::size_t j = 0; j < 3; ++j) {
      const std::size_t j1 = (j + 1) % 3;
      if (sideB[j] == sideB[j1]) continue;
      const int s = edgeSign(0, j);
      if (edgeSign(1, j) != s || edgeSign(2, j) != s) continue;
      const std::uint32_t v0 = query.b.corner(tb, j), v1 = query.b.corner(tb, j1);
      const Vec3 point =
          v0 < v1 ? crossingPoint(lb[j], lb[j1], la) : crossingPoint(lb[j1], lb[j], la);
      const EndKey key = endKey(false, v0, v1, ta);
      addEnd({point, key, sideB[j] > 0});
      Piece& piece = query.b.piece(tb);
      const int sigma = sideB[j] > 0 ? 1 : -1;  // entering A
      piece.parity[j] += sigma;
      ++piece.crossings[j];
      query.b.crossings().push_back({query.b.pieceSlot(tb), static_cast<std::uint8_t>(j),
                                     static_cast<std::int8_t>(sigma), key, point});
    }
  if (found == 0) return;
  if (found != 2 || ends[0].start == ends[1].start)
    throw Error("overlap: inconsistent crossing (internal error)");
  const End& start = ends[0].start ? ends[0] : ends[1];
  const End& end = ends[0].start ? ends[1] : ends[0];
  // On A's triangle the part inside B lies left of start → end; on B's, right of it.
  query.a.piece(ta);
  query.b.piece(tb);
  query.segments.push_back({start.point, end.point, start.key, end.key, ta, tb,
                            query.a.pieceSlot(ta), query.b.pieceSlot(tb), 0, 0});
}

/// Whether the segment from vertex `from` of `side` to a point beyond the other mesh's box
/// crosses `other` an odd number of times: `from` lies inside it. (Any such point gives the same
/// parity: it lies outside the other mesh, displaced or not.)
bool insideByRay(Side& side, Side& other, const Vec3& from) {
  // Out through the nearest face of the other's box (the shortest ray meets the fewest
  // triangles), to a point beyond it.
  const Aabb& box = other.box();
  std::size_t axis = 0;
  bool up = true;
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < 3; ++k) {
    if (box.upper[k] - from[k] < nearest) nearest = box.upper[k] - from[k], axis = k, up = true;
    if (from[k] - box.lower[k] < nearest) nearest = from[k] - box.lower[k], axis = k, up = false;
  }
  const double step = std::max({1.0, std::abs(box.upper[axis]), std::abs(box.lower[axis]),
                                box.upper[axis] - box.lower[axis]});
  Vec3 to = from;
  to[axis] = up ? box.upper[axis] + step : box.lower[axis] - step;
  Aabb ray;
  ray.extend(from);
  ray.extend(to);
  const bool segmentOfA = side.isA();
  bool inside = false;
  trianglesNear(other, ray, [&](std::uint32_t k) {
    const PlacedTriangle& placed = other.triangle(k);
    if (!meet(placed.box, ray)) return;
    const std::array<Vec3, 3>& t = placed.p;
    int s0, s1;
    if (segmentOfA) {
      s0 = sideOfAVertex(placed, from);
      s1 = sideOfAVertex(placed, to);
    } else {
      s0 = sideOfBVertex(placed, from);
      s1 = sideOfBVertex(placed, to);
    }
    if (s0 == 0 || s0 == s1) return;
    int first = 0;
    for (std::size_t e = 0; e < 3; ++e) {
      const Vec3 &p = t[e], &q = t[(e + 1) % 3];
      const int s =
          segmentOfA ? detail::edgeSign(from, to, p, q) : detail::edgeSign(p, q, from, to);
      if (e == 0)
        first = s;
      else if (s != first)
        return;
    }
    inside = !inside;
  });
  return inside;
}

/// Which of `side`'s vertices lie inside the other mesh, for every triangle with a part inside
/// it, and a piece for each such triangle. Work in proportion to those triangles: a region of
/// the surface inside the other mesh is bounded by crossings, so a walk from the crossed
/// triangles across the edges with a part inside reaches all of it. Along an edge the status
/// flips at each crossing (the parity Σσ, exact); a triangle whose corners nothing decides yet
/// takes a corner outside the other's box as outside, or one exact ray test. A connected piece
/// of the mesh that nothing crosses is wholly inside or outside: one ray test from its
/// representative vertex, where its box meets the other's.
class Classifier {
 public:
  Classifier(Side& side, Side& other) : side_(side), other_(other), otherBox_(other.box()) {}

  void run() {
    walkFromCrossings();
    classifyUncrossedComponents();
  }

 private:
  [[noreturn]] void inconsistent() const {
    throw Error(std::string("overlap: the ") + (side_.isA() ? "first" : "second") +
                " mesh's vertices are inside and outside the other along one edge: a mesh is "
                "not closed or crosses itself");
  }

  /// Decides the corners of triangle k from one another along its edges (the parity of the
  /// crossings on each, or a corner outside the other's box); false while none is known.
  bool resolve(std::uint32_t k) {
    const std::array<std::int32_t, 3> slots = side_.placed(k).slots;
    const std::int32_t pieceSlot = side_.pieceSlot(k);
    const std::array<int, 3> parity =
        pieceSlot == kAbsent ? std::array<int, 3>{}
                             : side_.pieces()[static_cast<std::size_t>(pieceSlot)].parity;
    bool known = false;
    for (const std::int32_t slot : slots)
      known |= side_.state(slot).inside != -1;
    if (!known)
      for (const std::int32_t slot : slots)
        if (!otherBox_.contains(side_.state(slot).world)) {
          side_.state(slot).inside = 0;
          known = true;
        }
    if (!known) return false;
    for (int round = 0; round < 2; ++round)
      for (std::size_t i = 0; i < 3; ++i) {
        std::int8_t& from = side_.state(slots[i]).inside;
        std::int8_t& to = side_.state(slots[(i + 1) % 3]).inside;
        if (from != -1) {
          const int expected = from + parity[i];
          if (expected != 0 && expected != 1) inconsistent();
          if (to == -1)
            to = static_cast<std::int8_t>(expected);
          else if (to != expected)
            inconsistent();
        } else if (to != -1) {
          const int expected = to - parity[i];
          if (expected != 0 && expected != 1) inconsistent();
          from = static_cast<std::int8_t>(expected);
        }
      }
    return true;
  }

  /// Triangle k (its corners decided) is a piece if a part of it is inside; the walk goes on
  /// across its edges with a part inside.
  void expand(std::uint32_t k, std::vector<std::uint32_t>& queue) {
    const std::array<std::int32_t, 3> slots = side_.placed(k).slots;
    const std::int32_t pieceSlot = side_.pieceSlot(k);
    const std::array<int, 3> crossings =
        pieceSlot == kAbsent ? std::array<int, 3>{}
                             : side_.pieces()[static_cast<std::size_t>(pieceSlot)].crossings;
    bool inside = false;
    for (std::size_t i = 0; i < 3; ++i) {
      const bool part = crossings[i] > 0 || side_.state(slots[i]).inside == 1 ||
                        side_.state(slots[(i + 1) % 3]).inside == 1;
      inside |= part;
      if (!part) continue;
      const std::uint32_t across = side_.across(k, i);
      if (across == detail::Pseudonormals::kNone) continue;
      PlacedTriangle& neighbour = side_.placed(across);
      if (neighbour.visited) continue;
      neighbour.visited = true;
      queue.push_back(across);
    }
    if (inside) side_.piece(k);
  }

  /// Phase 1: the walk from the crossed triangles across the edges with a part inside; where it
  /// stalls on triangles none of whose corners is decided, one ray test, and on.
  void walkFromCrossings() {
    std::vector<std::uint32_t>& queue = recycled<std::uint32_t, 1>();
    std::vector<std::uint32_t>& pending = recycled<std::uint32_t, 2>();
    crossed_ = side_.pieces().size();
    for (std::size_t p = 0; p < crossed_; ++p) {
      const std::uint32_t k = side_.pieces()[p].sorted;
      side_.placed(k).visited = true;
      queue.push_back(k);
    }
    while (true) {
      while (!queue.empty()) {
        const std::uint32_t k = queue.back();
        queue.pop_back();
        if (resolve(k))
          expand(k, queue);
        else
          pending.push_back(k);
      }
      if (pending.empty()) break;
      // The walk may since have decided a corner of some of these; where it has not decided
      // any, one ray test, and the walk goes on from there.
      bool decided = false;
      for (const std::uint32_t k : pending)
        for (const std::int32_t slot : side_.placed(k).slots)
          decided |= side_.state(slot).inside != -1;
      if (!decided) {
        const std::int32_t slot = side_.placed(pending.back()).slots[0];
        side_.state(slot).inside = insideByRay(side_, other_, side_.state(slot).world) ? 1 : 0;
      }
      queue.insert(queue.end(), pending.begin(), pending.end());
      pending.clear();
    }
  }

  /// Phase 2: the connected pieces of the mesh that nothing crosses, each wholly inside or
  /// outside: one ray test from its representative vertex, where its box meets the other's.
  void classifyUncrossedComponents() {
    const detail::MeshComponents& components = side_.data().components();
    if (components.count() == 1 && crossed_ > 0) return;
    std::vector<std::uint32_t>& reached = recycled<std::uint32_t, 3>();
    reached.assign(components.count(), 0);
    for (std::size_t p = 0; p < crossed_; ++p)
      reached[components.ofVertex[side_.corner(side_.pieces()[p].sorted, 0)]] = 1;
    for (std::size_t c = 0; c < components.count(); ++c) {
      if (reached[c] || !meet(side_.toWorld(components.boxes[c]), otherBox_)) continue;
      const std::int32_t slot = side_.vertex(components.representative[c]);
      if (!insideByRay(side_, other_, side_.state(slot).world)) continue;
      for (std::uint32_t t = components.offsets[c]; t < components.offsets[c + 1]; ++t) {
        const std::uint32_t k = components.triangles[t];
        for (const std::int32_t corner : side_.placed(k).slots)
          side_.state(corner).inside = 1;
        side_.piece(k);
      }
    }
  }

  Side& side_;
  Side& other_;
  const Aabb& otherBox_;
  std::size_t crossed_ = 0;  ///< the pieces the crossings made, before the walk added more
};

void classify(Side& side, Side& other) {
  Classifier(side, other).run();
}

/// A connected part of one triangle's part inside the other mesh (a triangle crossed by two
/// separate regions has two), with the integrals over it.
struct Face {
  Integrals integrals;
  bool ofA = true;
};

/// A corner of a triangle as a node of its boundary chain (crossings are nodes by their EndKey).
EndKey vertexKey(std::uint32_t vertex) noexcept {
  return {vertex, std::uint64_t{2} << 32};
}

constexpr std::size_t kNoSegment = std::numeric_limits<std::size_t>::max();

/// One oriented piece of a triangle's boundary chain, between two of its nodes.
struct Element {
  std::size_t from = 0, to = 0;  ///< nodes
  Vec3 p, q;
  std::size_t segment = kNoSegment;  ///< the Segment, or kNoSegment for a part of an edge
  std::size_t edge = 3;              ///< the triangle's edge it is a part of (3: a segment)
};

/// Union–find over small index sets, in a buffer recycled by the thread (allocated for each
/// query, the sets cost a malloc and a free each).
using UnionFind = detail::UnionFind<std::size_t>;

/// Whether the point `point` lies inside the closed chain of `elements` (those of face `face`
/// under `faceOf`), in the plane whose normal's largest component is `axis`: the parity of the
/// chain's crossings with a ray along the first other axis.
bool chainContains(const std::vector<Element>& elements, const std::vector<std::size_t>& faceOf,
                   std::size_t face, const Vec3& point, std::size_t axis) {
  const std::size_t u = (axis + 1) % 3, v = (axis + 2) % 3;
  bool inside = false;
  for (std::size_t e = 0; e < elements.size(); ++e) {
    if (faceOf[e] != face) continue;
    const Vec3 &p = elements[e].p, &q = elements[e].q;
    if ((p[v] > point[v]) == (q[v] > point[v])) continue;
    const double at = p[u] + (q[u] - p[u]) * ((point[v] - p[v]) / (q[v] - p[v]));
    if (at > point[u]) inside = !inside;
  }
  return inside;
}

/// The faces of `side`'s triangles: each triangle's boundary chain inside the other mesh (its
/// segments, and its edges' parts between the corners inside and the crossings, in order along
/// each edge), split into connected cycles; a cycle that runs clockwise inside the triangle (a
/// hole) joins the face around it. Appends them to `faces`, sets the segments' faces, and adds to
/// `joins` the pairs of faces that share a part of an edge. In phases: the crossings and
/// segments grouped by piece; then, piece by piece, its chain's elements, a face per cycle, the
/// holes joined, the faces handed over; last, the faces on either side of each edge joined.
class FaceBuilder {
 public:
  FaceBuilder(Side& side, Query& query, std::vector<Face>& faces,
              std::vector<std::pair<std::size_t, std::size_t>>& joins)
      : side_(side),
        query_(query),
        faces_(faces),
        joins_(joins),
        ofA_(side.isA()),
        pieces_(side.pieces()),
        crossings_(side.crossings()),
        count_(pieces_.size()) {}

  void run() {
    groupByPiece();
    intervalStart_.resize(3 * count_ + 1);
    for (std::size_t p = 0; p < count_; ++p) {
      if (wholeInside(p)) {
        addWhole(p);
        continue;
      }
      if (oneCycle(p)) {
        collectElements(p, false);
        handOverOneFace(p);
        continue;
      }
      collectElements(p, true);
      facesOfCycles(p);
      if (local_.size() > 1) joinHoles(p);
      handOver(p);
    }
    intervalStart_[3 * count_] = static_cast<std::uint32_t>(intervalFaces_.size());
    joinAcrossEdges();
  }

 private:
  [[noreturn]] static void inconsistent() {
    throw Error("overlap: a triangle's crossings along an edge do not alternate (internal error)");
  }

  std::size_t pieceOf(const Segment& segment) const noexcept {
    return static_cast<std::size_t>(ofA_ ? segment.pieceA : segment.pieceB);
  }

  /// Phase 1: the crossings and the segments in order of their pieces (counting sorts).
  void groupByPiece() {
    crossingStart_.assign(count_ + 1, 0);
    segmentStart_.assign(count_ + 1, 0);
    for (const EdgeCrossing& c : crossings_)
      ++crossingStart_[static_cast<std::size_t>(c.piece) + 1];
    for (const Segment& segment : query_.segments)
      ++segmentStart_[pieceOf(segment) + 1];
    std::partial_sum(crossingStart_.begin(), crossingStart_.end(), crossingStart_.begin());
    std::partial_sum(segmentStart_.begin(), segmentStart_.end(), segmentStart_.begin());
    crossingOrder_.resize(crossings_.size());
    segmentOrder_.resize(query_.segments.size());
    std::vector<std::uint32_t>& fill = recycled<std::uint32_t, 5>();
    fill.assign(crossingStart_.begin(), crossingStart_.end() - 1);
    for (std::size_t c = 0; c < crossings_.size(); ++c)
      crossingOrder_[fill[static_cast<std::size_t>(crossings_[c].piece)]++] =
          static_cast<std::uint32_t>(c);
    fill.assign(segmentStart_.begin(), segmentStart_.end() - 1);
    for (std::size_t s = 0; s < query_.segments.size(); ++s)
      segmentOrder_[fill[pieceOf(query_.segments[s])]++] = static_cast<std::uint32_t>(s);
  }

  /// Whether piece `p` lies wholly inside (most triangles of a deep overlap): no crossing, no
  /// segment, every corner inside.
  bool wholeInside(std::size_t p) const {
    const PlacedTriangle& t = side_.triangle(pieces_[p].sorted);
    return crossingStart_[p] == crossingStart_[p + 1] && segmentStart_[p] == segmentStart_[p + 1] &&
           side_.state(t.slots[0]).inside == 1 && side_.state(t.slots[1]).inside == 1 &&
           side_.state(t.slots[2]).inside == 1;
  }

  /// A whole piece: one face, its whole boundary, one interval an edge.
  void addWhole(std::size_t p) {
    const PlacedTriangle& t = side_.triangle(pieces_[p].sorted);
    Face whole{{}, ofA_};
    whole.integrals.add(t.local[0], t.local[1], t.local[2]);
    closeFace(whole.integrals, t.local, t.local[0]);
    for (std::size_t i = 0; i < 3; ++i) {
      intervalStart_[3 * p + i] = static_cast<std::uint32_t>(intervalFaces_.size());
      intervalFaces_.push_back(faces_.size());
    }
    faces_.push_back(whole);
  }

  /// Whether piece `p`'s chain is one cycle, known before it is built: one segment, and two
  /// crossings of its edges. (Both ends of a piece's only segment lie on its edges: an end where
  /// an edge of the other mesh passes through it would continue along another of its segments.
  /// The chain is then the segment and the edges' parts along one side of it.) Most crossed
  /// triangles of a DEM overlap are such a piece.
  bool oneCycle(std::size_t p) const noexcept {
    return segmentStart_[p + 1] - segmentStart_[p] == 1 &&
           crossingStart_[p + 1] - crossingStart_[p] == 2;
  }

  /// The node of `key` in the piece's chain (added where new).
  std::size_t node(const EndKey& key) {
    for (std::size_t n = 0; n < nodes_.size(); ++n)
      if (nodes_[n] == key) return n;
    nodes_.push_back(key);
    return nodes_.size() - 1;
  }

  /// Phase 2: the elements of piece `p`'s chain: its segments (oriented as the piece's side
  /// sees them), then along each edge in order the parts inside, between the corners inside and
  /// the crossings. With `nodes` false (a chain known to be one cycle), their nodes are not
  /// looked up (left 0).
  void collectElements(std::size_t p, bool nodes) {
    const std::uint32_t sorted = pieces_[p].sorted;
    const PlacedTriangle& t = side_.triangle(sorted);
    nodes_.clear();
    elements_.clear();
    const auto nodeOf = [&](const EndKey& key) { return nodes ? node(key) : 0; };
    for (std::uint32_t k = segmentStart_[p]; k < segmentStart_[p + 1]; ++k) {
      const Segment& segment = query_.segments[segmentOrder_[k]];
      if (ofA_)
        elements_.push_back({nodeOf(segment.startKey), nodeOf(segment.endKey), segment.start,
                             segment.end, segmentOrder_[k]});
      else
        elements_.push_back({nodeOf(segment.endKey), nodeOf(segment.startKey), segment.end,
                             segment.start, segmentOrder_[k]});
    }
    for (std::size_t i = 0; i < 3; ++i) {
      const std::size_t i1 = (i + 1) % 3;
      sortAlongEdge(p, i);
      int inside = side_.state(t.slots[i]).inside;
      EndKey previous = vertexKey(side_.corner(sorted, i));
      Vec3 previousPoint = t.local[i];
      for (const EdgeCrossing* c : along_) {
        if (inside == 1)
          elements_.push_back(
              {nodeOf(previous), nodeOf(c->key), previousPoint, c->point, kNoSegment, i});
        inside += c->sigma;
        previous = c->key;
        previousPoint = c->point;
      }
      if (inside != side_.state(t.slots[i1]).inside) inconsistent();
      if (inside == 1)
        elements_.push_back({nodeOf(previous), nodeOf(vertexKey(side_.corner(sorted, i1))),
                             previousPoint, t.local[i1], kNoSegment, i});
    }
  }

  /// The crossings of piece `p`'s edge `i` into `along_`, in order along it: the exact order
  /// under the displacement (detail::crossingOrder), as every other decision of the query.
  /// (Ordered by their rounded points, crossings within rounding of one another came out of
  /// order: where two unit cubes turned alike share coplanar faces, an edge lies in the other's
  /// face to an ulp, and where it crosses the planes of that face's two triangles is anywhere
  /// along it.) Crossings at one point whatever the displacement (through triangles of one
  /// plane: faces of the other mesh back to back) come in either order: among them, the one
  /// that keeps inside/outside alternating first.
  void sortAlongEdge(std::size_t p, std::size_t i) {
    along_.clear();
    for (std::uint32_t k = crossingStart_[p]; k < crossingStart_[p + 1]; ++k)
      if (crossings_[crossingOrder_[k]].edge == i) along_.push_back(&crossings_[crossingOrder_[k]]);
    if (along_.empty()) return;
    const PlacedTriangle& t = side_.triangle(pieces_[p].sorted);
    const Vec3 e0 = t.p[i], e1 = t.p[(i + 1) % 3];
    int inside = side_.state(t.slots[i]).inside;
    Side& other = ofA_ ? query_.b : query_.a;
    const auto order = [&](const EdgeCrossing* x, const EdgeCrossing* y) {
      // Copied: placed triangles' references hold until the next placing (these are placed).
      const std::array<Vec3, 3> first = other.triangle(x->through()).p;
      return detail::crossingOrder(e0, e1, first, other.triangle(y->through()).p, ofA_);
    };
    std::sort(along_.begin(), along_.end(),
              [&](const EdgeCrossing* x, const EdgeCrossing* y) { return order(x, y) < 0; });
    for (std::size_t k = 0; k < along_.size(); ++k) {
      if (inside + along_[k]->sigma == 0 || inside + along_[k]->sigma == 1) {
        inside += along_[k]->sigma;
        continue;
      }
      std::size_t swap = k + 1;
      while (swap < along_.size() && along_[swap]->sigma == along_[k]->sigma &&
             order(along_[k], along_[swap]) == 0)
        ++swap;
      if (swap == along_.size() || order(along_[k], along_[swap]) != 0) inconsistent();
      std::rotate(along_.begin() + static_cast<std::ptrdiff_t>(k),
                  along_.begin() + static_cast<std::ptrdiff_t>(swap),
                  along_.begin() + static_cast<std::ptrdiff_t>(swap) + 1);
      inside += along_[k]->sigma;
    }
  }

  /// The fans' origin o for the faces of the chain (Integrals): its first point, on the
  /// triangle's plane up to the rounding of the crossings and near every face it sums. (The
  /// triangle's corner, o before, lies as far from them as the triangle is large: a box of side
  /// 10⁶ against one of 10⁻³ summed terms of 10³ into an area of 10⁻⁶, and gave a zero area
  /// vector, a centroid 10⁴ away and a volume 12% off.)
  Vec3 fanOrigin() const noexcept { return elements_.empty() ? Vec3{} : elements_.front().p; }

  /// Ends `integrals`, a face of triangle `local` with fan origin `origin` (Integrals::closeFace):
  /// its points round at ulps of the magnitude the query computes them at about the reference
  /// point, the origin's and the face's extent (all of it within the triangle), each coordinate
  /// counted (finite here, and a bound of the largest). Not where a pose placed them: the answer
  /// is the volume of the meshes as placed (in doubles), and a placed vertex is exact from then
  /// on.
  static void closeFace(Integrals& integrals, const std::array<Vec3, 3>& local,
                        const Vec3& origin) noexcept {
    const auto sum = [](const Vec3& v) { return std::abs(v.x) + std::abs(v.y) + std::abs(v.z); };
    integrals.closeFace(sum(origin) + 2.0 * (sum(local[1] - local[0]) + sum(local[2] - local[0])));
  }

  /// Phase 3: the chain's cycles, a face per cycle (`local_`, `faceOf_` of each element), and
  /// which faces touch the triangle's edges (of piece `p`).
  void facesOfCycles(std::size_t p) {
    const Vec3 origin = fanOrigin();
    cycles_.reset(nodes_.size());
    for (const Element& e : elements_)
      cycles_.join(e.from, e.to);
    faceOfRoot_.assign(nodes_.size(), kNoSegment);
    faceOf_.resize(elements_.size());
    local_.clear();
    touchesEdge_.clear();
    for (std::size_t e = 0; e < elements_.size(); ++e) {
      const std::size_t root = cycles_.find(elements_[e].from);
      if (faceOfRoot_[root] == kNoSegment) {
        faceOfRoot_[root] = local_.size();
        local_.push_back({{}, ofA_});
        touchesEdge_.push_back(false);
      }
      faceOf_[e] = faceOfRoot_[root];
      local_[faceOf_[e]].integrals.add(origin, elements_[e].p, elements_[e].q);
      if (elements_[e].segment == kNoSegment) touchesEdge_[faceOf_[e]] = true;
    }
    const std::array<Vec3, 3>& local = side_.triangle(pieces_[p].sorted).local;
    for (Face& face : local_)
      closeFace(face.integrals, local, origin);
  }

  /// Phase 4: the holes (cycles inside the triangle that run clockwise) join the smallest face
  /// around them.
  void joinHoles(std::size_t p) {
    const PlacedTriangle& t = side_.triangle(pieces_[p].sorted);
    const Vec3 normal = cross(t.local[1] - t.local[0], t.local[2] - t.local[0]);
    std::size_t axis = 0;
    for (std::size_t k = 1; k < 3; ++k)
      if (std::abs(normal[k]) > std::abs(normal[axis])) axis = k;
    std::vector<std::size_t>& target = recycled<std::size_t, 3>();
    target.resize(local_.size());
    std::iota(target.begin(), target.end(), std::size_t{0});
    for (std::size_t h = 0; h < local_.size(); ++h) {
      if (touchesEdge_[h] || !(dot(local_[h].integrals.area, normal) < 0.0)) continue;
      Vec3 point;
      for (std::size_t e = 0; e < elements_.size(); ++e)
        if (faceOf_[e] == h) {
          point = elements_[e].p;
          break;
        }
      std::size_t best = kNoSegment;
      double bestArea = std::numeric_limits<double>::infinity();
      for (std::size_t f = 0; f < local_.size(); ++f) {
        const double area = dot(local_[f].integrals.area, normal);
        if (f == h || !(area > 0.0) || !(area < bestArea)) continue;
        if (!chainContains(elements_, faceOf_, f, point, axis)) continue;
        best = f;
        bestArea = area;
      }
      if (best != kNoSegment) target[h] = best;
    }
    for (std::size_t h = 0; h < local_.size(); ++h)
      if (target[h] != h) local_[target[h]].integrals.add(local_[h].integrals);
    for (std::size_t& f : faceOf_)
      f = target[f];
  }

  /// Phase 5: the piece's faces (those still holding an element) into the query's; each segment
  /// learns its face, and each part of an edge is recorded, in order along its edge.
  void handOver(std::size_t p) {
    std::vector<std::size_t>& global = recycled<std::size_t, 4>();
    global.assign(local_.size(), kNoSegment);
    for (std::size_t f = 0; f < local_.size(); ++f) {
      bool used = false;
      for (const std::size_t g : faceOf_)
        used |= g == f;
      if (!used) continue;
      global[f] = faces_.size();
      faces_.push_back(local_[f]);
    }
    std::size_t edge = 0;
    intervalStart_[3 * p] = static_cast<std::uint32_t>(intervalFaces_.size());
    for (std::size_t e = 0; e < elements_.size(); ++e) {
      const std::size_t face = global[faceOf_[e]];
      const Element& element = elements_[e];
      if (element.segment != kNoSegment) {
        Segment& segment = query_.segments[element.segment];
        (ofA_ ? segment.faceA : segment.faceB) = face;
        continue;
      }
      while (edge < element.edge)  // the edges' parts come in order of edges, each along it
        intervalStart_[3 * p + ++edge] = static_cast<std::uint32_t>(intervalFaces_.size());
      intervalFaces_.push_back(face);
    }
    while (edge < 2)
      intervalStart_[3 * p + ++edge] = static_cast<std::uint32_t>(intervalFaces_.size());
  }

  /// Phases 3–5 for a chain of one cycle (oneCycle): one face, summed as facesOfCycles sums it
  /// (element by element, in order), handed over as handOver hands it.
  void handOverOneFace(std::size_t p) {
    Face face{{}, ofA_};
    const Vec3 origin = fanOrigin();
    for (const Element& element : elements_)
      face.integrals.add(origin, element.p, element.q);
    closeFace(face.integrals, side_.triangle(pieces_[p].sorted).local, origin);
    const std::size_t index = faces_.size();
    faces_.push_back(face);
    std::size_t edge = 0;
    intervalStart_[3 * p] = static_cast<std::uint32_t>(intervalFaces_.size());
    for (const Element& element : elements_) {
      if (element.segment != kNoSegment) {
        Segment& segment = query_.segments[element.segment];
        (ofA_ ? segment.faceA : segment.faceB) = index;
        continue;
      }
      while (edge < element.edge)
        intervalStart_[3 * p + ++edge] = static_cast<std::uint32_t>(intervalFaces_.size());
      intervalFaces_.push_back(index);
    }
    while (edge < 2)
      intervalStart_[3 * p + ++edge] = static_cast<std::uint32_t>(intervalFaces_.size());
  }

  /// Phase 6: per piece and edge, the triangle across the edge sees the same intervals in the
  /// opposite order, and their faces join.
  void joinAcrossEdges() {
    const auto intervalsOf = [&](std::size_t p, std::size_t i) {
      return std::pair{intervalStart_[3 * p + i], intervalStart_[3 * p + i + 1]};
    };
    for (std::size_t p = 0; p < count_; ++p) {
      const std::uint32_t sorted = pieces_[p].sorted;
      for (std::size_t i = 0; i < 3; ++i) {
        const auto [from, to] = intervalsOf(p, i);
        if (from == to) continue;
        const std::uint32_t across = side_.across(sorted, i);
        const std::int32_t twin =
            across == detail::Pseudonormals::kNone ? kAbsent : side_.pieceSlot(across);
        if (twin == kAbsent) inconsistent();
        const auto other = static_cast<std::size_t>(twin);
        if (other < p) continue;  // joined from there
        std::size_t shared = 3;
        for (std::size_t j = 0; j < 3; ++j)
          if (side_.corner(across, j) == side_.corner(sorted, (i + 1) % 3) &&
              side_.corner(across, (j + 1) % 3) == side_.corner(sorted, i))
            shared = j;
        if (shared == 3) inconsistent();
        const auto [twinFrom, twinTo] = intervalsOf(other, shared);
        if (twinTo - twinFrom != to - from) inconsistent();
        for (std::uint32_t j = 0; j < to - from; ++j)
          joins_.emplace_back(intervalFaces_[from + j], intervalFaces_[twinTo - 1 - j]);
      }
    }
  }

  Side& side_;
  Query& query_;
  std::vector<Face>& faces_;
  std::vector<std::pair<std::size_t, std::size_t>>& joins_;
  const bool ofA_;
  const std::vector<Piece>& pieces_;
  const std::vector<EdgeCrossing>& crossings_;
  const std::size_t count_;
  // The scratch, kept from call to call on this thread (recycled).
  std::vector<std::uint32_t>& crossingStart_ = recycled<std::uint32_t, 1>();
  std::vector<std::uint32_t>& segmentStart_ = recycled<std::uint32_t, 2>();
  std::vector<std::uint32_t>& crossingOrder_ = recycled<std::uint32_t, 3>();
  std::vector<std::uint32_t>& segmentOrder_ = recycled<std::uint32_t, 4>();
  /// Per piece and edge, where its intervals' faces start in intervalFaces_.
  std::vector<std::uint32_t>& intervalStart_ = recycled<std::uint32_t, 6>();
  std::vector<std::size_t>& intervalFaces_ = recycled<std::size_t, 5>();
  // The piece at hand: its chain's nodes and elements, the crossings along one edge, its faces.
  std::vector<EndKey>& nodes_ = recycled<EndKey, 0>();
  std::vector<Element>& elements_ = recycled<Element, 0>();
  std::vector<const EdgeCrossing*>& along_ = recycled<const EdgeCrossing*, 0>();
  std::vector<std::size_t>& faceOfRoot_ = recycled<std::size_t, 1>();
  std::vector<std::size_t>& faceOf_ = recycled<std::size_t, 2>();
  std::vector<Face>& local_ = recycled<Face, 1>();
  std::vector<char>& touchesEdge_ = recycled<char, 0>();
  UnionFind cycles_{recycled<std::size_t, 20>()};
};

void buildFaces(Side& side, Query& query, std::vector<Face>& faces,
                std::vector<std::pair<std::size_t, std::size_t>>& joins) {
  FaceBuilder(side, query, faces, joins).run();
}

void checkMesh(const QueryMesh& mesh, const char* which) {
  if (!mesh.closed())
    throw Error(std::string("overlap: the ") + which +
                " mesh is not closed and consistently oriented (" +
                describeDefects(mesh.topology()) + "): it bounds no volume");
  const SelfIntersections& crossings = selfIntersections(mesh);
  if (crossings.any())
    throw Error(std::string("overlap: the ") + which + " mesh crosses itself (" +
                std::to_string(crossings.count) + " pairs of triangles, the first " +
                std::to_string(crossings.pairs.front().first) + " and " +
                std::to_string(crossings.pairs.front().second) + "): it bounds no volume");
  const PartNesting& nesting = partNesting(mesh);
  if (!nesting.nested())
    throw Error(std::string("overlap: the ") + which +
                " mesh bounds no solid: " + describePartNesting(nesting));
}

/// The curves through the segments: each segment's end is the next one's start.
std::vector<IntersectionCurve> chainCurves(const Query& query,
                                           const std::vector<std::size_t>& regionOfSegment) {
  std::vector<IntersectionCurve> curves;
  const std::vector<Segment>& segments = query.segments;
  // The segments by the key of their start, and of their end: sorted, searched by halves (a
  // few dozen keys; hash maps allocated a node each).
  using Keyed = std::pair<EndKey, std::size_t>;
  const auto byKey = [](const Keyed& x, const Keyed& y) {
    return std::tie(x.first.edge, x.first.triangle, x.second) <
           std::tie(y.first.edge, y.first.triangle, y.second);
  };
  std::vector<Keyed>& startingAt = recycled<Keyed, 0>();
  std::vector<Keyed>& endingAt = recycled<Keyed, 1>();
  for (std::size_t s = 0; s < segments.size(); ++s) {
    startingAt.emplace_back(segments[s].startKey, s);
    endingAt.emplace_back(segments[s].endKey, s);
  }
  std::sort(startingAt.begin(), startingAt.end(), byKey);
  std::sort(endingAt.begin(), endingAt.end(), byKey);
  // The first segment whose key is `key`, or segments.size().
  const auto find = [&](const std::vector<Keyed>& keyed, const EndKey& key) {
    const auto at = std::lower_bound(keyed.begin(), keyed.end(), Keyed{key, 0}, byKey);
    return at != keyed.end() && at->first == key ? at->second : segments.size();
  };
  std::vector<std::uint8_t>& used = recycled<std::uint8_t, 0>();
  used.assign(segments.size(), 0);
  const auto& orderA = query.a.data().order;
  const auto& orderB = query.b.data().order;
  // Open chains first start where no segment ends; then the closed loops.
  std::vector<std::size_t>& heads = recycled<std::size_t, 7>();
  for (std::size_t s = 0; s < segments.size(); ++s)
    if (find(endingAt, segments[s].startKey) == segments.size()) heads.push_back(s);
  for (std::size_t s = 0; s < segments.size(); ++s)
    heads.push_back(s);
  for (const std::size_t head : heads) {
    if (used[head] || regionOfSegment[head] == std::numeric_limits<std::size_t>::max()) continue;
    // The chain from `head`: its segments, then the curve made at its size.
    std::vector<std::size_t>& chain = recycled<std::size_t, 9>();
    bool closed = false;
    for (std::size_t s = head;;) {
      used[s] = 1;
      chain.push_back(s);
      const std::size_t next = find(startingAt, segments[s].endKey);
      if (next == segments.size() || (next != head && used[next])) break;
      if (next == head) {
        closed = true;
        break;
      }
      s = next;
    }
    IntersectionCurve curve;
    curve.region = regionOfSegment[head];
    curve.closed = closed;
    curve.points.reserve(chain.size() + 1);
    curve.trianglesA.reserve(chain.size());
    curve.trianglesB.reserve(chain.size());
    curve.points.push_back(query.reference + segments[head].start);
    for (const std::size_t s : chain) {
      const Segment& segment = segments[s];
      curve.points.push_back(query.reference + segment.end);
      curve.trianglesA.push_back(orderA[segment.sortedA]);
      curve.trianglesB.push_back(orderB[segment.sortedB]);
      curve.length += length(segment.end - segment.start);
    }
    if (closed) curve.points.back() = curve.points.front();
    curves.push_back(std::move(curve));
  }
  return curves;
}

}  // namespace

}  // namespace delta::contactdetection

namespace delta::detail {

const MeshComponents& QueryMeshData::components() const {
  std::call_once(componentsOnce_, [this] {
    MeshComponents& made = components_;
    VertexParts parts = vertexParts(vertices.size(), corners);
    made.ofVertex = std::move(parts.ofVertex);
    // Each part's first vertex met and the box of its vertices.
    made.representative.assign(parts.count, std::numeric_limits<std::uint32_t>::max());
    made.boxes.assign(parts.count, Aabb{});
    for (const TriangleIndices& c : corners)
      for (const std::uint32_t v : c) {
        const std::uint32_t part = made.ofVertex[v];
        if (made.representative[part] == std::numeric_limits<std::uint32_t>::max())
          made.representative[part] = v;
        made.boxes[part].extend(vertices[v]);
      }
    made.offsets.assign(made.representative.size() + 1, 0);
    for (const TriangleIndices& c : corners)
      ++made.offsets[made.ofVertex[c[0]] + 1];
    std::partial_sum(made.offsets.begin(), made.offsets.end(), made.offsets.begin());
    made.triangles.resize(corners.size());
    std::vector<std::uint32_t> fill(made.offsets.begin(), made.offsets.end() - 1);
    for (std::size_t k = 0; k < corners.size(); ++k)
      made.triangles[fill[made.ofVertex[corners[k][0]]]++] = static_cast<std::uint32_t>(k);
    componentsMade_.store(true, std::memory_order_release);
  });
  return components_;
}

}  // namespace delta::detail

namespace delta::contactdetection {

namespace {

/// A pair of triangles, A's and B's sorted indices, as one key: increasing keys cross them in
/// the order of A's, then B's.
std::uint64_t pairKey(std::uint32_t first, std::uint32_t second) noexcept {
  return std::uint64_t{first} << 32 | second;
}

/// Whether sorted triangle i of A and k of B (both placed) lie farther than `reach` apart by the
/// plane of one of them: all three corners of the other beyond it on one side (dual_traversal.h:
/// separated, with its margin for the rounding). A box test cannot see this for a particle's
/// triangles near a large obstacle triangle, whose box holds the whole particle.
bool planesApart(Side& a, std::uint32_t i, Side& b, std::uint32_t k, double reach) {
  const detail::SeparatingPlane& planeA = a.plane(i);
  const detail::SeparatingPlane& planeB = b.plane(k);
  const std::array<Vec3, 3>&p = a.triangle(i).p, &q = b.triangle(k).p;
  return detail::separated(planeA, Triangle{q[0], q[1], q[2]}, planeB.magnitude, reach) ||
         detail::separated(planeB, Triangle{p[0], p[1], p[2]}, planeA.magnitude, reach);
}

/// Phase 2a: every pair of triangles whose world boxes lie within `skin` of each other (0: whose
/// boxes meet), both trees descended together in A's frame, then per leaf pair the triangles
/// whose world boxes come that close (single precision, conservative; the other mesh's box grown
/// by the skin in setReference): only these are placed. Into `pairs`, by increasing keys.
void pairsWithin(Query& query, const detail::MatrixMotion& motion, bool moved, double skin,
                 std::vector<std::uint64_t>& pairs) {
  Side &a = query.a, &b = query.b;
  const detail::QueryMeshData &dataA = a.data(), &dataB = b.data();
  const detail::MovedTree secondTree(dataB.levels, moved ? &motion : nullptr);
  const double reach = 4.0 * (a.margin() + b.margin()) + dataA.slack + dataB.slack + skin;
  std::vector<detail::LeafPair>& leafPairs = recycled<detail::LeafPair, 0>();
  detail::leafPairsWithin(dataA, dataB, secondTree, reach, leafPairs);
  pairs.clear();
  for (const detail::LeafPair& pair : leafPairs) {
    const LeafBoxes& boxesB = b.leafBoxes(pair.second);
    if (boxesB.nearOther == 0) continue;
    const LeafBoxes& boxesA = a.leafBoxes(pair.first);
    const std::size_t fromA = std::size_t{pair.first} * detail::kFanout;
    const std::size_t fromB = std::size_t{pair.second} * detail::kFanout;
    for (std::uint32_t firsts = boxesA.nearOther; firsts != 0; firsts &= firsts - 1) {
      const auto lane = static_cast<std::size_t>(std::countr_zero(firsts));
      // B's lanes whose boxes come within the skin of this one's.
      float lower[3], upper[3];
      for (std::size_t axis = 0; axis < 3; ++axis) {
        lower[axis] = boxesA.boxes.lower[axis][lane];
        upper[axis] = boxesA.boxes.upper[axis][lane];
        if (skin > 0.0) {
          lower[axis] = floatBelow(double{lower[axis]} - skin);
          upper[axis] = floatAbove(double{upper[axis]} + skin);
        }
      }
      std::uint32_t hits = detail::lanesMeeting(boxesB.boxes, lower, upper);
      hits &= boxesB.nearOther;
      if (hits == 0) continue;
      const auto i = static_cast<std::uint32_t>(fromA + lane);
      const Aabb boxA = a.triangle(i).box.grown(skin);
      for (; hits != 0; hits &= hits - 1) {
        const auto k = static_cast<std::uint32_t>(fromB + std::countr_zero(hits));
        if (meet(boxA, b.triangle(k).box) && (skin == 0.0 || !planesApart(a, i, b, k, skin)))
          pairs.push_back(pairKey(i, k));
      }
    }
  }
  std::sort(pairs.begin(), pairs.end());
}

/// Phase 2b: the pairs (increasing keys) whose boxes meet crossed, their intersection segments
/// found (crossPair). A pair that does not cross adds nothing, so what this phase leaves depends
/// only on the crossing pairs and their order: the same from a cache's pairs as from a fresh
/// pairsWithin's, as long as both hold every pair that crosses.
void crossPairs(Query& query, const std::vector<std::uint64_t>& pairs) {
  Side &a = query.a, &b = query.b;
  std::uint32_t last = 0;
  const PlacedTriangle* ta = nullptr;  // A's triangle of a run of keys: B's placing leaves it
  for (const std::uint64_t key : pairs) {
    const auto i = static_cast<std::uint32_t>(key >> 32), k = static_cast<std::uint32_t>(key);
    if (ta == nullptr || i != last) {
      ta = &a.triangle(i);
      last = i;
    }
    const PlacedTriangle& tb = b.triangle(k);
    if (meet(ta->box, tb.box)) crossPair(query, i, k, *ta, tb);
  }
}

/// What a region adds up: its faces' integrals (B's volume terms in them, B's area vector apart),
/// its curves' length, its face count.
struct Sums {
  Integrals integrals;
  Vec3 areaB;
  double curveLength = 0.0;
  std::size_t faces = 0;

  void add(const Sums& sums) {
    integrals.add(sums.integrals);
    areaB += sums.areaB;
    curveLength += sums.curveLength;
    faces += sums.faces;
  }
};

/// Phase 4: the faces of both sides, and the regions, faces joined across edges and along
/// segments (into `regions`); `faces` gets the faces.
void joinRegions(Query& query, std::vector<Face>& faces, UnionFind& regions) {
  std::vector<std::pair<std::size_t, std::size_t>>& joins =
      recycled<std::pair<std::size_t, std::size_t>, 0>();
  buildFaces(query.a, query, faces, joins);
  buildFaces(query.b, query, faces, joins);
  regions.reset(faces.size());
  for (const auto& [x, y] : joins)
    regions.join(x, y);
  for (const Segment& segment : query.segments)
    regions.join(segment.faceA, segment.faceB);
}

/// Phase 5: the sums of each region, at its root.
std::vector<Sums>& sumRegions(const Query& query, const std::vector<Face>& faces,
                              UnionFind& regions) {
  std::vector<Sums>& byRoot = recycled<Sums, 0>();
  byRoot.resize(faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f) {
    Sums& sums = byRoot[regions.find(f)];
    const Integrals& integrals = faces[f].integrals;
    if (faces[f].ofA) {
      sums.integrals.add(integrals);
    } else {
      // B's faces add to the volume; their area vector is reported apart.
      sums.integrals.volume += integrals.volume;
      sums.integrals.volumeScale += integrals.volumeScale;
      sums.integrals.volumeMoment += integrals.volumeMoment;
      sums.areaB += integrals.area;
    }
    ++sums.faces;
  }
  for (const Segment& segment : query.segments)
    byRoot[regions.find(segment.faceA)].curveLength += length(segment.end - segment.start);
  return byRoot;
}

/// A region's report from its sums, about the query's reference point.
OverlapRegion regionOf(const Query& query, const Sums& sums) {
  OverlapRegion region;
  const Integrals& integrals = sums.integrals;
  region.volume = integrals.volume;
  const Vec3 offset = integrals.volumeMoment * (1.0 / integrals.volume);
  region.centroid = query.reference + offset;
  region.areaVector = integrals.area;
  region.areaVectorB = sums.areaB;
  region.moment = integrals.areaMoment - cross(offset, integrals.area);
  region.curveLength = sums.curveLength;
  region.triangles = sums.faces;
  return region;
}

/// Phase 6: the regions into `result`, largest first, and their total. A region whose volume is
/// within the rounding its terms may carry (16 ulps of Integrals::volumeScale, whose norms and
/// magnitudes are generous already) encloses nothing we can be sure of (surfaces that touch, or
/// faces that lie on one another: the perturbation puts them a zero distance apart): counted as
/// touching. Returns, per root, its region's index in result.regions (kNoSegment for none).
std::vector<std::size_t>& reportRegions(const Query& query, const std::vector<Sums>& byRoot,
                                        Overlap& result) {
  constexpr double kRoundingFactor = 16.0 * std::numeric_limits<double>::epsilon();
  std::vector<std::pair<std::size_t, Sums>>& kept = recycled<std::pair<std::size_t, Sums>, 0>();
  std::vector<Sums>& cavities = recycled<Sums, 1>();
  for (std::size_t root = 0; root < byRoot.size(); ++root) {
    const Sums& sums = byRoot[root];
    if (sums.faces == 0) continue;
    if (std::abs(sums.integrals.volume) <= kRoundingFactor * sums.integrals.volumeScale)
      ++result.touching;
    else if (sums.integrals.volume < 0.0)
      cavities.push_back(sums);
    else
      kept.emplace_back(root, sums);
  }
  std::sort(kept.begin(), kept.end(), [](const auto& x, const auto& y) {
    return x.second.integrals.volume > y.second.integrals.volume ||
           (x.second.integrals.volume == y.second.integrals.volume && x.first < y.first);
  });
  Sums total;
  std::vector<std::size_t>& regionOfRoot = recycled<std::size_t, 1>();
  regionOfRoot.assign(byRoot.size(), kNoSegment);
  for (const auto& [root, sums] : kept) {
    regionOfRoot[root] = result.regions.size();
    result.regions.push_back(regionOf(query, sums));
    total.add(sums);
  }
  for (const Sums& cavity : cavities)
    total.add(cavity);
  if (!kept.empty() && total.integrals.volume > 0.0) result.total = regionOf(query, total);
  return regionOfRoot;
}

/// The reverse query's region `region` (overlap(second, first)) as the first mesh's part: the
/// same solid, its surface's two parts swapped. ∂(A ∩ B) is closed, so ∫ (x − c) × n dA over it
/// is zero: the first mesh's part's moment is minus the second's.
OverlapRegion asFirstPart(const OverlapRegion& region) {
  OverlapRegion first = region;
  first.areaVector = region.areaVectorB;
  first.areaVectorB = region.areaVector;
  first.moment = -region.moment;
  return first;
}

/// `into`'s surface integrals made the mean of its own and `other`'s (the same solid under the
/// other displacement; its moment carried to into's centroid). Volume and centroid stay into's.
void average(OverlapRegion& into, const OverlapRegion& other) {
  const Vec3 moment = other.moment + cross(other.centroid - into.centroid, other.areaVector);
  into.areaVector = (into.areaVector + other.areaVector) * 0.5;
  into.areaVectorB = (into.areaVectorB + other.areaVectorB) * 0.5;
  into.moment = (into.moment + moment) * 0.5;
}

/// The regions `regions[k]`, k in `which` (increasing), as one: volumes, area vectors, curve
/// lengths and counts added, the centroid their volume-weighted mean, the moments carried to it.
OverlapRegion joined(const std::vector<OverlapRegion>& regions,
                     const std::vector<std::size_t>& which) {
  OverlapRegion one;
  Vec3 weighted;
  for (const std::size_t k : which) {
    one.volume += regions[k].volume;
    weighted += regions[k].centroid * regions[k].volume;
  }
  one.centroid = weighted * (1.0 / one.volume);
  for (const std::size_t k : which) {
    const OverlapRegion& region = regions[k];
    one.areaVector += region.areaVector;
    one.areaVectorB += region.areaVectorB;
    one.moment += region.moment + cross(region.centroid - one.centroid, region.areaVector);
    one.curveLength += region.curveLength;
    one.triangles += region.triangles;
  }
  return one;
}

/// Phase 7, where coplanar faces met: `result`'s integrals (B displaced by +t) averaged with
/// `reverse`'s (overlap(second, first), its regions as the first mesh's parts: B displaced by
/// −t), region by region. The two partition the same solid. Each region is matched with the
/// unmatched one of the other of the nearest centroid, where their volumes agree to 10⁻³ and
/// their centroids to 2⁻¹³ of the region's size (its curves' length and the cube root of its
/// volume). Pieces meeting only at an edge or a point may be joined under one displacement and
/// not the other (P1 + P2 and P3 one way, P1 and P2 + P3 the other: equal counts and volumes,
/// other solids): the regions left unmatched on each side are joined into one, which is then
/// the mean of both sides' joins, and the curves renumbered. False (nothing changed) where the
/// joins' volumes disagree or one side has none.
bool averageDisplacements(Overlap& result, const Overlap& reverse) {
  std::vector<OverlapRegion> other;
  for (const OverlapRegion& region : reverse.regions)
    other.push_back(asFirstPart(region));
  const std::size_t count = result.regions.size();
  constexpr std::size_t kNone = std::numeric_limits<std::size_t>::max();
  std::vector<std::size_t> partner(count, kNone);
  std::vector<bool> taken(other.size(), false);
  for (std::size_t i = 0; i < count; ++i) {
    const OverlapRegion& region = result.regions[i];
    std::size_t best = kNone;
    for (std::size_t j = 0; j < other.size(); ++j)
      if (!taken[j] && (best == kNone || distance(other[j].centroid, region.centroid) <
                                             distance(other[best].centroid, region.centroid)))
        best = j;
    if (best == kNone) continue;
    const double volume = other[best].volume;
    const double size = region.curveLength + std::cbrt(region.volume);
    if (std::abs(volume - region.volume) <= 1e-3 * std::max(volume, region.volume) &&
        distance(other[best].centroid, region.centroid) <= 0x1p-13 * size) {
      partner[i] = best;
      taken[best] = true;
    }
  }
  std::vector<std::size_t> leftA, leftB;
  for (std::size_t i = 0; i < count; ++i)
    if (partner[i] == kNone) leftA.push_back(i);
  for (std::size_t j = 0; j < other.size(); ++j)
    if (!taken[j]) leftB.push_back(j);
  if (leftA.empty() != leftB.empty()) return false;
  if (leftA.empty()) {
    for (std::size_t i = 0; i < count; ++i)
      average(result.regions[i], other[partner[i]]);
  } else {
    OverlapRegion one = joined(result.regions, leftA);
    const OverlapRegion otherOne = joined(other, leftB);
    if (!(std::abs(one.volume - otherOne.volume) <= 1e-3 * std::max(one.volume, otherOne.volume)))
      return false;
    average(one, otherOne);
    // The matched regions, averaged, and the join, largest volume first (ties in the order
    // they had, the join where its first region was); each old index's new one, for the curves.
    std::vector<std::pair<OverlapRegion, std::size_t>> kept;
    for (std::size_t i = 0; i < count; ++i)
      if (partner[i] != kNone) {
        average(result.regions[i], other[partner[i]]);
        kept.emplace_back(result.regions[i], i);
      }
    kept.emplace_back(one, leftA.front());
    std::stable_sort(kept.begin(), kept.end(), [](const auto& x, const auto& y) {
      return x.first.volume > y.first.volume ||
             (x.first.volume == y.first.volume && x.second < y.second);
    });
    std::vector<std::size_t> renumbered(count);
    result.regions.clear();
    for (const auto& [region, old] : kept) {
      renumbered[old] = result.regions.size();
      result.regions.push_back(region);
    }
    for (const std::size_t i : leftA)
      renumbered[i] = renumbered[leftA.front()];
    for (IntersectionCurve& curve : result.curves)
      if (curve.region < count) curve.region = renumbered[curve.region];
  }
  average(result.total, asFirstPart(reverse.total));
  return true;
}

}  // namespace

/// In phases: the meshes checked and placed about a reference point (1); the triangles whose
/// boxes meet crossed, their intersection segments found (2: from the cache where it holds, else
/// from a descent, which makes the cache anew where it has a skin); every triangle's corners
/// classified inside or outside the other mesh (3); the faces inside and the regions they join
/// into (4); each region's integrals summed (5); the regions reported, with their curves if
/// asked (6). overlap() then averages, where coplanar faces met, with the opposite
/// displacement's (7).
Overlap OverlapCache::oneWay(const QueryMesh& first, const QueryMesh& second,
                             const OverlapOptions& options, OverlapCache& cache) {
  checkMesh(first, "first");
  checkMesh(second, "second");
  const RigidTransform secondToFirst = detail::checkPlacedPair(first, second, "overlap");
  const detail::MatrixMotion motion = detail::matrixMotion(secondToFirst);
  const bool moved = first.moved() || second.moved();
  const bool holds =
      cache.holds(cache.moveSince(first, second, motion.rotation, motion.translation));
  // Made for meshes that shared nothing and had no triangles within the skin of each other: every
  // point of each surface lay farther than the skin from the other surface, and no distance has
  // changed by the skin since, so no point has passed into the other mesh: they share nothing.
  if (holds && cache.apart_) {
    cache.answered();
    return {};
  }
  Overlap result;
  Query query(first, second);
  Side &a = query.a, &b = query.b;
  if (!meet(a.box(), b.box())) return result;
  // The reference point: the middle of the boxes' common part (the integrals' origin, near the
  // overlap so that they keep their accuracy far from the world's origin).
  Aabb common{max(a.box().lower, b.box().lower), min(a.box().upper, b.box().upper)};
  query.reference = common.center();

  const double skin = cache.skin();
  bool making = false;
  if (holds) {
    a.setReference(query.reference, b.box());
    b.setReference(query.reference, a.box());
    crossPairs(query, cache.pairs_);
    cache.answered();
  } else if (cache.keeps()) {
    // Kept: the pairs whose boxes lie within the skin now. A pair that crosses later, after the
    // second has moved by less than the skin less what rounding can add, lies within it now:
    // the placement of the vertices (world frame) and the move's measure (the first's frame)
    // round by a few ulps of their coordinates (and of the placing translation) each; allowed
    // 2⁻³⁶ of the largest of them.
    // Forgotten first: pairsWithin refills the pairs, and a throw before keep() must not leave
    // them under the pose they were not made for.
    cache.clear();
    cache.apart_ = false;  // until this call's result is known
    a.setReference(query.reference, b.box().grown(skin));
    b.setReference(query.reference, a.box().grown(skin));
    pairsWithin(query, motion, moved, skin, cache.pairs_);
    crossPairs(query, cache.pairs_);
    const double magnitude =
        detail::placedMagnitude(a.data().bounds, b.data().bounds, secondToFirst) +
        maxAbs(motion.translation) +
        std::max({maxAbs(a.box().lower), maxAbs(a.box().upper), maxAbs(b.box().lower),
                  maxAbs(b.box().upper)});
    cache.keep(first, second, motion.rotation, motion.translation, 0x1p-36 * magnitude);
    making = true;
  } else {
    a.setReference(query.reference, b.box());
    b.setReference(query.reference, a.box());
    std::vector<std::uint64_t>& pairs = recycled<std::uint64_t, 0>();
    pairsWithin(query, motion, moved, 0.0, pairs);
    crossPairs(query, pairs);
    cache.madeWithoutKeeping();
  }

  classify(a, b);
  classify(b, a);
  std::vector<Face>& faces = recycled<Face, 0>();
  UnionFind regions(recycled<std::size_t, 21>());
  joinRegions(query, faces, regions);
  const std::vector<Sums>& byRoot = sumRegions(query, faces, regions);
  const std::vector<std::size_t>& regionOfRoot = reportRegions(query, byRoot, result);

  result.segments = query.segments.size();
  result.coplanar = query.coplanar;
  if (options.curves && !query.segments.empty()) {
    std::vector<std::size_t>& regionOfSegment = recycled<std::size_t, 8>();
    regionOfSegment.resize(query.segments.size());
    for (std::size_t s = 0; s < query.segments.size(); ++s)
      regionOfSegment[s] = regionOfRoot[regions.find(query.segments[s].faceA)];
    result.curves = chainCurves(query, regionOfSegment);
  }
  if (making)
    cache.apart_ = cache.pairs_.empty() && result.regions.empty() && result.touching == 0 &&
                   result.segments == 0 && result.total.volume == 0.0;
  return result;
}

Overlap overlap(const QueryMesh& first, const QueryMesh& second, const OverlapOptions& options,
                OverlapCache& cache) {
  Overlap result = OverlapCache::oneWay(first, second, options, cache);
  if (result.coplanar == 0 || result.regions.empty()) return result;
  if (!options.symmetric) {
    result.oneSided = true;
    return result;
  }
  // Its B displaced by −t: the first mesh's part of each region is the reverse's part of B.
  OverlapOptions reverseOptions;
  reverseOptions.curves = false;
  OverlapCache none;
  try {
    const Overlap reverse = OverlapCache::oneWay(second, first, reverseOptions, none);
    result.oneSided = !averageDisplacements(result, reverse);
  } catch (const Error&) {
    // Refused the other way round only (a coordinate at the range's edge in the other frame):
    // +t's answer stands, and says so.
    result.oneSided = true;
  }
  return result;
}

Overlap overlap(const QueryMesh& first, const QueryMesh& second, const OverlapOptions& options) {
  OverlapCache none;  // no skin: a fresh query
  return overlap(first, second, options, none);
}

}  // namespace delta::contactdetection
