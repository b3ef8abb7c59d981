// The exact oracle for the triangle kernels (exact_distance.h): compiled once, so that the tests
// that use it do not each parse CGAL.

// The oracle combines CGAL::Uncertain<bool> with `&`, not `&&`: with the interval kernel `&` keeps
// the uncertainty where `&&` would force a decision. clang warns about `&` on plain bools.
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wbitwise-instead-of-logical"
#endif

#include "exact_distance.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/FPU.h>
#include <CGAL/Gmpq.h>
#include <CGAL/Interval_nt.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/intersections.h>
#include <CGAL/squared_distance_3.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace delta::test {

namespace {  // the oracle's parts, this file's alone

using Predicates = CGAL::Exact_predicates_inexact_constructions_kernel;
using Rational = CGAL::Simple_cartesian<CGAL::Gmpq>;
using Interval = CGAL::Simple_cartesian<CGAL::Interval_nt<false>>;

template <class Kernel>
typename Kernel::Point_3 point(const Vec3& v) {
  return {v.x, v.y, v.z};  // exact for every kernel here
}

inline std::array<Vec3, 3> corners(const Triangle& t) {
  return {t.a, t.b, t.c};
}

inline bool degenerate(const Triangle& t) {
  return CGAL::collinear(point<Predicates>(t.a), point<Predicates>(t.b), point<Predicates>(t.c));
}

/// The smaller of two values; for intervals the interval of the smaller value, which needs no
/// decision (ties, common here, would make the comparison uncertain).
inline CGAL::Gmpq smaller(const CGAL::Gmpq& x, const CGAL::Gmpq& y) {
  return y < x ? y : x;
}
inline CGAL::Interval_nt<false> smaller(const CGAL::Interval_nt<false>& x,
                                        const CGAL::Interval_nt<false>& y) {
  return CGAL::min(x, y);
}

/// `ifTrue` or `ifFalse` by `condition`; an interval comparison too close to call gives the hull
/// of both, which holds the true value either way (the two agree closely there: the condition
/// is a region boundary where both formulas give the same distance).
inline const CGAL::Gmpq& choose(bool condition, const CGAL::Gmpq& ifTrue,
                                const CGAL::Gmpq& ifFalse) {
  return condition ? ifTrue : ifFalse;
}
inline CGAL::Interval_nt<false> choose(CGAL::Uncertain<bool> condition,
                                       const CGAL::Interval_nt<false>& ifTrue,
                                       const CGAL::Interval_nt<false>& ifFalse) {
  if (CGAL::is_certain(condition)) return CGAL::get_certain(condition) ? ifTrue : ifFalse;
  return {std::min(ifTrue.inf(), ifFalse.inf()), std::max(ifTrue.sup(), ifFalse.sup())};
}

/// Point–segment: the distance to the line when the projection falls on the segment, to the
/// nearer end otherwise. (CGAL's own version compares equal intervals when p is an end, which
/// p often is here, and then throws.)
template <class Kernel>
typename Kernel::FT pointSegment(const Vec3& p, const Vec3& s0, const Vec3& s1) {
  const auto q = point<Kernel>(p), a = point<Kernel>(s0), b = point<Kernel>(s1);
  const typename Kernel::FT ends =
      smaller(CGAL::squared_distance(q, a), CGAL::squared_distance(q, b));
  if (s0 == s1) return ends;
  const typename Kernel::Vector_3 along = b - a, offset = q - a;
  const typename Kernel::FT projection = along * offset, lengthSquared = along * along;
  const typename Kernel::Vector_3 across = CGAL::cross_product(along, offset);
  return choose((projection >= 0) & (projection <= lengthSquared),
                (across * across) / lengthSquared, ends);
}

template <class Kernel>
typename Kernel::FT segmentSegment(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  if (p0 == p1) return pointSegment<Kernel>(p0, q0, q1);
  if (q0 == q1) return pointSegment<Kernel>(q0, p0, p1);
  using Segment = typename Kernel::Segment_3;
  return CGAL::squared_distance(Segment(point<Kernel>(p0), point<Kernel>(p1)),
                                Segment(point<Kernel>(q0), point<Kernel>(q1)));
}

/// Point–triangle: the distance to the plane when the projection falls inside the triangle, the
/// distance to the nearest edge otherwise (CGAL's own version picks among edges by comparisons,
/// which ties at every vertex region make undecidable in intervals).
template <class Kernel>
typename Kernel::FT pointTriangle(const Vec3& p, const Triangle& t, bool isDegenerate) {
  using Vector = typename Kernel::Vector_3;
  const typename Kernel::FT nearestEdge =
      smaller(smaller(pointSegment<Kernel>(p, t.a, t.b), pointSegment<Kernel>(p, t.b, t.c)),
              pointSegment<Kernel>(p, t.c, t.a));
  if (isDegenerate) return nearestEdge;
  const auto a = point<Kernel>(t.a), b = point<Kernel>(t.b), c = point<Kernel>(t.c);
  const auto q = point<Kernel>(p);
  const Vector normal = CGAL::cross_product(b - a, c - a);
  auto inside = [&](const typename Kernel::Point_3& e0, const typename Kernel::Point_3& e1) {
    return CGAL::cross_product(e1 - e0, normal) * (q - e0) <= 0;
  };
  const typename Kernel::FT height = normal * (q - a);
  return choose(inside(a, b) & inside(b, c) & inside(c, a),
                CGAL::square(height) / (normal * normal), nearestEdge);
}

/// The 15 candidates of disjoint triangles: 0–2 the vertices of A to B, 3–5 the vertices of B to
/// A, 6–14 the edge pairs.
template <class Kernel>
typename Kernel::FT candidate(int index, const Triangle& first, bool flatFirst,
                              const Triangle& second, bool flatSecond) {
  const auto a = corners(first), b = corners(second);
  if (index < 3) return pointTriangle<Kernel>(a[index], second, flatSecond);
  if (index < 6) return pointTriangle<Kernel>(b[index - 3], first, flatFirst);
  const int i = (index - 6) / 3, j = (index - 6) % 3;
  return segmentSegment<Kernel>(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3]);
}

