#pragma once

// The hybrid solver's SIMD stages for W pairs, branch-free. First stage: from the penalty Newton
// point, pick the features the minimum lies on, solve them in closed form, and certify the
// answer by the optimality (KKT) conditions of this convex problem; separately, certify an
// intersection by an edge that clearly pierces the other triangle. Second stage, for the lanes
// the first could not certify: the same with all 15 candidates. Lanes that certify neither go to
// the scalar brute force (src/kernels/hybrid.cpp).

#include "delta/kernels/detail/lanes.h"
#include "delta/kernels/detail/pair_lanes.h"
#include "delta/kernels/detail/penalty_newton.h"

namespace delta::detail {

/// Tolerances of the certificates, relative to the pair's size L (its longest edge).
struct HybridTolerances {
  /// A candidate (P, Q) is accepted when its duality gap G (see penaltyLanes) is at most
  /// kGap·L·|P − Q|: then |P − Q| − d* ≤ G/|P − Q| ≤ kGap·L.
  static constexpr double kGap = 2e-13;
  /// A certified distance must exceed kSeparation·L: below it, "touching or not" is a rounding
  /// question that the brute force (and trianglesIntersect) decides.
  static constexpr double kSeparation = 1e-9;
  /// A piercing edge must cross the plane with both ends at least kPierce·L·|n| away from it
  /// (n the unnormalised face normal), and the crossing point lie inside the face by at least
  /// kPierce in barycentric coordinates.
  static constexpr double kPierce = 1e-9;
  /// ... and the pierced face must not be a sliver: |n| ≥ kThick·L² (its height at least about
  /// kThick·L). A plain cross product tilts a sliver's normal by ε·L/height, which would move the
  /// crossing point across the sliver's width; slivers go to the brute force (accurate normals).
  static constexpr double kThick = 1e-3;
  /// The least L² of a pair certified intersecting (L ≥ 2⁻¹²⁰): the piercing test's products,
  /// of degree 7 in L, stay normal numbers above it.
  static constexpr double kSmallestPiercedSquared = 0x1p-240;
  /// The largest (L ≤ 2¹²⁰): its products stay finite below it.
  static constexpr double kLargestPiercedSquared = 0x1p240;
  /// Edges whose cross product is below kParallel of |d1|²|d2|² count as parallel.
  static constexpr double kParallel = 1e-20;
};

/// The point of triangle (o, o + u, o + v) closest to o + ap: o + s·u + t·v (Ericson, Real-Time
/// Collision Detection 5.1.5, its Voronoi regions as masks and one division). uu, uv, vv is the
/// Gram matrix of u, v. A zero-area triangle gives NaN or a wrong point, which the certificate
/// then rejects.
template <int W>
inline void closestOnTriangle(const Vec3Lanes<W>& ap, const Vec3Lanes<W>& u, const Vec3Lanes<W>& v,
                              const Real<W>& uu, const Real<W>& uv, const Real<W>& vv, Real<W>& s,
                              Real<W>& t) noexcept {
  const Real<W> zero = splat<W>(0.0), one = splat<W>(1.0);
  const Real<W> d1 = dot<W>(u, ap), d2 = dot<W>(v, ap);
  const Real<W> d3 = d1 - uu, d4 = d2 - uv;  // u·(p − b), v·(p − b)
  const Real<W> d5 = d1 - uv, d6 = d2 - vv;  // u·(p − c), v·(p − c)
  const Real<W> det = uu * vv - uv * uv;
  const Real<W> vb = d1 * vv - uv * d2;  // Cramer numerators of the face point
  const Real<W> vc = uu * d2 - uv * d1;
  const Real<W> va = det - vb - vc;
  // Ericson tests the regions in this order and takes the first that holds; blending from the
  // last to the first does the same.
  Real<W> ns = vb, nt = vc, den = det;  // the face
  const Mask<W> inBC = (va <= 0.0) & (d4 - d3 >= 0.0) & (d5 - d6 >= 0.0);
  ns = select<W>(inBC, d5 - d6, ns);
  nt = select<W>(inBC, d4 - d3, nt);
  den = select<W>(inBC, (d4 - d3) + (d5 - d6), den);
  const Mask<W> inAC = (vb <= 0.0) & (d2 >= 0.0) & (d6 <= 0.0);
  ns = select<W>(inAC, zero, ns);
  nt = select<W>(inAC, d2, nt);
  den = select<W>(inAC, d2 - d6, den);
  const Mask<W> inC = (d6 >= 0.0) & (d5 <= d6);
  ns = select<W>(inC, zero, ns);
  nt = select<W>(inC, one, nt);
  den = select<W>(inC, one, den);
  const Mask<W> inAB = (vc <= 0.0) & (d1 >= 0.0) & (d3 <= 0.0);
  ns = select<W>(inAB, d1, ns);
  nt = select<W>(inAB, zero, nt);
  den = select<W>(inAB, d1 - d3, den);
  const Mask<W> inB = (d3 >= 0.0) & (d4 <= d3);
  ns = select<W>(inB, one, ns);
  nt = select<W>(inB, zero, nt);
  den = select<W>(inB, one, den);
  const Mask<W> inA = (d1 <= 0.0) & (d2 <= 0.0);
  ns = select<W>(inA, zero, ns);
  nt = select<W>(inA, zero, nt);
  den = select<W>(inA, one, den);
  const Real<W> inverse = 1.0 / den;
  s = ns * inverse;
  t = nt * inverse;
}

/// Closest points p0 + s·d1, q0 + t·d2 of two segments (Ericson 5.1.9, with masks). Parallel
/// segments take s = 0 (one of the closest pairs); a zero-length segment gives NaN, which the
/// certificate rejects.
template <int W>
inline void closestOnSegments(const Vec3Lanes<W>& p0, const Vec3Lanes<W>& d1,
                              const Vec3Lanes<W>& q0, const Vec3Lanes<W>& d2, Real<W>& s,
                              Real<W>& t) noexcept {
  const Vec3Lanes<W> r = p0 - q0;
  const Real<W> a = dot<W>(d1, d1), e = dot<W>(d2, d2), b = dot<W>(d1, d2);
  const Real<W> c = dot<W>(d1, r), f = dot<W>(d2, r);
  const Real<W> ae = a * e;
  const Real<W> denRaw = ae - b * b;
  const Mask<W> parallel = denRaw <= HybridTolerances::kParallel * ae;
  const Real<W> den = select<W>(parallel, splat<W>(1.0), denRaw);
  // One division for 1/a, 1/e and 1/den.
  const Real<W> inverse = 1.0 / (ae * den);
  const Real<W> invA = e * den * inverse, invE = a * den * inverse, invDen = ae * inverse;
  const Real<W> s0 = select<W>(parallel, splat<W>(0.0), clamp01<W>((b * f - c * e) * invDen));
  const Real<W> t0 = (b * s0 + f) * invE;
  const Mask<W> below = t0 < 0.0;
  const Mask<W> above = t0 > 1.0;
  t = clamp01<W>(t0);
  s = select<W>(below, clamp01<W>(-c * invA), select<W>(above, clamp01<W>((b - c) * invA), s0));
}

/// The three vertices (rows) of a triangle in the local frame, picked per lane by a mask pair.
template <int W>
inline Vec3Lanes<W> pick3(const Mask<W>& first, const Mask<W>& second, const Vec3Lanes<W>& v0,
                          const Vec3Lanes<W>& v1, const Vec3Lanes<W>& v2) noexcept {
  return select<W>(first, v0, select<W>(second, v1, v2));
}

/// A certified piercing point: an edge of one triangle crossing the other's face.
template <int W>
struct Piercing {
  Mask<W> found;
  Vec3Lanes<W> point;  ///< local frame
};

/// Edges of triangle T (vertices t0, t1, t2, signed distances s0, s1, s2 to the plane of face F,
/// scaled by F's normal length) that cross F's plane, tested against F = (o, o + u, o + v) with
/// Gram (uu, uv, vv). Two edges at most cross: those at the vertex alone on its side.
template <int W>
inline Piercing<W> pierce(const Vec3Lanes<W>& t0, const Vec3Lanes<W>& t1, const Vec3Lanes<W>& t2,
                          const Real<W>& s0, const Real<W>& s1, const Real<W>& s2,
                          const Real<W>& planeMargin, const Vec3Lanes<W>& o, const Vec3Lanes<W>& u,
                          const Vec3Lanes<W>& v, const Real<W>& uu, const Real<W>& uv,
                          const Real<W>& vv) noexcept {
  const Mask<W> p0 = s0 > 0.0, p1 = s1 > 0.0, p2 = s2 > 0.0;
  const Mask<W> lone0 = p1 == p2, lone1 = p0 == p2;
  // The lone vertex L and the other two, O and O'.
  const Vec3Lanes<W> lone = pick3<W>(lone0, lone1, t0, t1, t2);
  const Vec3Lanes<W> other1 = pick3<W>(lone0, lone1, t1, t2, t0);
  const Vec3Lanes<W> other2 = pick3<W>(lone0, lone1, t2, t0, t1);
  const Real<W> sL = select<W>(lone0, s0, select<W>(lone1, s1, s2));
  const Real<W> sO1 = select<W>(lone0, s1, select<W>(lone1, s2, s0));
  const Real<W> sO2 = select<W>(lone0, s2, select<W>(lone1, s0, s1));
  const Real<W> det = uu * vv - uv * uv;
  Piercing<W> result;
  result.found = noLanes<W>();
  result.point = o;
  const Vec3Lanes<W>* others[2] = {&other1, &other2};
  const Real<W>* otherS[2] = {&sO1, &sO2};
  for (int k = 0; k < 2; ++k) {
    const Real<W> sO = *otherS[k];
    // Strictly on opposite sides, both ends clear of the plane.
    const Mask<W> crosses =
        ((sL > planeMargin) & (sO < -planeMargin)) | ((sL < -planeMargin) & (sO > planeMargin));
    // Homogeneous crossing point X = X'/D with D = |sL| + |sO| > 0: no division to test it.
    const Real<W> sign = select<W>(sL > 0.0, splat<W>(1.0), splat<W>(-1.0));
    const Real<W> wO = sign * sL, wL = -sign * sO;  // X' = wL·L + wO·O, both weights > 0
    const Real<W> D = wO + wL;
    const Vec3Lanes<W> xo = wL * (lone - o) + wO * (*others[k] - o);  // D·(X − o)
    const Real<W> d1 = dot<W>(u, xo), d2 = dot<W>(v, xo);
    const Real<W> nb = d1 * vv - uv * d2;  // D·det·(barycentric of o + u)
    const Real<W> nc = uu * d2 - uv * d1;  // D·det·(barycentric of o + v)
    const Real<W> margin = HybridTolerances::kPierce * D * det;
    const Mask<W> inside = (nb >= margin) & (nc >= margin) & (D * det - nb - nc >= margin);
    const Mask<W> take = crosses & inside & ~result.found;
    const Real<W> invD = 1.0 / D;
    result.point = select<W>(take, o + invD * xo, result.point);
    result.found |= take;
  }
  return result;
}

/// The Newton schedule of the hybrid: it only has to name the features of the minimum (3 steps
/// do for about 97% of near contacts; the rest go to the exhaustive stage).
struct HybridSchedule {
  static constexpr int kIterations = 3;
  static constexpr double kPenalty[kIterations] = {1e2, 1e5, 1e8};
  static constexpr double kRegularisation[kIterations] = {1e-2, 1e-5, 1e-8};
  static constexpr bool kGuarded = false;  // a NaN Newton point only misguides the candidates
};

/// The nearest candidate so far: closest points p, q (local frame) and |p − q|².
template <int W>
struct Candidate {
  Vec3Lanes<W> p, q;
  Real<W> distanceSquared;

