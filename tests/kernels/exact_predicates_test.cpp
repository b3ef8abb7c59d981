// The exact predicates (kernels/detail/exact_predicates.h) against exact rational
// arithmetic (CGAL's Gmpq on the given doubles): orient's sign by the filter and by the
// expansions, the leading sign of a cross product of differences, the exact sum of triple
// products, and the order of an edge's crossings with two planes (filter and integers), on random
// points and on adversarial ones: exactly coplanar in an axis plane and in a lattice plane, exactly
// coplanar where no difference is a double, nearly coplanar (the fourth point rounded into the
// plane of the others), collinear, repeated, huge offsets, tiny scales, and coordinates whose
// exponents span the whole range the predicates take (2⁻²⁵⁰ to 2²⁰⁰), where a difference is not a
// double.

#include "kernels/detail/exact_predicates.h"

#include <CGAL/Gmpq.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <optional>
#include <random>
#include <utility>

#include "delta/core/vec3.h"

namespace delta {
namespace {

using Rational = CGAL::Gmpq;

struct RationalVector {
  Rational x, y, z;
};

RationalVector rational(const Vec3& p) {
  return {Rational(p.x), Rational(p.y), Rational(p.z)};
}
RationalVector minus(const RationalVector& a, const RationalVector& b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
RationalVector cross(const RationalVector& a, const RationalVector& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
Rational dot(const RationalVector& a, const RationalVector& b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
int signOf(const Rational& x) {
  return x > 0 ? 1 : x < 0 ? -1 : 0;
}

/// orient(p, q, r, s) = (s − p)·((q − p) × (r − p)), exactly.
int oracleOrient(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const RationalVector rp = rational(p);
  return signOf(dot(minus(rational(s), rp), cross(minus(rational(q), rp), minus(rational(r), rp))));
}

/// The sign of the first non-zero component of (q − p) × (s − r), exactly.
int oracleCrossLeading(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const RationalVector n = cross(minus(rational(q), rational(p)), minus(rational(s), rational(r)));
  for (const Rational* component : {&n.x, &n.y, &n.z})
    if (const int sign = signOf(*component); sign != 0) return sign;
  return 0;
}

/// Quadruples of points of one kind, drawn from `random`.
class Quadruples {
 public:
  enum Kind {
    kRandom,          ///< uniform in [−1, 1]³
    kAxisPlane,       ///< all four with one coordinate equal (faces coplanar in z = c)
    kLatticePlane,    ///< small integers on 3x − 2y + 5z = 7, scaled by a power of two
    kNearlyCoplanar,  ///< s = p + α(q − p) + β(r − p), rounded
    kCollinear,       ///< q, r, s on the line through p (rounded)
    kRepeated,        ///< two of the four the same point
    kHugeOffset,      ///< kNearlyCoplanar moved by 10⁶ to 2¹⁰⁰
    kTinyScale,  ///< kNearlyCoplanar scaled by 2⁻²⁰⁰ (every coordinate ≥ 2⁻²⁵⁰)
    kMixedExponents,  ///< coordinates 0 or ±2^e · m, e anywhere in [−250, 200]
    /// on the plane z = ±2^k x exactly, with x and y of exponents from −40 to 40, so that no
    /// difference is a double: the determinant is 0 and every evaluation short of exact rounds
    kInexactPlane,
    kKinds
  };

  explicit Quadruples(std::uint64_t seed) : random_(seed) {}

  std::array<Vec3, 4> next(Kind kind) {
    switch (kind) {
      case kRandom:
        return {point(), point(), point(), point()};
      case kAxisPlane: {
        std::array<Vec3, 4> p{point(), point(), point(), point()};
        const double c = unit_(random_);
        const std::size_t axis = random_() % 3;
        for (Vec3& v : p)
          (axis == 0 ? v.x : axis == 1 ? v.y : v.z) = c;
        return p;
      }
      case kLatticePlane: {
        std::array<Vec3, 4> p;
        const double scale = std::ldexp(1.0, static_cast<int>(random_() % 41) - 20);
        for (Vec3& v : p) {
          // 3x − 2y + 5z = 7 with z = (7 − 3x + 2y)/5 an integer: x, y chosen until it is.
          long x, y;
          do {
            x = static_cast<long>(random_() % 2001) - 1000;
            y = static_cast<long>(random_() % 2001) - 1000;
          } while ((7 - 3 * x + 2 * y) % 5 != 0);
          const long z = (7 - 3 * x + 2 * y) / 5;
          v = Vec3{static_cast<double>(x), static_cast<double>(y), static_cast<double>(z)} * scale;
        }
        return p;
      }
      case kNearlyCoplanar:
        return nearlyCoplanar({});
      case kCollinear: {
        const Vec3 p = point(), direction = point();
        return {p, p + unit_(random_) * direction, p + unit_(random_) * direction,
                p + unit_(random_) * direction};
      }
      case kRepeated: {
        std::array<Vec3, 4> p{point(), point(), point(), point()};
        p[random_() % 4] = p[random_() % 4];
        return p;
      }
      case kHugeOffset: {
        const double magnitude = std::ldexp(1.0, 20 + static_cast<int>(random_() % 81));
        return nearlyCoplanar(Vec3{magnitude, -0.5 * magnitude, 0.25 * magnitude});
      }
      case kTinyScale: {
        std::array<Vec3, 4> p = nearlyCoplanar({});
        for (Vec3& v : p)
          v = ldexp(v, -200);
        for (Vec3& v : p)
          for (double* c : {&v.x, &v.y, &v.z})
            if (std::abs(*c) < detail::kSmallestExactCoordinate) *c = 0.0;
        return p;
      }
      case kInexactPlane: {
        const double slope =
            std::copysign(std::ldexp(1.0, static_cast<int>(random_() % 5) - 2), unit_(random_));
        std::array<Vec3, 4> p;
        for (Vec3& v : p) {
          const auto draw = [&] {
            return std::ldexp(unit_(random_), static_cast<int>(random_() % 81) - 40);
          };
          const double x = draw();
          v = Vec3{x, draw(), slope * x};
        }
        return p;
      }
      case kMixedExponents:
      default: {
        std::array<Vec3, 4> p;
        for (Vec3& v : p)
          for (double* c : {&v.x, &v.y, &v.z}) {
            const auto draw = random_() % 8;
            const double magnitude = 0.5 + 0.5 * std::abs(unit_(random_));  // [0.5, 1]
            *c = draw == 0
                     ? 0.0
                     : std::copysign(std::ldexp(magnitude, static_cast<int>(random_() % 450) - 249),
                                     unit_(random_));
          }
        return p;
      }
    }
  }

 private:
  Vec3 point() { return {unit_(random_), unit_(random_), unit_(random_)}; }
  std::array<Vec3, 4> nearlyCoplanar(const Vec3& offset) {
    const Vec3 p = point(), q = point(), r = point();
    const double alpha = unit_(random_), beta = unit_(random_);
    const Vec3 s = p + alpha * (q - p) + beta * (r - p);
    return {p + offset, q + offset, r + offset, s + offset};
  }

  std::mt19937_64 random_;
  std::uniform_real_distribution<double> unit_{-1.0, 1.0};
};

#ifdef DELTA_TESTS_EMULATED
constexpr int kTrials = 1000;
#else
constexpr int kTrials = 5000;
#endif

TEST(ExactPredicates, OrientSignsAreTheRationalSigns) {
  Quadruples quadruples(35);
  for (int kind = 0; kind < Quadruples::kKinds; ++kind) {
    int zeros = 0;
    for (int trial = 0; trial < kTrials; ++trial) {
      const auto [p, q, r, s] = quadruples.next(static_cast<Quadruples::Kind>(kind));
      const int expected = oracleOrient(p, q, r, s);
      zeros += expected == 0;
      ASSERT_EQ(detail::exactOrientSign(p, q, r, s), expected) << kind << " " << trial;
      ASSERT_EQ(detail::orientSign(p, q, r, s), expected) << kind << " " << trial;
      // The filter alone: right or undecided.
      const int filtered = detail::filteredOrientSign(q - p, r - p, s - p);
      ASSERT_TRUE(filtered == 0 || filtered == expected) << kind << " " << trial;
    }
    // The adversarial kinds reach the exact evaluation and its zeros.
    if (kind == Quadruples::kAxisPlane || kind == Quadruples::kLatticePlane ||
        kind == Quadruples::kRepeated || kind == Quadruples::kInexactPlane) {
      EXPECT_GT(zeros, kTrials / 2) << kind;
    }
  }
}

TEST(ExactPredicates, CrossProductLeadingSignsAreTheRationalSigns) {
  Quadruples quadruples(36);
  for (int kind = 0; kind < Quadruples::kKinds; ++kind)
    for (int trial = 0; trial < kTrials; ++trial) {
      const auto [p, q, r, s] = quadruples.next(static_cast<Quadruples::Kind>(kind));
      // Edges (p, q) and (r, s), and the normal of triangle (p, q, s): parallel edges, exact
      // zeros in the leading components and differences that are not doubles among them.
      ASSERT_EQ(detail::exactCrossLeadingSign(p, q, r, s), oracleCrossLeading(p, q, r, s))
          << kind << " " << trial;
      ASSERT_EQ(detail::exactCrossLeadingSign(p, q, p, s), oracleCrossLeading(p, q, p, s))
          << kind << " " << trial;
      ASSERT_EQ(detail::exactCrossLeadingSign(p, q, r, r + (q - p)),
                oracleCrossLeading(p, q, r, r + (q - p)))
          << kind << " " << trial;
    }
}

TEST(ExactPredicates, TripleProductSumsAreTheRationalSums) {
  Quadruples quadruples(37);
  for (int kind = 0; kind < Quadruples::kKinds; ++kind)
    for (int trial = 0; trial < kTrials / 20; ++trial) {
      detail::ExactTripleProductSum sum;
      Rational expected = 0;
      // A closed-surface-like sum: terms that cancel but for the last bits.
      for (int term = 0; term < 20; ++term) {
        const auto [a, b, c, d] = quadruples.next(static_cast<Quadruples::Kind>(kind));
        for (const auto& [x, y, z] : {std::array<Vec3, 3>{a, b, c}, std::array<Vec3, 3>{a, c, b},
                                      std::array<Vec3, 3>{d, b, c}}) {
          sum.add(x, y, z);
          expected += dot(rational(x), cross(rational(y), rational(z)));
        }
      }
      ASSERT_EQ(sum.sign(), signOf(expected)) << kind << " " << trial;
    }
}

/// crossingOrder's answer from its definition (exact_predicates.h), in rationals: where the edge
/// e0 → e1 crosses the planes of `first` and `second`, λ_k = at_k / along_k, the order is the
/// sign of (λ_first − λ_second) = along_1·along_2·F, F = at_1·along_2 − at_2·along_1, and where
/// F = 0 that of the displacement's term; nullopt where a plane is parallel to the edge (not
/// asked).
std::optional<int> oracleCrossingOrder(const Vec3& e0, const Vec3& e1,
                                       const std::array<Vec3, 3>& first,
                                       const std::array<Vec3, 3>& second, bool edgeOfA) {
  const RationalVector re0 = rational(e0), along = minus(re0, rational(e1));
  const auto plane = [&](const std::array<Vec3, 3>& t) {
    const RationalVector t0 = rational(t[0]);
    const RationalVector normal = cross(minus(rational(t[1]), t0), minus(rational(t[2]), t0));
    return std::array<Rational, 2>{dot(minus(re0, t0), normal), dot(along, normal)};
  };
  const auto normalOf = [](const std::array<Vec3, 3>& t) {
    const RationalVector t0 = rational(t[0]);
    return cross(minus(rational(t[1]), t0), minus(rational(t[2]), t0));
  };
  const auto [atS, alongS] = plane(first);
  const auto [atT, alongT] = plane(second);
  const int signs = signOf(alongS) * signOf(alongT);
  if (signs == 0) return std::nullopt;
  if (const int sign = signOf(atS * alongT - atT * alongS); sign != 0) return signs * sign;
  const RationalVector normalS = normalOf(first), normalT = normalOf(second);
  for (const auto& [s, t] : {std::pair{&normalS.x, &normalT.x}, std::pair{&normalS.y, &normalT.y},
                             std::pair{&normalS.z, &normalT.z}})
    if (const int sign = signOf(alongT * *s - alongS * *t); sign != 0)
      return signs * (edgeOfA ? -sign : sign);
  return 0;
}

TEST(ExactPredicates, CrossingOrdersAreTheRationalOrders) {
  // Each kind's points as two triangles (sharing an edge, and a plane where the kind is
  // coplanar) and an edge from the next draw: through a shared corner in a third of the trials
  // (both crossings at one point: F = 0, the displacement decides), otherwise across the
  // plane(s), where nearly coplanar triangles put the crossings within their rounding of one
  // another and the integers decide.
  Quadruples quadruples(38);
  std::mt19937_64 random(39);
  for (int kind = 0; kind < Quadruples::kKinds; ++kind) {
    int asked = 0, ties = 0;
    for (int trial = 0; trial < kTrials; ++trial) {
      const auto [p, q, r, s] = quadruples.next(static_cast<Quadruples::Kind>(kind));
      const auto [e0Drawn, e1, x, y] = quadruples.next(static_cast<Quadruples::Kind>(kind));
      const Vec3 e0 = random() % 3 == 0 ? p : e0Drawn;
      const std::array<Vec3, 3> first{p, q, r}, second{p, r, s};
      for (const bool edgeOfA : {true, false}) {
        const std::optional<int> expected = oracleCrossingOrder(e0, e1, first, second, edgeOfA);
        if (!expected) continue;
        ++asked;
        ties += e0 == p;
        ASSERT_EQ(detail::crossingOrder(e0, e1, first, second, edgeOfA), *expected)
            << kind << " " << trial;
        ASSERT_EQ(detail::crossingOrder(e0, e1, second, first, edgeOfA), -*expected)
            << kind << " " << trial;
      }
    }
    EXPECT_GT(asked, kTrials / 5) << kind;
    EXPECT_GT(ties, kTrials / 10) << kind;
  }
}

}  // namespace
}  // namespace delta