inline bool segmentMeetsTriangle(const Vec3& s0, const Vec3& s1,
                                 const Predicates::Triangle_3& triangle) {
  if (s0 == s1) return CGAL::do_intersect(point<Predicates>(s0), triangle);
  return CGAL::do_intersect(Predicates::Segment_3(point<Predicates>(s0), point<Predicates>(s1)),
                            triangle);
}

inline bool segmentsMeet(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  using Segment = Predicates::Segment_3;
  if (p0 == p1 && q0 == q1) return p0 == q0;
  if (p0 == p1)
    return Segment(point<Predicates>(q0), point<Predicates>(q1)).has_on(point<Predicates>(p0));
  if (q0 == q1)
    return Segment(point<Predicates>(p0), point<Predicates>(p1)).has_on(point<Predicates>(q0));
  return CGAL::do_intersect(Segment(point<Predicates>(p0), point<Predicates>(p1)),
                            Segment(point<Predicates>(q0), point<Predicates>(q1)));
}

inline double largestEdge(const Triangle& first, const Triangle& second) {
  double longest = 0.0;
  for (const Triangle* t : {&first, &second})
    longest = std::max({longest, distance(t->a, t->b), distance(t->b, t->c), distance(t->c, t->a)});
  return longest;
}

/// `compute(kernel)` (a squared distance, written once for any kernel) in interval arithmetic,
/// certified when the enclosure pins the distance to kCertifiedFraction × (size + distance);
/// otherwise in exact rationals, rounded once.
template <class Compute>
double certifiedSquaredDistance(const Compute& compute, double size) {
  double low = 0.0, high = 0.0;
  bool certain = true;
  {
    CGAL::Protect_FPU_rounding<true> upward;  // Interval_nt<false> needs it, restored on exit
    try {
      const auto value = compute(Interval{});
      low = std::max(value.inf(), 0.0);  // a squared distance; a product can straddle 0
      high = value.sup();
    } catch (const CGAL::Uncertain_conversion_exception&) {
      certain = false;  // a branch the intervals could not decide
    }
  }
  if (certain && std::isfinite(high) &&
      std::sqrt(high) - std::sqrt(low) <= kCertifiedFraction * (size + std::sqrt(high)))
    return 0.5 * (low + high);
  return CGAL::to_double(compute(Rational{}));
}

}  // namespace

/// Whether the two solid triangles share a point, decided exactly (touching counts). Zero-area
/// triangles are the union of their edges.
bool exactIntersect(const Triangle& first, const Triangle& second) {
  const bool flatA = degenerate(first), flatB = degenerate(second);
  const auto a = corners(first), b = corners(second);
  if (!flatA && !flatB)
    return CGAL::do_intersect(
        Predicates::Triangle_3(point<Predicates>(a[0]), point<Predicates>(a[1]),
                               point<Predicates>(a[2])),
        Predicates::Triangle_3(point<Predicates>(b[0]), point<Predicates>(b[1]),
                               point<Predicates>(b[2])));
  if (!flatA || !flatB) {
    const auto& edges = flatA ? a : b;
    const auto& solid = flatA ? b : a;
    const Predicates::Triangle_3 triangle(point<Predicates>(solid[0]), point<Predicates>(solid[1]),
                                          point<Predicates>(solid[2]));
    for (int i = 0; i < 3; ++i)
      if (segmentMeetsTriangle(edges[i], edges[(i + 1) % 3], triangle)) return true;
    return false;
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segmentsMeet(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3])) return true;
  return false;
}

