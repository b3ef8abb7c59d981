#include "delta/kernels/triangle_triangle.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

/// Candidates 0–2: vertex i of the first triangle onto the second's face; 3–5: vertex i of the
/// second onto the first's face; 6–14: edge (index − 6) / 3 of the first to edge (index − 6) % 3
/// of the second. A vertex–face candidate whose projection falls outside the face (or onto a flat
/// triangle) does not exist (infinite distance): the edge–edge candidates cover those distances.
Candidate candidate(const LocalPair& pair, int index) noexcept {
  Candidate c;
  PointTriangleResult r;
  if (index < 3) {
    const Vec3& v = pair.first.vertex[index];
    if (!detail::closestOnLocalFace(v, pair.second, r)) return c;
    c.p = v, c.q = r.closest, c.distanceSquared = r.distanceSquared;
    vertexCoordinates(index, c.a1, c.a2);
    c.a3 = r.u, c.a4 = r.v;
  } else if (index < 6) {
    const Vec3& v = pair.second.vertex[index - 3];
    if (!detail::closestOnLocalFace(v, pair.first, r)) return c;
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
  return false;
}

}  // namespace delta::kernels
