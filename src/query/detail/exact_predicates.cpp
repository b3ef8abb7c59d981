#include "exact_predicates.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace delta::detail {
namespace {

// Shewchuk's expansion arithmetic: a number is an unevaluated sum of doubles, non-overlapping and
// in increasing magnitude, zeros eliminated. Exact for any sums and products of doubles that
// neither overflow nor underflow (the coordinate range keeps them inside, coordinate_range.h).
using Expansion = std::vector<double>;

/// a + b = x + y exactly, x = fl(a + b).
inline void twoSum(double a, double b, double& x, double& y) noexcept {
  x = a + b;
  const double bVirtual = x - a;
  const double aVirtual = x - bVirtual;
  y = (a - aVirtual) + (b - bVirtual);
}

/// a·b = x + y exactly, x = fl(a·b).
inline void twoProduct(double a, double b, double& x, double& y) noexcept {
  x = a * b;
  y = std::fma(a, b, -x);
}

/// e + f (Shewchuk's linear-time fast_expansion_sum_zeroelim, by merging and grow steps done
/// plainly: sum every component of f into e).
Expansion sum(const Expansion& e, const Expansion& f) {
  Expansion h = e;
  for (const double component : f) {
    // grow_expansion_zeroelim(h, component)
    Expansion grown;
    grown.reserve(h.size() + 1);
    double q = component;
    for (const double hi : h) {
      double sumHigh, sumLow;
      twoSum(q, hi, sumHigh, sumLow);
      if (sumLow != 0.0) grown.push_back(sumLow);
      q = sumHigh;
    }
    if (q != 0.0 || grown.empty()) grown.push_back(q);
    h = std::move(grown);
  }
  return h;
}

Expansion negate(Expansion e) {
  for (double& component : e)
    component = -component;
  return e;
}

/// e·b (scale_expansion_zeroelim).
Expansion scale(const Expansion& e, double b) {
  Expansion h;
  h.reserve(2 * e.size());
  if (e.empty()) return h;
  double q, low;
  twoProduct(e[0], b, q, low);
  if (low != 0.0) h.push_back(low);
  for (std::size_t i = 1; i < e.size(); ++i) {
    double productHigh, productLow;
    twoProduct(e[i], b, productHigh, productLow);
    double sumHigh, sumLow;
    twoSum(q, productLow, sumHigh, sumLow);
    if (sumLow != 0.0) h.push_back(sumLow);
    double highest;
    twoSum(productHigh, sumHigh, highest, sumLow);
    if (sumLow != 0.0) h.push_back(sumLow);
    q = highest;
  }
  if (q != 0.0 || h.empty()) h.push_back(q);
  return h;
}

Expansion product(const Expansion& e, const Expansion& f) {
  Expansion h;
  for (const double component : f)
    h = sum(h, scale(e, component));
  return h;
}

/// x − y exactly.
Expansion difference(double x, double y) {
  double high, low;
  twoSum(x, -y, high, low);
  Expansion e;
  if (low != 0.0) e.push_back(low);
  if (high != 0.0 || e.empty()) e.push_back(high);
  return e;
}

int signOf(const Expansion& e) noexcept {
  for (std::size_t i = e.size(); i-- > 0;)
    if (e[i] != 0.0) return e[i] > 0.0 ? 1 : -1;
  return 0;
}

using ExactVector = std::array<Expansion, 3>;

ExactVector exactDifference(const Vec3& q, const Vec3& p) {
  return {difference(q.x, p.x), difference(q.y, p.y), difference(q.z, p.z)};
}

ExactVector exactCross(const ExactVector& u, const ExactVector& v) {
  return {sum(product(u[1], v[2]), negate(product(u[2], v[1]))),
          sum(product(u[2], v[0]), negate(product(u[0], v[2]))),
          sum(product(u[0], v[1]), negate(product(u[1], v[0])))};
}

/// An integer of any size, for the products of degree 6 that leave a double's exponent range
/// (crossingOrder): a sign and a magnitude in 32-bit limbs, least significant first, no leading
/// zero limb (0 has none).
class BigInteger {
 public:
  BigInteger() = default;
  /// x·2^shift, which must be an integer (x's lowest bit at 2^−shift or above).
  static BigInteger scaled(double x, int shift) {
    BigInteger result;
    if (x == 0.0) return result;
    int exponent = 0;
    const auto mantissa =
        static_cast<std::uint64_t>(std::ldexp(std::abs(std::frexp(x, &exponent)), 53));
    const int position = exponent - 53 + shift;  // of the mantissa's lowest bit, ≥ 0
    result.limbs_.assign(static_cast<std::size_t>(position / 32) + 3, 0);
    const int bit = position % 32;
    const std::size_t limb = static_cast<std::size_t>(position / 32);
    result.limbs_[limb] = static_cast<std::uint32_t>(mantissa << bit);
    result.limbs_[limb + 1] = static_cast<std::uint32_t>(mantissa >> (32 - bit));
    result.limbs_[limb + 2] = static_cast<std::uint32_t>((mantissa >> (32 - bit)) >> 32);
    result.negative_ = x < 0.0;
    result.trim();
    return result;
  }

