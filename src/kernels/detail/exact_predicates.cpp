#include "exact_predicates.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "delta/core/error.h"

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

/// An integer of up to 32·N bits, for crossingOrder's products of degree 6, which leave a double's
/// exponent range: a sign and a magnitude in 32-bit limbs, limbs[0, size), least significant
/// first, no leading zero limb (0 has none). As with Expansion, the capacity is in the type and
/// grows with each operation (a sum's by one limb, a product's to the sum of its operands'), so
/// that the numbers live on the stack: held in std::vector, they were a third of an overlap
/// between cylinders' caps turned alike (malloc, free and copies), whose crossings along an edge
/// lie within their rounding of one another and are ordered here.
template <std::size_t N>
struct Integer {
  std::array<std::uint32_t, N> limbs;
  std::size_t size = 0;
  bool negative = false;

  int sign() const noexcept { return size == 0 ? 0 : negative ? -1 : 1; }
  void trim() noexcept {
    while (size > 0 && limbs[size - 1] == 0)
      --size;
  }
};

/// The least shift (crossingOrder's: every coordinate is an integer times 2^−shift) and the
/// limbs a coordinate needs with it. A coordinate is below 2²⁰¹ in magnitude (kLargestCoordinate)
/// and 0 or at least 2⁻²⁵⁰ (kSmallestExactCoordinate), so the shift is at most 52 + 250 and the
/// mantissa's lowest bit at most 2⁴⁵⁰: its 53 bits end in limb 16.
constexpr int kMostShift = 52 + 250;
constexpr int kMostCoordinateExponent = 201;  // frexp's, of 2²⁰⁰
constexpr std::size_t kCoordinateLimbs =
    static_cast<std::size_t>((kMostCoordinateExponent - 53 + kMostShift) / 32) + 3;
static_assert(kCoordinateLimbs == 17);

/// The exponent of a normal double x (std::ilogb's, from its bits: ilogb is a call into libm);
/// −1023 for 0 and subnormals.
int exponentOf(double x) noexcept {
  return static_cast<int>((std::bit_cast<std::uint64_t>(x) >> 52) & 0x7ff) - 1023;
}

/// x·2^shift, which must be an integer (x's lowest bit at 2^−shift or above) below 2^(32·17):
/// crossingOrder's bounds above. x is 0 or normal.
Integer<kCoordinateLimbs> scaledInteger(double x, int shift) noexcept {
  Integer<kCoordinateLimbs> result;
  if (x == 0.0) return result;
  // |x| = mantissa·2^(exponent − 52), the mantissa's 53 bits with the implicit one.
  const auto bits = std::bit_cast<std::uint64_t>(x);
  const std::uint64_t mantissa = (bits & ((std::uint64_t{1} << 52) - 1)) | (std::uint64_t{1} << 52);
  const int position = exponentOf(x) - 52 + shift;  // of the mantissa's lowest bit, ≥ 0
  const int bit = position % 32;
  const std::size_t limb = static_cast<std::size_t>(position / 32);
  std::fill(result.limbs.begin(), result.limbs.begin() + static_cast<std::ptrdiff_t>(limb), 0u);
  result.limbs[limb] = static_cast<std::uint32_t>(mantissa << bit);
  result.limbs[limb + 1] = static_cast<std::uint32_t>(mantissa >> (32 - bit));
  result.limbs[limb + 2] = static_cast<std::uint32_t>((mantissa >> (32 - bit)) >> 32);
  result.size = limb + 3;
  result.negative = x < 0.0;
  result.trim();
  return result;
}

/// |a| < |b|.
template <std::size_t N, std::size_t M>
bool lessInMagnitude(const Integer<N>& a, const Integer<M>& b) noexcept {
  if (a.size != b.size) return a.size < b.size;
  for (std::size_t i = a.size; i-- > 0;)
    if (a.limbs[i] != b.limbs[i]) return a.limbs[i] < b.limbs[i];
  return false;
}

