#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <optional>
#include <span>

#include "delta/kernels/isa.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/query/winding_number.h"

#include "../../kernels/detail/exact_predicates.h"
#include "isa_list.h"  // generated: DELTA_ISAS (src/CMakeLists.txt)
#include "point_kernels.h"
#include "query_mesh_data.h"

// Each ISA's table, in its own translation unit (query/isa/point_table.cpp).
#define DELTA_DECLARE_TABLE(enumerator, name, lanes) \
  namespace delta::detail::name {                    \
  const PointKernels& pointKernels() noexcept;       \
  }
DELTA_ISAS(DELTA_DECLARE_TABLE)
#undef DELTA_DECLARE_TABLE

namespace delta::detail {

const PointKernels& pointKernels(kernels::Isa isa) noexcept {
  switch (kernels::supportedIsaAtMost(isa)) {
#define DELTA_TABLE(enumerator, name, lanes) \
  case kernels::Isa::enumerator:             \
    return name::pointKernels();
    DELTA_ISAS(DELTA_TABLE)
#undef DELTA_TABLE
    default:
      return scalar::pointKernels();
  }
}

Nearest nearestTriangle(const QueryMeshData& mesh, const Vec3& point,
                        double limitSquared) noexcept {
  static const PointKernels& table = pointKernels(kernels::defaultIsa());
  return table.nearest(mesh, point, limitSquared);
}

Nearest nearestTriangle(const QueryMeshData& mesh, const Vec3& point, double limitSquared,
                        kernels::Isa isa) noexcept {
  return pointKernels(isa).nearest(mesh, point, limitSquared);
}

std::size_t sieveByGrid(const GridView& grid, const Vec3* points, std::size_t count, double limit,
                        std::uint32_t* kept, bool& inRange) noexcept {
  static const PointKernels& table = pointKernels(kernels::defaultIsa());
  return table.sieve(grid, points, count, limit, kept, inRange);
}

std::size_t sieveByGrid(const GridView& grid, const Vec3* points, std::size_t count, double limit,
                        std::uint32_t* kept, bool& inRange, kernels::Isa isa) noexcept {
  return pointKernels(isa).sieve(grid, points, count, limit, kept, inRange);
}

namespace {

/// Slot `i` of octet `from` into slot `slot` of `to`: each of the arrays `fields`.
template <typename Octet, typename... Fields>
void copySlot(const Octet& from, std::size_t i, Octet& to, std::size_t slot,
              Fields... fields) noexcept {
  (((to.*fields)[slot] = (from.*fields)[i]), ...);
}

}  // namespace

bool LeafCandidates::collect(const QueryMeshData& mesh, const Vec3& center, double radiusSquared) {
  static const PointKernels& table = pointKernels(kernels::defaultIsa());
  return pack(mesh, table.collect(mesh, center, radiusSquared, found_.data()));
}

bool LeafCandidates::collect(const QueryMeshData& mesh, const Vec3& center, double radiusSquared,
                             kernels::Isa isa) {
  return pack(mesh, pointKernels(isa).collect(mesh, center, radiusSquared, found_.data()));
}

bool LeafCandidates::pack(const QueryMeshData& mesh, std::size_t found) {
  count_ = 0;
  boxes_.clear();
  cylinders_.clear();
  leaves_.clear();
  if (found > kMostCandidates) return false;
  // Empty slots: lower > upper, infinitely far away (BoxOctet); their cylinders' centres are NaN.
  BoxOctet empty;
  for (std::size_t i = 0; i < kFanout; ++i) {
    empty.lowerX[i] = empty.lowerY[i] = empty.lowerZ[i] = std::numeric_limits<float>::infinity();
    empty.upperX[i] = empty.upperY[i] = empty.upperZ[i] = -std::numeric_limits<float>::infinity();
  }
  for (std::size_t k = 0; k < found; ++k) {
    const std::size_t slot = k % kFanout;
    if (slot == 0) {
      boxes_.push_back(empty);
      cylinders_.push_back({});
      leaves_.insert(leaves_.end(), kFanout, CandidateView::kNoLeaf);
    }
    const std::uint32_t leaf = found_[k];
    const BoxOctet& from = mesh.childOctets[0][leaf / kFanout];
    const CylinderOctet& around = mesh.leafCylinders[leaf / kFanout];
    const std::size_t i = leaf % kFanout;
    copySlot(from, i, boxes_.back(), slot, &BoxOctet::lowerX, &BoxOctet::lowerY, &BoxOctet::lowerZ,
             &BoxOctet::upperX, &BoxOctet::upperY, &BoxOctet::upperZ);
    copySlot(around, i, cylinders_.back(), slot, &CylinderOctet::normalX, &CylinderOctet::normalY,
             &CylinderOctet::normalZ, &CylinderOctet::low, &CylinderOctet::high,
             &CylinderOctet::radius, &CylinderOctet::taper, &CylinderOctet::step);
    leaves_[leaves_.size() - kFanout + slot] = leaf;
  }
  count_ = found;
  return true;
}

Nearest nearestAmong(const QueryMeshData& mesh, const Vec3& point, double limitSquared,
                     const LeafCandidates& candidates) noexcept {
  static const PointKernels& table = pointKernels(kernels::defaultIsa());
  return table.among(mesh, point, limitSquared, candidates.view());
}

Nearest nearestAmong(const QueryMeshData& mesh, const Vec3& point, double limitSquared,
                     const LeafCandidates& candidates, kernels::Isa isa) noexcept {
  return pointKernels(isa).among(mesh, point, limitSquared, candidates.view());
}

Nearest resolveUnderflow(const QueryMeshData& mesh, const Vec3& point,
                         const Nearest& nearest) noexcept {
  if (!(nearest.distanceSquared < kUnderflowingSquare)) return nearest;
  double best = distanceOf(mesh, point, nearest);
  if (!(best > 0.0)) return nearest;  // on the winner: nothing is nearer
  // Every triangle whose square is below kUnderflowingSquare lies within 2⁻⁴⁸⁰ of the point, in
  // a leaf whose box meets the box of that reach around it.
  constexpr double kReach = 0x1p-479;
  Aabb around;
  around.extend(point - Vec3{kReach, kReach, kReach});
  around.extend(point + Vec3{kReach, kReach, kReach});
  Nearest resolved = nearest;
  std::vector<TreeEntry> stack;
  try {
    forTrianglesMeeting(mesh, around, stack, [&](std::uint32_t k) {
      const Triangle triangle = mesh.triangle(k);
      const kernels::PointTriangleResult r = kernels::closestPointOnTriangle(point, triangle);
      if (!(r.distanceSquared < kUnderflowingSquare)) return true;
      const double distance = kernels::distanceAtScale(point, triangle);
      if (distance < best || (distance == best && mesh.order[k] < resolved.triangle)) {
        best = distance;
        resolved.distanceSquared = r.distanceSquared;
        resolved.triangle = mesh.order[k];
        resolved.sorted = k;
        resolved.closest = r;
      }
      return true;
    });
  } catch (...) {  // the stack's memory: the search's own winner stands
    return nearest;
  }
  return resolved;
}

namespace {

/// Whether `p` lies on the closed triangle `t` exactly: in its plane and within its edges, as
/// the line from p to a point w off the plane sees them (all three orientations of one sign or
/// 0). w is p moved along the axis of the normal's largest component (computed: of an exact
/// normal that is not zero, that component is not zero either).
bool exactlyOnTriangle(const Triangle& t, const Vec3& p) {
  if (orientSign(t.a, t.b, t.c, p) != 0) return false;
  const Vec3 normal = cross(t.b - t.a, t.c - t.a);
  std::size_t axis = 0;
  for (std::size_t k = 1; k < 3; ++k)
    if (std::abs(normal[k]) > std::abs(normal[axis])) axis = k;
  if (!(std::abs(normal[axis]) > 0.0)) return false;  // zero area: its edges are its neighbours'
  Vec3 w = p;
  w[axis] += std::max(1.0, std::abs(p[axis]));
  const int e0 = orientSign(p, w, t.a, t.b), e1 = orientSign(p, w, t.b, t.c),
            e2 = orientSign(p, w, t.c, t.a);
  return !((e0 > 0 || e1 > 0 || e2 > 0) && (e0 < 0 || e1 < 0 || e2 < 0));
}

/// What a ray from a point meets.
enum class RaySide { crossed, onSurface, degenerate, inexact };

/// A ray's walk: how it ended, and where it crossed every triangle it tested (`crossed`) the
/// signed sum of its crossings, +1 for each leaving through a face's front.
struct RayWalk {
  RaySide ended = RaySide::crossed;
  int winding = 0;
};

/// Whether triangle t has zero area exactly: orient(a, b, c, s) vanishes at the four points
/// s = 0, e_x, e_y, e_z, which no plane holds all of.
bool exactlyFlat(const Triangle& t) {
  constexpr Vec3 kProbes[] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  return std::all_of(std::begin(kProbes), std::end(kProbes),
                     [&t](const Vec3& s) { return orientSign(t.a, t.b, t.c, s) == 0; });
}

/// The ray from `p` along `axis` (0, 1, 2), towards +∞ where `up`, else −∞, to a point `q` beyond
/// the mesh's box — where `skewed`, turned off the axis by about 2⁻²¹ and 2⁻²³ radians towards
/// the other two, which passes beside the copies of a vertex that a lattice of translated parts
/// lines up along the axis — : the signed sum of its crossings with the triangles that `skip(k)`
/// does not exclude (exact orientation signs: q is wherever its rounding put it). Only the
/// triangles whose leaf boxes the segment p → q meets are tested: O(log n) for a mesh whose few
/// triangles lie on any one line. A triangle of zero area is passed over: it subtends no solid
/// angle, and where the ray meets it, it meets an edge of a neighbour with area too (or only such
/// triangles, whose winding is 0).
template <class Skip>
RayWalk castRay(const QueryMeshData& mesh, const Vec3& p, std::size_t axis, bool up, bool skewed,
                std::vector<TreeEntry>& stack, const Skip& skip) {
  const double edge = up ? mesh.bounds.upper[axis] : mesh.bounds.lower[axis];
  Vec3 q = p;
  q[axis] = edge + (up ? 1.0 : -1.0) * (std::abs(edge) + 1.0);  // strictly beyond the box
  if (skewed) {
    const double span = std::abs(q[axis] - p[axis]);
    q[(axis + 1) % 3] += 0x1.3p-21 * span;
    q[(axis + 2) % 3] -= 0x1.7p-23 * span;
    if (!predicatesExactAt(q) || !isFinite(q)) return {RaySide::degenerate, 0};
  }
  Aabb segment;
  segment.extend(p);
  segment.extend(q);
  RayWalk walk;
  const bool walked = forTrianglesMeeting(mesh, segment, stack, [&](std::uint32_t k) {
    if (skip(k)) return true;
    const Triangle t = mesh.triangle(k);
    // Only a triangle whose box meets the segment can meet it.
    if (intersection(t.bounds(), segment).empty()) return true;
    if (!predicatesExactAt(t.a) || !predicatesExactAt(t.b) || !predicatesExactAt(t.c)) {
      walk.ended = RaySide::inexact;
      return false;
    }
    const int atP = orientSign(t.a, t.b, t.c, p), atQ = orientSign(t.a, t.b, t.c, q);
    if (atP == 0 && atQ == 0) {  // the ray in the triangle's plane, or no plane
      if (exactlyFlat(t)) return true;
      walk.ended = RaySide::degenerate;
      return false;
    }
    if (atP == atQ || atQ == 0) return true;  // one side, or q's plane (q lies beyond the box)
    const int e0 = orientSign(p, q, t.a, t.b), e1 = orientSign(p, q, t.b, t.c),
              e2 = orientSign(p, q, t.c, t.a);
    const bool positive = e0 > 0 || e1 > 0 || e2 > 0, negative = e0 < 0 || e1 < 0 || e2 < 0;
    if (positive && negative) return true;  // the line passes beside the triangle
    if (atP == 0) {                         // p in the triangle's plane, within its edges
      walk.ended = RaySide::onSurface;
      return false;
    }
    if (e0 == 0 || e1 == 0 || e2 == 0) {  // through an edge or vertex
      walk.ended = RaySide::degenerate;
      return false;
    }
    walk.winding += atQ;  // leaving through the face's front: +1
    return true;
  });
  if (walked) walk.ended = RaySide::crossed;
  return walk;
}

/// The first of the six axis rays from `point`, then of the six skewed ones, that decides
/// (castRay), each six in the order of their way out of the mesh's box, shortest first (a ray
/// along a row of parts would test every one of them): its walk, or `degenerate` where none
/// does. The expansions' memory may throw.
template <class Skip>
RayWalk firstDecidingRay(const QueryMeshData& mesh, const Vec3& point, const Skip& skip) {
  struct Direction {
    double way;
    std::size_t axis;
    bool up;
  };
  std::array<Direction, 6> directions;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    directions[2 * axis] = {mesh.bounds.upper[axis] - point[axis], axis, true};
    directions[2 * axis + 1] = {point[axis] - mesh.bounds.lower[axis], axis, false};
  }
  std::stable_sort(directions.begin(), directions.end(),
                   [](const Direction& x, const Direction& y) { return x.way < y.way; });
  std::vector<TreeEntry> stack;
  for (const bool skewed : {false, true})
    for (const Direction& direction : directions) {
      const RayWalk walk = castRay(mesh, point, direction.axis, direction.up, skewed, stack, skip);
      if (walk.ended != RaySide::degenerate) return walk;
    }
  return {RaySide::degenerate, 0};
}

}  // namespace

