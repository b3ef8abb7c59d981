#include "delta/kernels/triangle_triangle.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "delta/mesh/coordinate_range.h"

#include "detail/exact_predicates.h"
#include "detail/robust_geometry.h"

namespace delta::kernels {
namespace {

using detail::LocalTriangle;

/// The touching tolerance τ, in units of ε·R, R the largest local coordinate of the six vertices:
/// every distance and every height above a plane below is computed to a few ε·R, so pairs closer
/// than τ are decided "touching" (distance 0). τ ≈ 7e-15·R, far below the 1e-12·size the kernel
/// is tested to.
constexpr double kTouchingUlps = 32.0;

/// Both triangles in the frame of the first one's first vertex: differences of nearby large
/// coordinates are exact, so the kernel is as accurate relative to the size at 1e6 as at 0.
struct LocalPair {
  Vec3 origin;
  LocalTriangle first;
  LocalTriangle second;
  double touching = 0.0;  ///< τ
  /// The triangles as given (for the exact face test, faceCandidate).
  const Triangle* givenFirst = nullptr;
  const Triangle* givenSecond = nullptr;
};

LocalPair makeLocalPair(const Triangle& a, const Triangle& b) noexcept {
  LocalPair pair;
  pair.origin = a.a;
  pair.first = detail::makeLocalTriangle({}, a.b - pair.origin, a.c - pair.origin);
  pair.second = detail::makeLocalTriangle(b.a - pair.origin, b.b - pair.origin, b.c - pair.origin);
  double largest = 0.0;
  for (const LocalTriangle* t : {&pair.first, &pair.second})
    for (const Vec3& v : t->vertex)
      largest = std::max({largest, std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
  pair.touching = kTouchingUlps * detail::kEpsilon * largest;
  pair.givenFirst = &a;
  pair.givenSecond = &b;
  return pair;
}

/// Whether all vertices of `other` lie further than τ from the plane of `t`, on one side (then
/// the triangles are further than τ apart; Möller's first rejection test).
bool separatedByPlane(const LocalTriangle& t, const LocalTriangle& other,
                      double touching) noexcept {
  if (t.flat) return false;
  const double bound = touching * std::sqrt(t.normalLengthSquared);
  const double h0 = dot(t.normal, other.vertex[0] - t.vertex[0]);
  const double h1 = dot(t.normal, other.vertex[1] - t.vertex[0]);
  const double h2 = dot(t.normal, other.vertex[2] - t.vertex[0]);
  return (h0 > bound && h1 > bound && h2 > bound) || (h0 < -bound && h1 < -bound && h2 < -bound);
}

bool separated(const LocalPair& pair) noexcept {
  return separatedByPlane(pair.first, pair.second, pair.touching) ||
         separatedByPlane(pair.second, pair.first, pair.touching);
}

/// If segment e0 → e1 crosses the plane of the non-flat triangle `t` with both ends further than
/// τ from it, on opposite sides, and the crossing point lies inside `t` by more than the rounding
/// of the areas that decide it and of the point itself, stores that point and returns true.
/// Crossings this test misses (an end within τ of the plane, a crossing within rounding of the
/// triangle's boundary) are touching candidates: some vertex–face or edge–edge distance is then
/// within τ, or the triangles do not meet. (Without the rounding, a segment passing just beyond
/// the tip of a needle, whose edges' lines meet there at an angle below it, pierced it: an audit
/// found 3.9e-7 apart called intersecting.)
///
/// The crossing point's rounding: the heights h₀, h₁ are within 24εR|n| of the exact ones (R the
/// largest local coordinate, τ = 32εR), so the parameter h₀/(h₀ − h₁) is off by at most
/// 0.75τ|n|/(|h₀| + |h₁|) + 3ε, and the point by that times |e₁ − e₀| plus 3εR; the areas move
/// by |n|·|e|·that (faceAreaBound's margin for the rest).
bool pierces(const Vec3& e0, const Vec3& e1, const LocalTriangle& t, double touching,
             Vec3& crossing) noexcept {
  if (t.flat) return false;
  const double bound = touching * std::sqrt(t.normalLengthSquared);
  const double h0 = dot(t.normal, e0 - t.vertex[0]);
  const double h1 = dot(t.normal, e1 - t.vertex[0]);
  if (!((h0 > bound && h1 < -bound) || (h0 < -bound && h1 > bound))) return false;
  const Vec3 along = e1 - e0;
  const Vec3 x = e0 + along * (h0 / (h0 - h1));
  const double moved =
      (bound / (std::abs(h0) + std::abs(h1)) + 4.0 * detail::kEpsilon) * detail::normOne(along) +
      touching / 8.0;
  const double normalSize = detail::normOne(t.normal), point = detail::normOne(x);
  const double longest = std::sqrt(t.longestEdgeSquared);
  for (int k = 0; k < 3; ++k) {
    const Vec3 w = x - t.vertex[k];
    const double margin = detail::faceAreaBound(t.edge[k], w, normalSize, point, longest) +
                          2.0 * normalSize * detail::normOne(t.edge[k]) * moved;
    if (!(dot(t.normal, cross(t.edge[k], w)) > margin)) return false;
  }
  crossing = x;
  return true;
}

// Exact intersection, where the rounded tests above leave no witness: some pairs that meet do
// so only within the rounding of those tests (an edge crossing a needle within the rounding of
// its boundary, a vertex resting on a face whose distances round to more than τ), and there the
// orientation signs of the given coordinates decide (exact_predicates.h).

/// The exact sign of the orientation of p, q, r projected along `axis` (that coordinate
/// dropped, the other two in cyclic order): the sign of `axis`'s component of (q − p) × (r − p),
/// which is orient of the projected points and one lifted by 1 along the projection, all of
/// them exact doubles.
int projectedOrientSign(const Vec3& p, const Vec3& q, const Vec3& r, int axis) noexcept {
  const auto project = [axis](const Vec3& v, double lift) {
    return Vec3{v[(axis + 1) % 3], v[(axis + 2) % 3], lift};
  };
  const Vec3 pp = project(p, 0.0);
  return detail::orientSign(pp, project(q, 0.0), project(r, 0.0), project(p, 1.0));
}

/// Whether `p` lies on the closed segment a–b, given that the three are collinear in the
/// projection along `axis`: between a and b in both kept coordinates.
bool withinProjectedSegment(const Vec3& p, const Vec3& a, const Vec3& b, int axis) noexcept {
  for (const int k : {(axis + 1) % 3, (axis + 2) % 3})
    if (p[k] < std::min(a[k], b[k]) || p[k] > std::max(a[k], b[k])) return false;
  return true;
}

/// Whether the closed segments p0–p1 and q0–q1 meet in the projection along `axis` (either may
/// be a point).
bool projectedSegmentsMeet(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1,
                           int axis) noexcept {
  const int o0 = projectedOrientSign(p0, p1, q0, axis), o1 = projectedOrientSign(p0, p1, q1, axis);
  const int o2 = projectedOrientSign(q0, q1, p0, axis), o3 = projectedOrientSign(q0, q1, p1, axis);
  if (o0 * o1 < 0 && o2 * o3 < 0) return true;
  return (o0 == 0 && withinProjectedSegment(q0, p0, p1, axis)) ||
         (o1 == 0 && withinProjectedSegment(q1, p0, p1, axis)) ||
         (o2 == 0 && withinProjectedSegment(p0, q0, q1, axis)) ||
         (o3 == 0 && withinProjectedSegment(p1, q0, q1, axis));
}

/// Whether `p` lies in the closed triangle t, in the projection along `axis` (t's projection of
/// non-zero area).
bool insideProjectedTriangle(const Vec3& p, const Triangle& t, int axis) noexcept {
  const int s0 = projectedOrientSign(t.a, t.b, p, axis),
            s1 = projectedOrientSign(t.b, t.c, p, axis),
            s2 = projectedOrientSign(t.c, t.a, p, axis);
  return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

/// Whether the closed segment p–q, lying in the plane of the triangle t (of non-zero area in the
/// projection along `axis`), meets t.
bool projectedSegmentMeetsTriangle(const Vec3& p, const Vec3& q, const Triangle& t,
                                   int axis) noexcept {
  return insideProjectedTriangle(p, t, axis) || projectedSegmentsMeet(p, q, t.a, t.b, axis) ||
         projectedSegmentsMeet(p, q, t.b, t.c, axis) || projectedSegmentsMeet(p, q, t.c, t.a, axis);
}

/// An axis along which t (of non-zero area) projects to non-zero area: the normal's largest
/// rounded component, checked exactly (the others where rounding misled).
int projectionAxis(const Triangle& t) noexcept {
  const Vec3 n = t.areaVector();
  const double size[3] = {std::fabs(n.x), std::fabs(n.y), std::fabs(n.z)};
  const int largest =
      size[0] >= size[1] ? (size[0] >= size[2] ? 0 : 2) : (size[1] >= size[2] ? 1 : 2);
  for (int k = 0; k < 3; ++k)
    if (const int axis = (largest + k) % 3; projectedOrientSign(t.a, t.b, t.c, axis) != 0)
      return axis;
  return largest;  // not reached for a triangle of non-zero area
}

/// How a closed segment meets a closed triangle.
enum class Meeting { kNone, kAcross, kWithinPlane };

/// How the closed segment p–q meets the closed triangle t of non-zero area, given the exact
/// orientations of p and q against t's plane: crossing the plane (or touching it at an end), or
/// lying in it.
Meeting segmentMeetsTriangle(const Vec3& p, const Vec3& q, int sideP, int sideQ,
                             const Triangle& t) noexcept {
  if (sideP * sideQ > 0) return Meeting::kNone;
  if (sideP == 0 && sideQ == 0)
    return projectedSegmentMeetsTriangle(p, q, t, projectionAxis(t)) ? Meeting::kWithinPlane
                                                                     : Meeting::kNone;
  // The line p–q crosses the plane at one point, which is inside t where the line passes every
  // edge on the same side.
  const int s0 = detail::orientSign(p, q, t.a, t.b), s1 = detail::orientSign(p, q, t.b, t.c),
            s2 = detail::orientSign(p, q, t.c, t.a);
  return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0) ? Meeting::kAcross
                                                                            : Meeting::kNone;
}

/// Whether the exact predicates answer for these coordinates: within the coordinate range, and
/// none so small that their products would underflow (exact_predicates.h).
bool exactlyDecidable(const Triangle& t) noexcept {
  for (const Vec3& v : {t.a, t.b, t.c})
    if (!inCoordinateRange(v) || !detail::predicatesExactAt(v)) return false;
  return true;
}

/// Whether t has zero area exactly (its corners on one line, or one point).
bool exactlyFlat(const Triangle& t) noexcept {
  return detail::exactCrossLeadingSign(t.a, t.b, t.a, t.c) == 0;
}

/// Whether the closed triangles meet, decided exactly on the coordinates as given; false where
/// the exact predicates cannot answer (coordinates beyond their range) or both triangles have
/// zero area (then the rounded tests alone decide: segments and points, whose distances the
/// candidates give to a few ulps). `across` gets a bit for each edge that meets the other
/// triangle across its plane: bit k for the first's edge k (corner k to k + 1), 3 + k for the
/// second's.
bool intersectExactly(const Triangle& first, const Triangle& second, unsigned& across) noexcept {
  across = 0;
  if (!exactlyDecidable(first) || !exactlyDecidable(second)) return false;
  const bool firstFlat = exactlyFlat(first), secondFlat = exactlyFlat(second);
  if (firstFlat && secondFlat) return false;
  const std::array<Vec3, 3> corners[2] = {{first.a, first.b, first.c},
                                          {second.a, second.b, second.c}};
  const Triangle* triangles[2] = {&first, &second};
  std::array<int, 3> sides[2];  // each triangle's corners against the other's plane
  for (int m = 0; m < 2; ++m) {
    const Triangle& other = *triangles[1 - m];
    for (int k = 0; k < 3; ++k)
      sides[m][k] = detail::orientSign(other.a, other.b, other.c, corners[m][k]);
  }
  const auto oneSide = [](const std::array<int, 3>& s) {
    return (s[0] > 0 && s[1] > 0 && s[2] > 0) || (s[0] < 0 && s[1] < 0 && s[2] < 0);
  };
  // (Against a triangle of zero area every side is 0: no shortcut.)
  if ((!secondFlat && oneSide(sides[0])) || (!firstFlat && oneSide(sides[1]))) return false;
  if (!firstFlat && !secondFlat && sides[1] == std::array<int, 3>{}) {
    // One plane: the projections overlap where two edges meet or one contains the other.
    const int axis = projectionAxis(first);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (projectedSegmentsMeet(corners[0][i], corners[0][(i + 1) % 3], corners[1][j],
                                  corners[1][(j + 1) % 3], axis))
          return true;
    return insideProjectedTriangle(first.a, second, axis) ||
           insideProjectedTriangle(second.a, first, axis);
  }
  // Two planes: the triangles meet along their common line, where the two intervals they cut
  // from it overlap, and an end of the overlap is where an edge of one meets the other. A
  // triangle of zero area is the union of its edges, each against the other triangle.
  bool meet = false;
  for (int m = 0; m < 2; ++m) {
    if (m == 0 ? secondFlat : firstFlat) continue;  // edges against a triangle of zero area
    for (int k = 0; k < 3; ++k) {
      const int next = (k + 1) % 3;
      const Meeting meeting = segmentMeetsTriangle(corners[m][k], corners[m][next], sides[m][k],
                                                   sides[m][next], *triangles[1 - m]);
      if (meeting == Meeting::kAcross) across |= 1u << (3 * m + k);
      meet = meet || meeting != Meeting::kNone;
    }
  }
  return meet;
}

/// Where the segment e0 → e1 crosses the plane of t, its parameter clamped to the segment (where
/// it crosses exactly but the rounded heights do not say so).
Vec3 planeCrossing(const Vec3& e0, const Vec3& e1, const LocalTriangle& t) noexcept {
  const double h0 = dot(t.normal, e0 - t.vertex[0]), h1 = dot(t.normal, e1 - t.vertex[0]);
  const double along = h0 != h1 ? std::clamp(h0 / (h0 - h1), 0.0, 1.0) : 0.5;
  return e0 + (e1 - e0) * along;
}

/// One of the 15 candidate pairs of closest points, with the seed's barycentric unknowns.
struct Candidate {
  Vec3 p;
  Vec3 q;
  double distanceSquared = std::numeric_limits<double>::infinity();  ///< none yet
  double a1 = 0.0, a2 = 0.0, a3 = 0.0, a4 = 0.0;
};

/// Barycentrics (coefficients of b − a and c − a) of vertex i.
void vertexCoordinates(int i, double& u, double& v) noexcept {
  u = i == 1 ? 1.0 : 0.0;
  v = i == 2 ? 1.0 : 0.0;
}

/// Barycentrics of the point at parameter s of edge i (from vertex i to vertex i + 1).
void edgeCoordinates(int i, double s, double& u, double& v) noexcept {
  switch (i) {
    case 0:
      u = s, v = 0.0;
      break;
    case 1:
      u = 1.0 - s, v = s;
      break;
    default:
      u = 0.0, v = 1.0 - s;
      break;
  }
}

/// Corner i (0, 1, 2: a, b, c) of t.
const Vec3& cornerOf(const Triangle& t, int i) noexcept {
  return i == 0 ? t.a : i == 1 ? t.b : t.c;
}

/// The projection of local vertex `v` (`given` as given) onto the face of local triangle `t`
/// (`triangle` as given) into `result`, where it falls inside (closestPointOnTriangle's face
/// test: the rounded areas, and exact signs within their rounding of an edge's line); false
/// otherwise.
bool faceCandidate(const Vec3& v, const Vec3& given, const LocalTriangle& t,
                   const Triangle& triangle, PointTriangleResult& result) noexcept {
  detail::FaceAreas areas;
  unsigned nearEdges = 0;
  const detail::FaceSide side = detail::sideOfLocalFace(v, t, areas, nearEdges);
  if (side == detail::FaceSide::kOutside ||
      (side == detail::FaceSide::kNearEdge && !detail::insideNearEdges(given, triangle, nearEdges)))
    return false;
  result = detail::projectOntoLocalFace(v, t, areas);
  return true;
}

/// Candidates 0–2: vertex i of the first triangle onto the second's face; 3–5: vertex i of the
/// second onto the first's face; 6–14: edge (index − 6) / 3 of the first to edge (index − 6) % 3
/// of the second. A vertex–face candidate whose projection falls outside the face (or onto a flat
/// triangle) does not exist (infinite distance): the edge–edge candidates cover those distances.
Candidate candidate(const LocalPair& pair, int index) noexcept {
  Candidate c;
  PointTriangleResult r;
  if (index < 3) {
    const Vec3& v = pair.first.vertex[index];
    if (!faceCandidate(v, cornerOf(*pair.givenFirst, index), pair.second, *pair.givenSecond, r))
      return c;
    c.p = v, c.q = r.closest, c.distanceSquared = r.distanceSquared;
    vertexCoordinates(index, c.a1, c.a2);
    c.a3 = r.u, c.a4 = r.v;
  } else if (index < 6) {
    const Vec3& v = pair.second.vertex[index - 3];
    if (!faceCandidate(v, cornerOf(*pair.givenSecond, index - 3), pair.first, *pair.givenFirst, r))
      return c;
    c.p = r.closest, c.q = v, c.distanceSquared = r.distanceSquared;
    c.a1 = r.u, c.a2 = r.v;
    vertexCoordinates(index - 3, c.a3, c.a4);
  } else {
    const int i = (index - 6) / 3, j = (index - 6) % 3;
    const detail::SegmentPair s =
        detail::closestOnSegments(pair.first.vertex[i], pair.first.vertex[(i + 1) % 3],
                                  pair.second.vertex[j], pair.second.vertex[(j + 1) % 3]);
    c.p = s.p, c.q = s.q, c.distanceSquared = s.distanceSquared;
    edgeCoordinates(i, s.s, c.a1, c.a2);
    edgeCoordinates(j, s.t, c.a3, c.a4);
  }
  return c;
}

constexpr int kCandidates = 15;

}  // namespace

TriangleDistanceResult triangleDistanceBruteForce(const Triangle& first,
                                                  const Triangle& second) noexcept {
  const LocalPair pair = makeLocalPair(first, second);
  Candidate candidates[kCandidates];
  int nearest = 0;
  for (int k = 0; k < kCandidates; ++k) {
    candidates[k] = candidate(pair, k);
    if (candidates[k].distanceSquared < candidates[nearest].distanceSquared) nearest = k;
  }

  // Intersection: an edge piercing the other triangle's interior, or a candidate within τ
  // (touching). Both kinds of witness lie on both triangles (to τ); the intersection of two
  // triangles is convex and its extreme points are among them (each lies where an edge of one
  // meets the other), so the midpoint of the two furthest apart is a point of the intersection:
  // the middle of the intersection segment, or a point inside a coplanar overlap.
  if (!separated(pair)) {
    Vec3 witnesses[6 + kCandidates];
    int count = 0;
    for (int i = 0; i < 3; ++i) {
      const LocalTriangle& a = pair.first;
      const LocalTriangle& b = pair.second;
      if (pierces(a.vertex[i], a.vertex[(i + 1) % 3], b, pair.touching, witnesses[count])) ++count;
      if (pierces(b.vertex[i], b.vertex[(i + 1) % 3], a, pair.touching, witnesses[count])) ++count;
    }
    const double touchingSquared = pair.touching * pair.touching;
    for (const Candidate& c : candidates)
      if (c.distanceSquared <= touchingSquared) witnesses[count++] = (c.p + c.q) * 0.5;
    // Meeting only within the rounding of those tests: the exact signs decide, and the points
    // where edges cross the other's plane (or the nearest candidates) are the witnesses.
    if (unsigned across = 0; count == 0 && intersectExactly(first, second, across)) {
      for (int k = 0; k < 3; ++k) {
        const LocalTriangle& a = pair.first;
        const LocalTriangle& b = pair.second;
        // (Not across a plane that is lost in its rounding: a flat local triangle's normal.)
        if ((across & (1u << k)) && !b.flat)
          witnesses[count++] = planeCrossing(a.vertex[k], a.vertex[(k + 1) % 3], b);
        if ((across & (8u << k)) && !a.flat)
          witnesses[count++] = planeCrossing(b.vertex[k], b.vertex[(k + 1) % 3], a);
      }
      if (count == 0) witnesses[count++] = (candidates[nearest].p + candidates[nearest].q) * 0.5;
    }
    if (count > 0) {
      int from = 0, to = 0;
      double widest = -1.0;
      for (int i = 0; i < count; ++i)
        for (int j = i; j < count; ++j)
          if (const double d = distanceSquared(witnesses[i], witnesses[j]); d > widest)
            widest = d, from = i, to = j;
      const Vec3 x = (witnesses[from] + witnesses[to]) * 0.5;
      const PointTriangleResult onFirst = detail::closestOnLocalTriangle(x, pair.first);
      const PointTriangleResult onSecond = detail::closestOnLocalTriangle(x, pair.second);
      const Vec3 point = x + pair.origin;
      return {0.0, point, point, onFirst.u, onFirst.v, onSecond.u, onSecond.v, true};
    }
  }

  const Candidate& c = candidates[nearest];
  return {c.distanceSquared, c.p + pair.origin, c.q + pair.origin, c.a1, c.a2, c.a3, c.a4, false};
}

bool trianglesIntersect(const Triangle& first, const Triangle& second) noexcept {
  // The same decision as triangleDistanceBruteForce, with early exits.
  const LocalPair pair = makeLocalPair(first, second);
  if (separated(pair)) return false;
  Vec3 crossing;
  for (int i = 0; i < 3; ++i) {
    const LocalTriangle& a = pair.first;
    const LocalTriangle& b = pair.second;
    if (pierces(a.vertex[i], a.vertex[(i + 1) % 3], b, pair.touching, crossing)) return true;
    if (pierces(b.vertex[i], b.vertex[(i + 1) % 3], a, pair.touching, crossing)) return true;
  }
  const double touchingSquared = pair.touching * pair.touching;
  for (int k = 0; k < kCandidates; ++k)
    if (candidate(pair, k).distanceSquared <= touchingSquared) return true;
  unsigned across = 0;
  return intersectExactly(first, second, across);
}

}  // namespace delta::kernels