/// |a| + |b| into `out` (room for the longer's size + 1).
template <std::size_t K, std::size_t N, std::size_t M>
void addMagnitudes(const Integer<N>& a, const Integer<M>& b, Integer<K>& out) noexcept {
  const std::size_t longest = std::max(a.size, b.size);
  std::uint64_t carry = 0;
  for (std::size_t i = 0; i < longest; ++i) {
    carry += std::uint64_t{i < a.size ? a.limbs[i] : 0u} + (i < b.size ? b.limbs[i] : 0u);
    out.limbs[i] = static_cast<std::uint32_t>(carry);
    carry >>= 32;
  }
  out.limbs[longest] = static_cast<std::uint32_t>(carry);
  out.size = longest + 1;
}

/// |a| − |b| into `out`, for |a| ≥ |b|.
template <std::size_t K, std::size_t N, std::size_t M>
void subtractMagnitudes(const Integer<N>& a, const Integer<M>& b, Integer<K>& out) noexcept {
  std::uint32_t borrow = 0;
  for (std::size_t i = 0; i < a.size; ++i) {
    const std::uint64_t subtrahend = std::uint64_t{i < b.size ? b.limbs[i] : 0u} + borrow;
    borrow = std::uint64_t{a.limbs[i]} < subtrahend ? 1u : 0u;
    out.limbs[i] = static_cast<std::uint32_t>(
        (std::uint64_t{a.limbs[i]} + (std::uint64_t{borrow} << 32)) - subtrahend);
  }
  out.size = a.size;
}

/// a + b, or a − b where `kNegated`.
template <bool kNegated, std::size_t N, std::size_t M>
Integer<std::max(N, M) + 1> combined(const Integer<N>& a, const Integer<M>& b) noexcept {
  Integer<std::max(N, M) + 1> result;
  const bool bNegative = kNegated != b.negative;
  if (a.negative == bNegative) {
    addMagnitudes(a, b, result);
    result.negative = a.negative;
  } else if (lessInMagnitude(a, b)) {
    subtractMagnitudes(b, a, result);
    result.negative = bNegative;
  } else {
    subtractMagnitudes(a, b, result);
    result.negative = a.negative;
  }
  result.trim();
  return result;
}

template <std::size_t N, std::size_t M>
Integer<std::max(N, M) + 1> operator+(const Integer<N>& a, const Integer<M>& b) noexcept {
  return combined<false>(a, b);
}
template <std::size_t N, std::size_t M>
Integer<std::max(N, M) + 1> operator-(const Integer<N>& a, const Integer<M>& b) noexcept {
  return combined<true>(a, b);
}
template <std::size_t N, std::size_t M>
Integer<N + M> operator*(const Integer<N>& a, const Integer<M>& b) noexcept {
  Integer<N + M> result;
  if (a.size == 0 || b.size == 0) return result;
  // Row i adds a's limb i times b into limbs [i, i + b.size]; all but the last were written by
  // row i − 1, and row 0's are zeroed here.
  std::fill(result.limbs.begin(), result.limbs.begin() + static_cast<std::ptrdiff_t>(b.size), 0u);
  for (std::size_t i = 0; i < a.size; ++i) {
    std::uint64_t carry = 0;
    for (std::size_t j = 0; j < b.size; ++j) {
      // At most (2³² − 1)² + 2·(2³² − 1) = 2⁶⁴ − 1: no overflow.
      const std::uint64_t sum =
          std::uint64_t{result.limbs[i + j]} + std::uint64_t{a.limbs[i]} * b.limbs[j] + carry;
      result.limbs[i + j] = static_cast<std::uint32_t>(sum);
      carry = sum >> 32;
    }
    result.limbs[i + b.size] = static_cast<std::uint32_t>(carry);
  }
  result.size = a.size + b.size;
  result.negative = a.negative != b.negative;
  result.trim();
  return result;
}

template <std::size_t N>
using IntegerVector = std::array<Integer<N>, 3>;

IntegerVector<kCoordinateLimbs> integerPoint(const Vec3& p, int shift) noexcept {
  return {scaledInteger(p.x, shift), scaledInteger(p.y, shift), scaledInteger(p.z, shift)};
}
template <std::size_t N>
IntegerVector<N + 1> integerDifference(const IntegerVector<N>& u,
                                       const IntegerVector<N>& v) noexcept {
  return {u[0] - v[0], u[1] - v[1], u[2] - v[2]};
}
template <std::size_t N>
IntegerVector<2 * N + 1> integerCross(const IntegerVector<N>& u,
                                      const IntegerVector<N>& v) noexcept {
  return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}