  int sign() const noexcept { return limbs_.empty() ? 0 : negative_ ? -1 : 1; }

  friend BigInteger operator-(BigInteger a) {
    a.negative_ = !a.negative_;
    return a;
  }
  friend BigInteger operator+(const BigInteger& a, const BigInteger& b) {
    BigInteger result;
    if (a.negative_ == b.negative_) {
      result.limbs_ = addMagnitudes(a.limbs_, b.limbs_);
      result.negative_ = a.negative_;
    } else if (lessInMagnitude(a.limbs_, b.limbs_)) {
      result.limbs_ = subtractMagnitudes(b.limbs_, a.limbs_);
      result.negative_ = b.negative_;
    } else {
      result.limbs_ = subtractMagnitudes(a.limbs_, b.limbs_);
      result.negative_ = a.negative_;
    }
    result.trim();
    return result;
  }
  friend BigInteger operator-(const BigInteger& a, const BigInteger& b) { return a + -b; }
  friend BigInteger operator*(const BigInteger& a, const BigInteger& b) {
    BigInteger result;
    if (a.limbs_.empty() || b.limbs_.empty()) return result;
    result.limbs_.assign(a.limbs_.size() + b.limbs_.size(), 0);
    for (std::size_t i = 0; i < a.limbs_.size(); ++i) {
      std::uint64_t carry = 0;
      for (std::size_t j = 0; j < b.limbs_.size(); ++j) {
        // At most (2³² − 1)² + 2·(2³² − 1) = 2⁶⁴ − 1: no overflow.
        const std::uint64_t sum =
            std::uint64_t{result.limbs_[i + j]} + std::uint64_t{a.limbs_[i]} * b.limbs_[j] + carry;
        result.limbs_[i + j] = static_cast<std::uint32_t>(sum);
        carry = sum >> 32;
      }
      result.limbs_[i + b.limbs_.size()] = static_cast<std::uint32_t>(carry);
    }
    result.negative_ = a.negative_ != b.negative_;
    result.trim();
    return result;
  }

 private:
  using Limbs = std::vector<std::uint32_t>;

  void trim() noexcept {
    while (!limbs_.empty() && limbs_.back() == 0)
      limbs_.pop_back();
  }
  static bool lessInMagnitude(const Limbs& a, const Limbs& b) noexcept {
    if (a.size() != b.size()) return a.size() < b.size();
    for (std::size_t i = a.size(); i-- > 0;)
      if (a[i] != b[i]) return a[i] < b[i];
    return false;
  }
  static Limbs addMagnitudes(const Limbs& a, const Limbs& b) {
    const Limbs& longer = a.size() < b.size() ? b : a;
    const Limbs& shorter = a.size() < b.size() ? a : b;
    Limbs sum(longer.size() + 1, 0);
    std::uint64_t carry = 0;
    for (std::size_t i = 0; i < longer.size(); ++i) {
      carry += std::uint64_t{longer[i]} + (i < shorter.size() ? shorter[i] : 0u);
      sum[i] = static_cast<std::uint32_t>(carry);
      carry >>= 32;
    }
    sum[longer.size()] = static_cast<std::uint32_t>(carry);
    return sum;
  }
  /// |a| − |b| for |a| ≥ |b|.
  static Limbs subtractMagnitudes(const Limbs& a, const Limbs& b) {
    Limbs difference(a.size(), 0);
    std::uint32_t borrow = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
      const std::uint64_t subtrahend = std::uint64_t{i < b.size() ? b[i] : 0u} + borrow;
      borrow = std::uint64_t{a[i]} < subtrahend ? 1u : 0u;
      difference[i] = static_cast<std::uint32_t>(
          (std::uint64_t{a[i]} + (std::uint64_t{borrow} << 32)) - subtrahend);
    }
    return difference;
  }