  Candidate(const Vec3Lanes<W>& p0, const Vec3Lanes<W>& q0) noexcept
      : p(p0), q(q0), distanceSquared(dot<W>(p0 - q0, p0 - q0)) {}

  /// Takes `other` where it is nearer (a NaN candidate never is).
  void keepNearer(const Candidate& other) noexcept {
    const Mask<W> nearer = other.distanceSquared < distanceSquared;
    p = select<W>(nearer, other.p, p);
    q = select<W>(nearer, other.q, q);
    distanceSquared = select<W>(nearer, other.distanceSquared, distanceSquared);
  }
};

/// The pair's vertices in the local frame, and its Gram data.
template <int W>
struct PairGeometry {
  Vec3Lanes<W> a[3], b[3];
  const PairLanes<W>& pair;
  const PenaltyProblem<W>& m;

  PairGeometry(const PairLanes<W>& p, const PenaltyProblem<W>& problem) noexcept
      : pair(p), m(problem) {
    const Real<W> zero = splat<W>(0.0);
    a[0] = {zero, zero, zero};
    a[1] = p.e1;
    a[2] = p.e2;
    b[0] = p.r;
    b[1] = p.r + p.f1;
    b[2] = p.r + p.f2;
  }

  /// Vertex `v` of B against triangle A.
  Candidate<W> vertexOfB(const Vec3Lanes<W>& v) const noexcept {
    Real<W> s, t;
    closestOnTriangle<W>(v, pair.e1, pair.e2, m.e1e1, m.e1e2, m.e2e2, s, t);
    return {s * pair.e1 + t * pair.e2, v};
  }
  /// Vertex `v` of A against triangle B.
  Candidate<W> vertexOfA(const Vec3Lanes<W>& v) const noexcept {
    Real<W> s, t;
    closestOnTriangle<W>(v - pair.r, pair.f1, pair.f2, m.f1f1, m.f1f2, m.f2f2, s, t);
    return {v, pair.r + (s * pair.f1 + t * pair.f2)};
  }
  /// Segment p0 + s·d1 of A against segment q0 + t·d2 of B.
  Candidate<W> edges(const Vec3Lanes<W>& p0, const Vec3Lanes<W>& d1, const Vec3Lanes<W>& q0,
                     const Vec3Lanes<W>& d2) const noexcept {
    Real<W> s, t;
    closestOnSegments<W>(p0, d1, q0, d2, s, t);
    return {p0 + s * d1, q0 + t * d2};
  }
};

/// Certifies the nearest candidate: converged where it satisfies the optimality conditions and
/// is clearly apart, or where an edge clearly pierces the other triangle (then intersect, p = q
/// the piercing point); elsewhere converged = false. The piercing tests run only for a batch
/// where some lane not certified apart may intersect, as `mayIntersect()` (a Mask<W>, evaluated
/// only then) says: a batch-level shortcut, no lane's answer depends on it.
template <int W, class MayIntersect>
inline PairOutputLanes<W> certify(const PairGeometry<W>& g, const Candidate<W>& best,
                                  const MayIntersect& mayIntersect) noexcept {
  const PairLanes<W>& pair = g.pair;
  const Real<W> zero = splat<W>(0.0);
  // NaN fails every comparison, so a NaN candidate is never certified.
  const Real<W> gap = dualityGap<W>(pair, best.p, best.q);
  const Real<W> size2 = g.m.sizeSquared;
  const Mask<W> optimal =
      gap * gap <= (HybridTolerances::kGap * HybridTolerances::kGap) * size2 * best.distanceSquared;
  const Mask<W> separated = best.distanceSquared >
                            (HybridTolerances::kSeparation * HybridTolerances::kSeparation) * size2;
  const Mask<W> disjoint = optimal & separated;
  PairOutputLanes<W> out;
  out.distanceSquared = best.distanceSquared;
  out.p = pair.origin + best.p;
  out.q = pair.origin + best.q;
  out.errorBound = zero;
  out.newtonStep = zero;
  out.intersect = noLanes<W>();
  out.converged = disjoint;
  if (allLanes<W>(disjoint) || !anyLane<W>(mayIntersect() & ~disjoint)) return out;
  // An edge of B piercing A, or an edge of A piercing B.
  const Vec3Lanes<W> nA = cross<W>(pair.e1, pair.e2), nB = cross<W>(pair.f1, pair.f2);
  const Real<W> sb0 = dot<W>(nA, g.b[0]), sb1 = dot<W>(nA, g.b[1]), sb2 = dot<W>(nA, g.b[2]);
  const Real<W> sa0 = -dot<W>(nB, pair.r), sa1 = dot<W>(nB, pair.e1 - pair.r),
                sa2 = dot<W>(nB, pair.e2 - pair.r);
  const Real<W> size = sqrt<W>(size2);
  const Real<W> nAnA = dot<W>(nA, nA), nBnB = dot<W>(nB, nB);
  // A sliver face gets an infinite margin: nothing crosses it.
  const Real<W> thick = (HybridTolerances::kThick * HybridTolerances::kThick) * (size2 * size2);
  const Real<W> infinity = splat<W>(__builtin_inf());
  const Real<W> marginA =
      select<W>(nAnA >= thick, HybridTolerances::kPierce * size * sqrt<W>(nAnA), infinity);
  const Real<W> marginB =
      select<W>(nBnB >= thick, HybridTolerances::kPierce * size * sqrt<W>(nBnB), infinity);
  const Piercing<W> bThroughA = pierce<W>(g.b[0], g.b[1], g.b[2], sb0, sb1, sb2, marginA, g.a[0],
                                          pair.e1, pair.e2, g.m.e1e1, g.m.e1e2, g.m.e2e2);
  const Piercing<W> aThroughB = pierce<W>(g.a[0], g.a[1], g.a[2], sa0, sa1, sa2, marginB, pair.r,
                                          pair.f1, pair.f2, g.m.f1f1, g.m.f1f2, g.m.f2f2);
  // The piercing test's products are of degree 7 in the pair's size: below about 2⁻¹⁴² they
  // underflow, and its inequalities hold at 0 ≥ 0 (granulates scaled by 2⁻¹⁶⁰ were certified
  // intersecting 0.13 of their size apart); above about 2¹⁴⁶ D·det overflows and ∞ ≥ margin
  // holds (at 2¹⁴⁷, a pair 0.084 of its size apart). Such pairs go to the brute force.
  const Mask<W> intersect = (bThroughA.found | aThroughB.found) &
                            (size2 >= HybridTolerances::kSmallestPiercedSquared) &
                            (size2 <= HybridTolerances::kLargestPiercedSquared);
  const Vec3Lanes<W> touch =
      pair.origin + select<W>(bThroughA.found, bThroughA.point, aThroughB.point);
  out.intersect = intersect;
  out.converged = intersect | disjoint;
  out.distanceSquared = select<W>(intersect, zero, out.distanceSquared);
  out.p = select<W>(intersect, touch, out.p);
  out.q = select<W>(intersect, touch, out.q);
  return out;
}

/// |P − Q|² of the Newton point below which the first stage tests for an intersection, relative
/// to L².
inline constexpr double kNewtonClose = 1e-2;

/// The hybrid's first stage for W pairs: converged = certified; the other lanes go to
/// exhaustiveLanes (their other outputs are meaningless).
///
/// Candidates, from the Newton point's barycentric weights λ (on A) and μ (on B): the vertex of
/// B with the largest μ against triangle A, the vertex of A with the largest λ against B, and
/// the edges of A and B opposite their smallest weights (edge against edge, with clamping, which
/// covers vertex–edge and vertex–vertex). The nearest is certified or not.
template <int W, class Schedule = HybridSchedule>
inline PairOutputLanes<W> hybridLanes(const PairLanes<W>& pair) noexcept {
  const PenaltyProblem<W> m = makePenaltyProblem<W>(pair);
  const PenaltyIterate<W> x = penaltyNewton<W, Schedule>(m);
  const PairGeometry<W> g(pair, m);
  const Real<W> l0 = 1.0 - x.a1 - x.a2, m0 = 1.0 - x.a3 - x.a4;
  // The vertices with the largest weights.
  const Mask<W> aMax0 = (l0 > x.a1) & (l0 >= x.a2), aMax1 = ~aMax0 & (x.a1 >= x.a2);
  const Mask<W> bMax0 = (m0 > x.a3) & (m0 >= x.a4), bMax1 = ~bMax0 & (x.a3 >= x.a4);
  Candidate<W> best = g.vertexOfB(pick3<W>(bMax0, bMax1, g.b[0], g.b[1], g.b[2]));
  best.keepNearer(g.vertexOfA(pick3<W>(aMax0, aMax1, g.a[0], g.a[1], g.a[2])));
  // The edges opposite the smallest weights: from vertex k + 1 to k + 2.
  const Mask<W> aMin0 = (l0 <= x.a1) & (l0 <= x.a2), aMin1 = ~aMin0 & (x.a1 <= x.a2);
  const Mask<W> bMin0 = (m0 <= x.a3) & (m0 <= x.a4), bMin1 = ~bMin0 & (x.a3 <= x.a4);
  const Vec3Lanes<W> pStart = pick3<W>(aMin0, aMin1, g.a[1], g.a[2], g.a[0]);
  const Vec3Lanes<W> pEnd = pick3<W>(aMin0, aMin1, g.a[2], g.a[0], g.a[1]);
  const Vec3Lanes<W> qStart = pick3<W>(bMin0, bMin1, g.b[1], g.b[2], g.b[0]);
  const Vec3Lanes<W> qEnd = pick3<W>(bMin0, bMin1, g.b[2], g.b[0], g.b[1]);
  best.keepNearer(g.edges(pStart, pEnd - pStart, qStart, qEnd - qStart));
  // Only a Newton point with P near Q hints at an intersection (else the exhaustive stage,
  // which always tests, finds it).
  const auto newtonClose = [&] {
    const Vec3Lanes<W> d =
        (x.a1 * pair.e1 + x.a2 * pair.e2) - (pair.r + (x.a3 * pair.f1 + x.a4 * pair.f2));
    return dot<W>(d, d) <= kNewtonClose * m.sizeSquared;
  };
  PairOutputLanes<W> out = certify<W>(g, best, newtonClose);
  out.newtonStep = select<W>(x.step < __builtin_huge_val(), x.step, splat<W>(__builtin_inf()));
  return out;
}

/// The hybrid's second stage, for the few pairs the first could not certify: all 15 candidates
/// (the brute force's 6 vertex–face and 9 edge–edge), branch-free, and the same certificates.
/// What it cannot certify either (touching, coplanar or degenerate pairs) goes to the scalar
/// brute force.
template <int W>
inline PairOutputLanes<W> exhaustiveLanes(const PairLanes<W>& pair) noexcept {
  const PenaltyProblem<W> m = makePenaltyProblem<W>(pair);
  const PairGeometry<W> g(pair, m);
  Candidate<W> best = g.vertexOfB(g.b[0]);
  best.keepNearer(g.vertexOfB(g.b[1]));
  best.keepNearer(g.vertexOfB(g.b[2]));
  for (int i = 0; i < 3; ++i)
    best.keepNearer(g.vertexOfA(g.a[i]));
  for (int i = 0; i < 3; ++i) {
    const Vec3Lanes<W> d1 = g.a[(i + 1) % 3] - g.a[i];
    for (int j = 0; j < 3; ++j)
      best.keepNearer(g.edges(g.a[i], d1, g.b[j], g.b[(j + 1) % 3] - g.b[j]));
  }
  return certify<W>(g, best, [] { return ~noLanes<W>(); });
}

}  // namespace delta::detail
