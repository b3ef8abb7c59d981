#include "exact_predicates.h"

#include <array>
#include <cstddef>
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

}  // namespace

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