std::optional<bool> insideByExactRays(const QueryMeshData& mesh, const Vec3& point) noexcept {
  if (!predicatesExactAt(point)) return std::nullopt;
  try {
    const RayWalk walk = firstDecidingRay(mesh, point, [](std::uint32_t) { return false; });
    switch (walk.ended) {
      case RaySide::crossed:
        return walk.winding * mesh.orientation > 0.5;
      case RaySide::onSurface:
        return false;
      case RaySide::degenerate:
      case RaySide::inexact:
        return std::nullopt;
    }
  } catch (...) {  // the expansions' memory
  }
  return std::nullopt;
}

std::optional<int> windingOfOtherParts(const QueryMeshData& mesh, const Vec3& point,
                                       std::span<const std::uint32_t> partOf,
                                       std::uint32_t part) noexcept {
  if (!predicatesExactAt(point)) return std::nullopt;
  try {
    const RayWalk walk = firstDecidingRay(
        mesh, point, [&partOf, part](std::uint32_t k) { return partOf[k] == part; });
    if (walk.ended == RaySide::crossed) return walk.winding;
  } catch (...) {  // the expansions' memory
  }
  return std::nullopt;
}

std::optional<bool> insideNearSurface(const QueryMeshData& mesh, const Vec3& point,
                                      const Nearest& nearest, double distance) noexcept {
  const Triangle triangle = mesh.triangle(nearest.sorted);
  const double scale = maxAbs(nearest.closest.closest) + triangleExtent(triangle);
  if (!(distance <= 0x1p-40 * scale)) return std::nullopt;
  if (!predicatesExactAt(point) || !predicatesExactAt(triangle.a) ||
      !predicatesExactAt(triangle.b) || !predicatesExactAt(triangle.c))
    return std::nullopt;
  // On the nearest triangle (the kernel's distance 0 on an edge, or a rounding error's on the
  // face): on the surface, found at once.
  try {
    if (exactlyOnTriangle(triangle, point)) return false;
  } catch (...) {  // the expansions' memory
    return std::nullopt;
  }
  return insideByExactRays(mesh, point);
}

