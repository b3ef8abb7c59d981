#include "exact_predicates.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace delta::detail {
namespace {

// Shewchuk's expansion arithmetic: a number is an unevaluated sum of doubles, non-overlapping and
// in increasing magnitude, zeros eliminated. Exact for any sums and products of doubles that
// neither overflow nor underflow (the coordinate range keeps them inside, coordinate_range.h).
//
// An expansion's capacity is part of its type, carried through every operation (a sum's is the
// sum of its operands', a product's twice their product), so every predicate's numbers live on
// the stack: held in std::vector, as they were, malloc and free were half the profile of an
// overlap query between coplanar faces (169 µs for two turned cubes, 20 µs a hair apart).

/// At most N components, in terms[0, size).
template <std::size_t N>
struct Expansion {
  std::array<double, N> terms;
  std::size_t size = 0;

  Expansion() noexcept = default;
  explicit Expansion(double x) noexcept : size(1) { terms[0] = x; }

  void push(double term) noexcept { terms[size++] = term; }
  const double* begin() const noexcept { return terms.data(); }
  const double* end() const noexcept { return terms.data() + size; }
};

/// a + b = x + y exactly, x = fl(a + b).
[[gnu::always_inline]] inline void twoSum(double a, double b, double& x, double& y) noexcept {
  x = a + b;
  const double bVirtual = x - a;
  const double aVirtual = x - bVirtual;
  y = (a - aVirtual) + (b - bVirtual);
}

/// a·b = x + y exactly, x = fl(a·b): by a fused multiply–add where the instruction set has one,
/// else by Dekker's splitting (the same y, exactly: on the x86-64 baseline std::fma is a call
/// into libm, a tenth of an exact orientation). The split's a·(2²⁷ + 1) stays finite: the
/// predicates' numbers are below 2⁶⁰⁴ (coordinate_range.h).
[[gnu::always_inline]] inline void twoProduct(double a, double b, double& x, double& y) noexcept {
  x = a * b;
#if defined(__FMA__) || defined(__aarch64__)
  y = std::fma(a, b, -x);
#else
  const auto split = [](double v, double& high, double& low) {
    const double c = 134217729.0 * v;  // 2²⁷ + 1
    high = c - (c - v);
    low = v - high;
  };
  double aHigh, aLow, bHigh, bLow;
  split(a, aHigh, aLow);
  split(b, bHigh, bLow);
  y = aLow * bLow - (((x - aHigh * bHigh) - aLow * bHigh) - aHigh * bLow);
#endif
}

/// terms[0, size) += component, in place (grow_expansion_zeroelim); returns the new size, at
/// most size + 1, for which `terms` needs room. The output's k-th term is written after the
/// input's k-th is read, so one array serves both.
[[gnu::always_inline]] inline std::size_t growTerms(double* terms, std::size_t size,
                                                    double component) noexcept {
  double q = component;
  std::size_t out = 0;
  for (std::size_t i = 0; i < size; ++i) {
    double sumHigh, sumLow;
    twoSum(q, terms[i], sumHigh, sumLow);
    if (sumLow != 0.0) terms[out++] = sumLow;
    q = sumHigh;
  }
  if (q != 0.0 || out == 0) terms[out++] = q;
  return out;
}

/// h += component (growTerms): h needs room for one more term.
template <std::size_t N>
[[gnu::always_inline]] inline void grow(Expansion<N>& h, double component) noexcept {
  h.size = growTerms(h.terms.data(), h.size, component);
}

/// e + f, or e − f where `kNegated`: every component of f (negated: exactly) grown into e
/// (fast_expansion_sum_zeroelim's result, by grow steps done plainly).
template <bool kNegated, std::size_t N, std::size_t M>
[[gnu::always_inline]] inline Expansion<N + M> combined(const Expansion<N>& e,
                                                        const Expansion<M>& f) noexcept {
  Expansion<N + M> h;
  std::copy(e.begin(), e.end(), h.terms.begin());
  h.size = e.size;
  for (const double component : f)
    grow(h, kNegated ? -component : component);
  return h;
}

template <std::size_t N, std::size_t M>
[[gnu::always_inline]] inline Expansion<N + M> sum(const Expansion<N>& e,
                                                   const Expansion<M>& f) noexcept {
  return combined<false>(e, f);
}

template <std::size_t N, std::size_t M>
[[gnu::always_inline]] inline Expansion<N + M> subtract(const Expansion<N>& e,
                                                        const Expansion<M>& f) noexcept {
  return combined<true>(e, f);
}

/// e·b (scale_expansion_zeroelim).
template <std::size_t N>
[[gnu::always_inline]] inline Expansion<2 * N> scale(const Expansion<N>& e, double b) noexcept {
  Expansion<2 * N> h;
  if (e.size == 0) return h;
  double q, low;
  twoProduct(e.terms[0], b, q, low);
  if (low != 0.0) h.push(low);
  for (std::size_t i = 1; i < e.size; ++i) {
    double productHigh, productLow;
    twoProduct(e.terms[i], b, productHigh, productLow);
    double sumHigh, sumLow;
    twoSum(q, productLow, sumHigh, sumLow);
    if (sumLow != 0.0) h.push(sumLow);
    double highest;
    twoSum(productHigh, sumHigh, highest, sumLow);
    if (sumLow != 0.0) h.push(sumLow);
    q = highest;
  }
  if (q != 0.0 || h.size == 0) h.push(q);
  return h;
}

/// e·f: the sum of e scaled by each component of f.
template <std::size_t N, std::size_t M>
[[gnu::always_inline]] inline Expansion<2 * N * M> product(const Expansion<N>& e,
                                                           const Expansion<M>& f) noexcept {
  Expansion<2 * N * M> h;
  for (const double component : f)
    for (const double term : scale(e, component))
      grow(h, term);
  return h;
}

/// x − y exactly.
Expansion<2> difference(double x, double y) noexcept {
  double high, low;
  twoSum(x, -y, high, low);
  Expansion<2> e;
  if (low != 0.0) e.push(low);
  if (high != 0.0 || e.size == 0) e.push(high);
  return e;
}

/// The sign of the expansion terms[0, size): its largest non-zero term's.
int signOfTerms(const double* terms, std::size_t size) noexcept {
  for (std::size_t i = size; i-- > 0;)
    if (terms[i] != 0.0) return terms[i] > 0.0 ? 1 : -1;
  return 0;
}

template <std::size_t N>
int signOf(const Expansion<N>& e) noexcept {
  return signOfTerms(e.terms.data(), e.size);
}

template <std::size_t N>
using ExactVector = std::array<Expansion<N>, 3>;

ExactVector<2> exactDifference(const Vec3& q, const Vec3& p) noexcept {
  return {difference(q.x, p.x), difference(q.y, p.y), difference(q.z, p.z)};
}

template <std::size_t N>
ExactVector<4 * N * N> exactCross(const ExactVector<N>& u, const ExactVector<N>& v) noexcept {
  return {subtract(product(u[1], v[2]), product(u[2], v[1])),
          subtract(product(u[2], v[0]), product(u[0], v[2])),
          subtract(product(u[0], v[1]), product(u[1], v[0]))};
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

/// Shewchuk's adaptive stages B and C of orient3d ("Adaptive Precision Floating-Point Arithmetic
/// and Fast Robust Geometric Predicates", 1997, section 4.3), for the determinant
/// det[u; v; w] = orient(p, q, r, s) of the rounded differences u = q − p, v = r − p, w = s − p:
/// B evaluates it exactly from the rounded differences and decides where that is beyond
/// (3 + 28ε)ε of the permanent; C adds the differences' rounding errors to first order and
/// decides beyond (26 + 288ε)ε² of the permanent and (3 + 8ε)ε of the result. 0 where neither
/// decides (the full expansion then does), and where the permanent is below 2⁻⁹⁰⁰, so that the
/// bounds stay far above any product's underflow. Faces coplanar but for the rounding of turned
/// corners put four points a few ulps off a plane: C decides them, where the full expansion of
/// differences that are not doubles took a tenth of a microsecond each.
int adaptiveOrientSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s, const Vec3& u,
                       const Vec3& v, const Vec3& w) noexcept {
  // Shewchuk's names: a, b, c the rows u, v, w, expanded along z.
  const double adx = u.x, ady = u.y, adz = u.z, bdx = v.x, bdy = v.y, bdz = v.z, cdx = w.x,
               cdy = w.y, cdz = w.z;
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy, cdxady = cdx * ady, adxcdy = adx * cdy,
               adxbdy = adx * bdy, bdxady = bdx * ady;
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(adz) +
                           (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bdz) +
                           (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cdz);
  if (!(permanent >= 0x1p-900)) return 0;
  constexpr double kEpsilon = 0x1p-53;
  constexpr double kBoundB = (3.0 + 28.0 * kEpsilon) * kEpsilon;
  constexpr double kBoundC = (26.0 + 288.0 * kEpsilon) * kEpsilon * kEpsilon;
  constexpr double kResultBound = (3.0 + 8.0 * kEpsilon) * kEpsilon;
  const auto minor = [](double a, double b, double c, double d) {  // a·b − c·d, exactly
    return subtract(product(Expansion<1>{a}, Expansion<1>{b}),
                    product(Expansion<1>{c}, Expansion<1>{d}));
  };
  const auto whole =
      sum(sum(scale(minor(bdx, cdy, cdx, bdy), adz), scale(minor(cdx, ady, adx, cdy), bdz)),
          scale(minor(adx, bdy, bdx, ady), cdz));
  double det = 0.0;
  for (const double term : whole)
    det += term;
  const double boundB = kBoundB * permanent;
  if (det > boundB) return 1;
  if (-det > boundB) return -1;
  const auto tail = [](double x, double y) {  // (x − y) − fl(x − y), exactly
    double high, low;
    twoSum(x, -y, high, low);
    return low;
  };
  const double adxt = tail(q.x, p.x), adyt = tail(q.y, p.y), adzt = tail(q.z, p.z);
  const double bdxt = tail(r.x, p.x), bdyt = tail(r.y, p.y), bdzt = tail(r.z, p.z);
  const double cdxt = tail(s.x, p.x), cdyt = tail(s.y, p.y), cdzt = tail(s.z, p.z);
  const double boundC = kBoundC * permanent + kResultBound * std::abs(det);
  det += (adz * ((bdx * cdyt + cdy * bdxt) - (bdy * cdxt + cdx * bdyt)) +
          adzt * (bdx * cdy - bdy * cdx)) +
         (bdz * ((cdx * adyt + ady * cdxt) - (cdy * adxt + adx * cdyt)) +
          bdzt * (cdx * ady - cdy * adx)) +
         (cdz * ((adx * bdyt + bdy * adxt) - (ady * bdxt + bdx * adyt)) +
          cdzt * (adx * bdy - ady * bdx));
  if (det > boundC) return 1;
  if (-det > boundC) return -1;
  return 0;
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
  std::array<Vec3, 8> p;
  if (largest >= 0x1p-1000 && largest < 0x1p1000) {
    // 2^−⌊log₂ largest⌋ from the exponent's bits, and products by it, which are exact here (every
    // coordinate 0 or from 2⁻²⁵⁰ to 2²⁰⁰, the results from 2⁻⁴⁵⁰ to 2): std::ilogb and ldexp
    // are calls into libm, 24 of them a call, and a twentieth of a volume-law DEM step.
    const auto biased = static_cast<std::int64_t>(std::bit_cast<std::uint64_t>(largest) >> 52);
    const double factor = std::bit_cast<double>(static_cast<std::uint64_t>(2046 - biased) << 52);
    for (std::size_t k = 0; k < 8; ++k)
      p[k] = given[k] * factor;
  } else {
    const int exponent = -std::ilogb(largest);
    for (std::size_t k = 0; k < 8; ++k)
      p[k] = ldexp(given[k], exponent);
  }
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
  // Two of the points the same (a mesh against a copy of itself, a vertex of one mesh on a
  // corner of the other's triangle): 0, where the adaptive stages would each fail before the
  // full expansion found it.
  if (q == p || r == p || s == p || r == q || s == q || s == r) return 0;
  // A difference of doubles rounds to 0 only where it is 0: where each of the determinant's six
  // products has a zero difference among its factors (four points in a plane of constant z, the
  // overlap of faces coplanar in it), the determinant is exactly 0 without evaluating it.
  const Vec3 u = q - p, v = r - p, w = s - p;
  const auto zeroProducts = [](double a, double b, double c, double d, double e, double f) {
    return (a == 0.0 || b == 0.0 || c == 0.0) && (d == 0.0 || e == 0.0 || f == 0.0);
  };
  if (zeroProducts(u.x, v.y, w.z, u.x, v.z, w.y) && zeroProducts(u.y, v.z, w.x, u.y, v.x, w.z) &&
      zeroProducts(u.z, v.x, w.y, u.z, v.y, w.x))
    return 0;
  if (const int sign = adaptiveOrientSign(p, q, r, s, u, v, w); sign != 0) return sign;
  const ExactVector<2> eu = exactDifference(q, p), ev = exactDifference(r, p),
                       ew = exactDifference(s, p);
  const ExactVector<16> n = exactCross(eu, ev);
  return signOf(sum(sum(product(ew[0], n[0]), product(ew[1], n[1])), product(ew[2], n[2])));
}

void ExactTripleProductSum::add(const Vec3& a, const Vec3& b, const Vec3& c) {
  const ExactVector<4> n =
      exactCross(ExactVector<1>{Expansion<1>{b.x}, Expansion<1>{b.y}, Expansion<1>{b.z}},
                 ExactVector<1>{Expansion<1>{c.x}, Expansion<1>{c.y}, Expansion<1>{c.z}});
  const auto term = sum(sum(scale(n[0], a.x), scale(n[1], a.y)), scale(n[2], a.z));
  // Into the running sum, which may grow without limit: room for one more term each time.
  for (const double component : term) {
    const std::size_t size = sum_.size();
    sum_.push_back(0.0);
    sum_.resize(growTerms(sum_.data(), size, component));
  }
}

int ExactTripleProductSum::sign() const noexcept {
  return signOfTerms(sum_.data(), sum_.size());
}

int exactCrossLeadingSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) {
  const Vec3 u = q - p, v = s - r;
  // Each component a·b − c·d of differences: 0 where both products have a zero factor (a
  // difference rounds to 0 only where it is 0); else the sign of the rounded value where it
  // exceeds Shewchuk's bound for orient2d's determinant ((3 + 16ε)ε of |a·b| + |c·d|, the
  // differences' rounding included), grown by 2⁻¹⁰²⁰ for products that fell below the normal
  // range; else exact.
  const double factors[3][4] = {{u.y, v.z, u.z, v.y}, {u.z, v.x, u.x, v.z}, {u.x, v.y, u.y, v.x}};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const auto [a, b, c, d] = factors[axis];
    if ((a == 0.0 || b == 0.0) && (c == 0.0 || d == 0.0)) continue;
    const double left = a * b, right = c * d, value = left - right;
    const double bound =
        (3.0 + 16.0 * 0x1p-53) * 0x1p-53 * (std::abs(left) + std::abs(right)) + 0x1p-1020;
    if (value > bound) return 1;
    if (-value > bound) return -1;
    const ExactVector<2> eu = exactDifference(q, p), ev = exactDifference(s, r);
    const std::size_t first = (axis + 1) % 3, second = (axis + 2) % 3;
    if (const int sign =
            signOf(subtract(product(eu[first], ev[second]), product(eu[second], ev[first])));
        sign != 0)
      return sign;
  }
  return 0;
}

}  // namespace delta::detail