template <std::size_t N, std::size_t M>
Integer<N + M + 2> integerDot(const IntegerVector<N>& u, const IntegerVector<M>& v) noexcept {
  return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

/// The points as integers times 2^−shift, one shift for all (the least that makes every
/// coordinate an integer: its lowest bit's); delta::Error naming `what` for a coordinate the
/// predicates do not take (below kSmallestExactCoordinate but not 0, or beyond the coordinate
/// range), for which the integers' capacities would not hold.
template <std::size_t N>
std::array<IntegerVector<kCoordinateLimbs>, N> integerPoints(const std::array<Vec3, N>& given,
                                                             const char* what) {
  int shift = 0;
  double largest = 0.0;
  for (const Vec3& q : given)
    for (std::size_t axis = 0; axis < 3; ++axis) {
      largest = std::max(largest, std::abs(q[axis]));
      if (q[axis] != 0.0) shift = std::max(shift, 52 - exponentOf(q[axis]));
    }
  if (shift > kMostShift || !(largest < std::ldexp(1.0, kMostCoordinateExponent)))
    throw Error(std::string(what) +
                ": a coordinate outside the predicates' range (internal error)");
  std::array<IntegerVector<kCoordinateLimbs>, N> big;
  for (std::size_t k = 0; k < N; ++k)
    big[k] = integerPoint(given[k], shift);
  return big;
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

/// The sign of orient(p, q, r, s) from the rounded differences u = q − p, v = r − p, w = s − p
/// in double-double arithmetic, where its error bound decides it; 0 where it cannot (the full
/// expansion then does), and where the permanent P (of the rounded differences, as the filter's)
/// is below 2⁻⁹⁰⁰, so that every bound stays far above any product's underflow (2⁻¹⁰⁷⁴ each).
///
/// det[u; v; w] expanded along z, as Shewchuk's orient3d: Σ f·M over the rows, f a row's z and M
/// the 2×2 minor of the other two rows' x and y. The exact determinant of the given points is
/// that of the exact differences u + uₜ (uₜ = the tail twoSum leaves, |uₜ| ≤ ε|u|, ε = 2⁻⁵³),
/// trilinear in them: the determinant B of the rounded differences, the three terms of first
/// order in the tails (Shewchuk's stage C's expression, evaluated plainly), and terms of second
/// and third order, at most 3.01ε²P together, left out. With u the unit roundoff ε:
/// - each minor a·b − c·d as two products exactly (twoProduct), their heads' difference exactly
///   (twoSum) and the rest plainly: within 3.1ε²m of it, m = |ab| + |cd|, its low part below
///   2.2εm;
/// - each f·M as f times the head exactly and f·low added plainly: within 6.5ε²|f|m, so the
///   three within 6.5ε²P (Σ|f|m = P);
/// - the heads summed exactly (twoSum) and the five low parts (each below 3.3ε|f|m, the twoSums'
///   below 2.01εP together) in three rounding steps: 16ε²P;
/// - the first-order terms, below 3εP in all, in at most six rounding steps: 18ε²P;
/// - adding them to the low parts: 8.6ε²P.
/// In all within 56ε²P before the last addition, which rounds by ε of the result: a computed
/// value beyond 128ε²P (P's own rounding is a few ε of it) + 4ε of itself has the exact sign.
/// It decides what Shewchuk's stages B and C decided here (they stopped at 3ε and 26ε² of P),
/// but without their exact expansion of B: its sums of components one after the other (forty
/// dependent steps) made an exact orientation of four points a few ulps off a plane, the overlap
/// of faces coplanar but for the rounding of their turned corners, cost 300 ns.
int doubleDoubleOrientSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s,
                           const Vec3& u, const Vec3& v, const Vec3& w) noexcept {
  // Shewchuk's names: a, b, c the rows u, v, w, expanded along z.
  const double adx = u.x, ady = u.y, adz = u.z, bdx = v.x, bdy = v.y, bdz = v.z, cdx = w.x,
               cdy = w.y, cdz = w.z;
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy, cdxady = cdx * ady, adxcdy = adx * cdy,
               adxbdy = adx * bdy, bdxady = bdx * ady;
  const double permanent = (std::abs(bdxcdy) + std::abs(cdxbdy)) * std::abs(adz) +
                           (std::abs(cdxady) + std::abs(adxcdy)) * std::abs(bdz) +
                           (std::abs(adxbdy) + std::abs(bdxady)) * std::abs(cdz);
  if (!(permanent >= 0x1p-900)) return 0;
  struct DoubleDouble {
    double high, low;
  };
  const auto minor = [](double a, double b, double c, double d) {  // a·b − c·d
    double x1, x0, y1, y0, high, low;
    twoProduct(a, b, x1, x0);
    twoProduct(c, d, y1, y0);
    twoSum(x1, -y1, high, low);
    return DoubleDouble{high, low + (x0 - y0)};
  };
  const auto times = [](double f, const DoubleDouble& m) {  // f·m
    double high, low;
    twoProduct(f, m.high, high, low);
    return DoubleDouble{high, low + f * m.low};
  };
  const DoubleDouble x = times(adz, minor(bdx, cdy, cdx, bdy));
  const DoubleDouble y = times(bdz, minor(cdx, ady, adx, cdy));
  const DoubleDouble z = times(cdz, minor(adx, bdy, bdx, ady));
  double partial, partialLow, head, headLow;
  twoSum(x.high, y.high, partial, partialLow);
  twoSum(partial, z.high, head, headLow);
  const double lows = (partialLow + headLow) + ((x.low + y.low) + z.low);
  const auto tail = [](double a, double b) {  // (a − b) − fl(a − b), exactly
    double high, low;
    twoSum(a, -b, high, low);
    return low;
  };
  const double adxt = tail(q.x, p.x), adyt = tail(q.y, p.y), adzt = tail(q.z, p.z);
  const double bdxt = tail(r.x, p.x), bdyt = tail(r.y, p.y), bdzt = tail(r.z, p.z);
  const double cdxt = tail(s.x, p.x), cdyt = tail(s.y, p.y), cdzt = tail(s.z, p.z);
  const double firstOrder = (adz * ((bdx * cdyt + cdy * bdxt) - (bdy * cdxt + cdx * bdyt)) +
                             adzt * (bdx * cdy - bdy * cdx)) +
                            (bdz * ((cdx * adyt + ady * cdxt) - (cdy * adxt + adx * cdyt)) +
                             bdzt * (cdx * ady - cdy * adx)) +
                            (cdz * ((adx * bdyt + bdy * adxt) - (ady * bdxt + bdx * adyt)) +
                             cdzt * (adx * bdy - ady * bdx));
  const double det = head + (lows + firstOrder);
  constexpr double kEpsilon = 0x1p-53;
  const double bound = 128.0 * kEpsilon * kEpsilon * permanent + 4.0 * kEpsilon * std::abs(det);
  return static_cast<int>(det > bound) - static_cast<int>(-det > bound);
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
  const auto big = integerPoints(given, "crossingOrder");
  const auto along = integerDifference(big[0], big[1]);
  const auto normalS =
      integerCross(integerDifference(big[3], big[2]), integerDifference(big[4], big[2]));
  const auto normalT =
      integerCross(integerDifference(big[6], big[5]), integerDifference(big[7], big[5]));
  const auto atS = integerDot(integerDifference(big[0], big[2]), normalS);
  const auto atT = integerDot(integerDifference(big[0], big[5]), normalT);
  const auto alongS = integerDot(along, normalS), alongT = integerDot(along, normalT);
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

int exactFaceAreaSign(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& s, const Vec3& e,
                      const Vec3& p) {
  const auto big = integerPoints(std::array<Vec3, 6>{a, b, c, s, e, p}, "exactFaceAreaSign");
  const auto normal =
      integerCross(integerDifference(big[1], big[0]), integerDifference(big[2], big[0]));
  const auto side =
      integerCross(integerDifference(big[4], big[3]), integerDifference(big[5], big[3]));
  return integerDot(normal, side).sign();
}

int exactOrientSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) noexcept {
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
  if (const int sign = doubleDoubleOrientSign(p, q, r, s, u, v, w); sign != 0) return sign;
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

int exactCrossLeadingSign(const Vec3& p, const Vec3& q, const Vec3& r, const Vec3& s) noexcept {
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