/// The exact squared distance of the two solid triangles (0 when they intersect) in exact rational
/// arithmetic, rounded to double once, at the end. About 300 µs a pair.
double exactSquaredDistanceRational(const Triangle& first, const Triangle& second) {
  if (exactIntersect(first, second)) return 0.0;
  const bool flatA = degenerate(first), flatB = degenerate(second);
  CGAL::Gmpq best = candidate<Rational>(0, first, flatA, second, flatB);
  for (int index = 1; index < 15; ++index)
    best = std::min(best, candidate<Rational>(index, first, flatA, second, flatB));
  return CGAL::to_double(best);
}

/// The squared distance of the two solid triangles (0 when they intersect), its square root
/// within kCertifiedFraction × (pairSize + distance) of the exact distance (an interval filter,
/// with exact rational arithmetic where the intervals are too wide).
double exactSquaredDistance(const Triangle& first, const Triangle& second) {
  if (exactIntersect(first, second)) return 0.0;
  const bool flatA = degenerate(first), flatB = degenerate(second);
  constexpr double kInfinity = std::numeric_limits<double>::infinity();
  std::array<double, 15> lower{}, upper{};
  {
    CGAL::Protect_FPU_rounding<true> upward;  // Interval_nt<false> needs it, restored on exit
    for (int index = 0; index < 15; ++index) {
      try {
        const auto value = candidate<Interval>(index, first, flatA, second, flatB);
        lower[index] = std::max(value.inf(), 0.0);  // a product can straddle 0
        upper[index] = value.sup();
      } catch (const CGAL::Uncertain_conversion_exception&) {
        lower[index] = -kInfinity;  // a branch the intervals could not decide: unknown
        upper[index] = kInfinity;
      }
    }
  }
  const double bound = *std::min_element(upper.begin(), upper.end());
  double low = kInfinity;
  for (int index = 0; index < 15; ++index)
    if (lower[index] <= bound) low = std::min(low, lower[index]);
  const double certified = kCertifiedFraction * (largestEdge(first, second) + std::sqrt(bound));
  if (low >= 0.0 && std::isfinite(bound) && std::sqrt(bound) - std::sqrt(low) <= certified)
    return 0.5 * (low + bound);
  // The intervals cannot pin it down: the exact minimum of the candidates that may be it.
  CGAL::Gmpq best;
  bool any = false;
  for (int index = 0; index < 15; ++index) {
    if (lower[index] > bound) continue;
    const CGAL::Gmpq value = candidate<Rational>(index, first, flatA, second, flatB);
    if (!any || value < best) best = value;
    any = true;
  }
  return CGAL::to_double(best);
}

/// The squared distance from a point to a solid triangle, its square root within
/// kCertifiedFraction × (longest edge + distance) of the exact distance (interval filter, exact
/// rational fallback, as for two triangles).
double exactSquaredDistance(const Vec3& p, const Triangle& triangle) {
  const bool flat = degenerate(triangle);
  return certifiedSquaredDistance(
      [&](auto kernel) { return pointTriangle<decltype(kernel)>(p, triangle, flat); },
      largestEdge(triangle, triangle));
}

/// The squared distance between two segments (either may have zero length), certified likewise.
double exactSquaredDistance(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  return certifiedSquaredDistance(
      [&](auto kernel) { return segmentSegment<decltype(kernel)>(p0, p1, q0, q1); },
      std::max(distance(p0, p1), distance(q0, q1)));
}

/// CGAL's own Triangle_3–Triangle_3 squared distance in exact rationals (about 300 µs a pair),
/// for non-degenerate triangles only; the tests cross-check the oracle above with it.
double cgalTriangleSquaredDistance(const Triangle& first, const Triangle& second) {
  auto triangle = [](const Triangle& t) {
    return Rational::Triangle_3(point<Rational>(t.a), point<Rational>(t.b), point<Rational>(t.c));
  };
  return CGAL::to_double(CGAL::squared_distance(triangle(first), triangle(second)));
}

double exactSquaredDistanceRational(const Vec3& p, const Triangle& triangle) {
  return CGAL::to_double(pointTriangle<Rational>(p, triangle, degenerate(triangle)));
}

double exactSquaredDistanceRational(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                    const Vec3& q1) {
  return CGAL::to_double(segmentSegment<Rational>(p0, p1, q0, q1));
}

}  // namespace delta::test