  Limbs limbs_;
  bool negative_ = false;
};

using BigVector = std::array<BigInteger, 3>;

BigVector bigPoint(const Vec3& p, int shift) {
  return {BigInteger::scaled(p.x, shift), BigInteger::scaled(p.y, shift),
          BigInteger::scaled(p.z, shift)};
}
BigVector bigDifference(const BigVector& u, const BigVector& v) {
  return {u[0] - v[0], u[1] - v[1], u[2] - v[2]};
}
BigVector bigCross(const BigVector& u, const BigVector& v) {
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}
BigInteger bigDot(const BigVector& u, const BigVector& v) {
  return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

/// Where the edge e0 → e1 crosses the plane of triangle t (unperturbed), in floating point:
/// `at` = orient(t, e0) = (e0 − t0)·N and `along` = (e0 − e1)·N, N = (t1 − t0) × (t2 − t0), the
/// crossing at λ = at/along; with Shewchuk's bounds on their rounding (each a determinant of
/// three rounded differences, as orientSign's filter), and N for the displacement's term.
struct PlaneCrossing {
  double at = 0.0, along = 0.0;
  double atBound = 0.0, alongBound = 0.0;
};

PlaneCrossing planeCrossing(const Vec3& e0, const Vec3& e1, const std::array<Vec3, 3>& t) noexcept {
  const Vec3 u = t[1] - t[0], v = t[2] - t[0];
  const double a = u.y * v.z, b = u.z * v.y, c = u.z * v.x, d = u.x * v.z, e = u.x * v.y,
               f = u.y * v.x;
  const Vec3 normal{a - b, c - d, e - f};
  const Vec3 permanent{std::abs(a) + std::abs(b), std::abs(c) + std::abs(d),
                       std::abs(e) + std::abs(f)};
  const auto magnitudes = [](const Vec3& w) {
    return Vec3{std::abs(w.x), std::abs(w.y), std::abs(w.z)};
  };
  const Vec3 at = e0 - t[0], along = e0 - e1;
  return {dot(at, normal), dot(along, normal), kOrientErrorBound * dot(magnitudes(at), permanent),
          kOrientErrorBound * dot(magnitudes(along), permanent)};
}

/// The sign of F = at₁·along₂ − at₂·along₁ where the floating-point values decide it, 0 where
/// they cannot. Each value is within its bound β of the exact one, so each product is within
/// |x̃|β_y + |ỹ|β_x + β_xβ_y of its exact value before its rounding, and the rounding of the two
/// products and their difference adds at most 3ε of their magnitudes. The bound is computed in
/// floating point too (2⁻⁴⁰ of it covers that), and 2⁻¹⁰⁰⁰ any underflow: the points are scaled
/// to coordinates below 2, so that no value exceeds 2¹⁸, and an underflow's error is 2⁻¹⁰⁷⁴.
int filteredCrossingOrder(const PlaneCrossing& first, const PlaneCrossing& second) noexcept {
  const double x = first.at * second.along, y = second.at * first.along;
  const double bound = std::abs(first.at) * second.alongBound +
                       std::abs(second.along) * first.atBound + first.atBound * second.alongBound +
                       std::abs(second.at) * first.alongBound +
                       std::abs(first.along) * second.atBound + second.atBound * first.alongBound +
                       3.0 * 0x1p-53 * (std::abs(x) + std::abs(y));
  const double difference = x - y;
  const double margin = bound * (1.0 + 0x1p-40) + 0x1p-1000;
  return static_cast<int>(difference > margin) - static_cast<int>(-difference > margin);
}

}  // namespace