bool insideAt(const QueryMeshData& mesh, const Vec3& point, const Nearest& nearest) noexcept {
  // Outside the box of the vertices is outside the solid. (Far from the mesh, beyond about 1e16
  // of its size, the squared distances of all its triangles round alike and the nearest is the
  // smallest id among them, whose feature's normal may face away: its side is no answer there.)
  if (!mesh.bounds.contains(point)) return false;
  // Within rounding of the surface the offset from the closest point turns with the closest
  // point's own rounding (a point 3e-17 outside a unit sphere's mesh was inside), and a distance
  // may round to 0 off the surface: decided exactly there.
  const double distance = distanceOf(mesh, point, nearest);
  if (const std::optional<bool> exact = insideNearSurface(mesh, point, nearest, distance))
    return *exact;
  if (!(distance > 0.0)) return false;  // on the surface
  // The features VertexA … EdgeCA are the pseudonormal slots 0 … 5, in that order; a face point
  // takes the face's own normal.
  static_assert(static_cast<int>(kernels::TriangleFeature::VertexA) == 0 &&
                static_cast<int>(kernels::TriangleFeature::EdgeAB) == 3 &&
                static_cast<int>(kernels::TriangleFeature::EdgeCA) == 5);
  const kernels::TriangleFeature feature = nearest.closest.feature;
  const Vec3 normal = feature == kernels::TriangleFeature::Face
                          ? mesh.triangle(nearest.sorted).areaVector()
                          : mesh.pseudonormal(nearest.sorted, static_cast<std::size_t>(feature));
  const Vec3 offset = point - nearest.closest.closest;
  const double side = dot(offset, normal) * mesh.orientation;
  // Exactly, the side is positive outside and negative inside (Bærentzen and Aanæs); where it
  // is within rounding of zero (a degenerate triangle's zero normal, a point almost tangent to
  // the surface) the exact rays decide, or where each of them is degenerate the winding number,
  // O(n) but robust.
  if (std::abs(side) > 1e-9 * length(offset) * length(normal)) return side < 0.0;
  if (const std::optional<bool> exact = insideByExactRays(mesh, point)) return *exact;
  const auto triangleAt = [&mesh](std::size_t k) { return mesh.triangle(k); };
  return windingNumber(mesh.size(), triangleAt, point) * mesh.orientation > 0.5;
}

}  // namespace delta::detail