int crossingOrder(const Vec3& e0, const Vec3& e1, const std::array<Vec3, 3>& first,
                  const std::array<Vec3, 3>& second, bool edgeOfA) {
  // For the filter, scaled by a power of two (exact) to a largest |coordinate| in [1, 2): no
  // product of six differences overflows, and the bound's guard for underflow is relative to
  // that size.
  std::array<Vec3, 8> given;
  given[0] = e0, given[1] = e1;
  std::copy(first.begin(), first.end(), given.begin() + 2);
  std::copy(second.begin(), second.end(), given.begin() + 5);
  double largest = 0.0;
  for (const Vec3& p : given)
    largest = std::max(largest, maxAbs(p));
  if (!(largest > 0.0)) return 0;
  const int exponent = -std::ilogb(largest);
  std::array<Vec3, 8> p;
  for (std::size_t k = 0; k < 8; ++k)
    p[k] = ldexp(given[k], exponent);
  const std::array<Vec3, 3> s{p[2], p[3], p[4]}, t{p[5], p[6], p[7]};
  const PlaneCrossing x = planeCrossing(p[0], p[1], s), y = planeCrossing(p[0], p[1], t);
  const int alongSigns = (x.along > 0.0 ? 1 : -1) * (y.along > 0.0 ? 1 : -1);
  // The filter decides where both `along` are sure of their signs (they never vanish: the
  // planes cross the edge) and F is far enough from 0.
  if (std::abs(x.along) > x.alongBound && std::abs(y.along) > y.alongBound)
    if (const int sign = filteredCrossingOrder(x, y); sign != 0) return alongSigns * sign;

  // Exact, in integers: every coordinate is an integer times 2^−shift (a double's lowest bit),
  // and so is every product of six differences times 2^−6·shift. Some 3,000 bits where the
  // coordinates span the whole range (2⁻²⁵⁰ to 2²⁰⁰): beyond a double's exponents, which
  // expansions of doubles would need (a mesh shifted by 2⁻²⁵⁰ against its copy).
  int shift = 0;
  for (const Vec3& q : given)
    for (std::size_t axis = 0; axis < 3; ++axis)
      if (q[axis] != 0.0) shift = std::max(shift, 52 - std::ilogb(q[axis]));
  std::array<BigVector, 8> big;
  for (std::size_t k = 0; k < 8; ++k)
    big[k] = bigPoint(given[k], shift);
  const BigVector along = bigDifference(big[0], big[1]);
  const BigVector normalS = bigCross(bigDifference(big[3], big[2]), bigDifference(big[4], big[2]));
  const BigVector normalT = bigCross(bigDifference(big[6], big[5]), bigDifference(big[7], big[5]));
  const BigInteger atS = bigDot(bigDifference(big[0], big[2]), normalS);
  const BigInteger atT = bigDot(bigDifference(big[0], big[5]), normalT);
  const BigInteger alongS = bigDot(along, normalS), alongT = bigDot(along, normalT);
  const int signs = alongS.sign() * alongT.sign();
  if (signs == 0) return 0;  // a plane parallel to the edge: not asked
  if (const int sign = (atS * alongT - atT * alongS).sign(); sign != 0) return signs * sign;
  // F = 0: the displacement's term, −τ·G, τ = t for an edge of A (the triangles B's), −t for
  // one of B; t·G has the sign of G's first non-zero component.
  for (std::size_t axis = 0; axis < 3; ++axis)
    if (const int sign = (alongT * normalS[axis] - alongS * normalT[axis]).sign(); sign != 0)
      return signs * (edgeOfA ? -sign : sign);
  return 0;
}

int exactOrientSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const ExactVector u = exactDifference(q, p), v = exactDifference(r, p), w = exactDifference(s, p);
  const ExactVector n = exactCross(u, v);
  return signOf(sum(sum(product(w[0], n[0]), product(w[1], n[1])), product(w[2], n[2])));
}

void ExactTripleProductSum::add(const Vec3& a, const Vec3& b, const Vec3& c) {
  const ExactVector n = exactCross({Expansion{b.x}, Expansion{b.y}, Expansion{b.z}},
                                   {Expansion{c.x}, Expansion{c.y}, Expansion{c.z}});
  sum_ = sum(sum_, sum(sum(scale(n[0], a.x), scale(n[1], a.y)), scale(n[2], a.z)));
}

int ExactTripleProductSum::sign() const noexcept {
  return signOf(sum_);
}

int exactCrossLeadingSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const ExactVector n = exactCross(exactDifference(q, p), exactDifference(s, r));
  for (const Expansion& component : n)
    if (const int sign = signOf(component); sign != 0) return sign;
  return 0;
}

}  // namespace delta::detail
