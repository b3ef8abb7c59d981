#pragma once

// Triangle pairs for the kernel tests, by family, deterministic by seed. Every kernel test (brute
// force, penalty, hybrid, SIMD batches) draws its pairs from here so that they all meet the same
// adversarial cases.
//
// Only the raw 64-bit output of std::mt19937_64 is used (its sequence is fixed by the standard);
// the conversions to doubles are written out below, so the pairs are the same with every standard
// library. Where a family needs exact coincidences (exactly coplanar, exactly parallel, exactly
// touching) the coordinates are dyadic rationals on a 2^-20 grid, so the sums and midpoints that
// build them are exact in double.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/triangle.h"
#include "delta/core/vec3.h"

#include "../sanitized.h"  // relative: bench/kernels_bench.cpp includes this file too

namespace delta::test {

enum class PairFamily {
  Random,               ///< vertices uniform in two overlapping cubes: about one in nine intersect
  NearContact,          ///< DEM-like: similar sizes, separated by a plane, gap 0–0.2 of the size
  Far,                  ///< 3–50 sizes apart
  ParallelFaces,        ///< in parallel planes (exactly, or rotated and rounded), gap 0–0.3
  CoplanarOverlapping,  ///< in one plane, overlapping (exactly coplanar, or rotated and rounded)
  CoplanarDisjoint,     ///< in one plane, separated by a line in it
  ParallelEdges,        ///< an edge of B is an exact translate of an edge of A (some collinear)
  EdgeThroughFace,      ///< an edge of B pierces the interior of A (some end on A: a T)
  TouchingAtVertex,     ///< a vertex of B lies exactly on a vertex, an edge or the face of A
  Sliver,               ///< needles: one height 1e-4 … 1e-10 of the longest edge
  ZeroArea,             ///< exactly collinear vertices, repeated vertices, a point
  Tiny,                 ///< NearContact and Random pairs scaled to a size of 1e-6
  HugeOffset,           ///< NearContact and Random pairs moved by about 1e6 in every coordinate
};

inline constexpr std::array kAllFamilies = {
    PairFamily::Random,
    PairFamily::NearContact,
    PairFamily::Far,
    PairFamily::ParallelFaces,
    PairFamily::CoplanarOverlapping,
    PairFamily::CoplanarDisjoint,
    PairFamily::ParallelEdges,
    PairFamily::EdgeThroughFace,
    PairFamily::TouchingAtVertex,
    PairFamily::Sliver,
    PairFamily::ZeroArea,
    PairFamily::Tiny,
    PairFamily::HugeOffset,
};

inline const char* name(PairFamily family) {
  switch (family) {
    case PairFamily::Random:
      return "Random";
    case PairFamily::NearContact:
      return "NearContact";
    case PairFamily::Far:
      return "Far";
    case PairFamily::ParallelFaces:
      return "ParallelFaces";
    case PairFamily::CoplanarOverlapping:
      return "CoplanarOverlapping";
    case PairFamily::CoplanarDisjoint:
      return "CoplanarDisjoint";
    case PairFamily::ParallelEdges:
      return "ParallelEdges";
    case PairFamily::EdgeThroughFace:
      return "EdgeThroughFace";
    case PairFamily::TouchingAtVertex:
      return "TouchingAtVertex";
    case PairFamily::Sliver:
      return "Sliver";
    case PairFamily::ZeroArea:
      return "ZeroArea";
    case PairFamily::Tiny:
      return "Tiny";
    case PairFamily::HugeOffset:
      return "HugeOffset";
  }
  return "?";
}

/// True in builds much slower than an optimised one (sanitizers, an emulator such as qemu, or no
/// optimisation): the randomised tests then run fewer pairs, `scaledCount(n)`, to stay within a
/// few minutes.
#if defined(DELTA_TESTS_SANITIZED) || defined(DELTA_TESTS_EMULATED) || !defined(__OPTIMIZE__)
inline constexpr bool kSlowBuild = true;
#else
inline constexpr bool kSlowBuild = false;
#endif

/// n in an optimised build, n / 4 (at least 1) in a slow one.
inline constexpr std::size_t scaledCount(std::size_t n) {
  return kSlowBuild ? std::max<std::size_t>(1, n / 4) : n;
}

/// The largest edge length of the two triangles: the scale every tolerance is relative to.
inline double pairSize(const Triangle& first, const Triangle& second) {
  double longest = 0.0;
  for (const Triangle* t : {&first, &second}) {
    longest = std::max({longest, distance(t->a, t->b), distance(t->b, t->c), distance(t->c, t->a)});
  }
  return longest;
}

/// Both triangles' 18 coordinates at full precision, as C++ that pastes straight into a test.
inline std::string pasteable(const Triangle& first, const Triangle& second) {
  auto vertex = [](const Vec3& v) {
    char text[96];
    std::snprintf(text, sizeof text, "{%.17g, %.17g, %.17g}", v.x, v.y, v.z);
    return std::string(text);
  };
  auto triangle = [&](const char* variable, const Triangle& t) {
    return std::string("const Triangle ") + variable + "{" + vertex(t.a) + ", " + vertex(t.b) +
           ", " + vertex(t.c) + "};\n";
  };
  return triangle("first", first) + triangle("second", second);
}

/// Doubles from the raw output of std::mt19937_64, converted here (no std distributions).
class PairRandom {
 public:
  explicit PairRandom(std::uint64_t seed) : engine_(seed) {}

  std::uint64_t bits() { return engine_(); }
  /// Uniform in [0, 1), on the 2^-53 grid.
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double uniform(double low, double high) { return low + (high - low) * uniform(); }
  /// Uniform in {0, …, count − 1} (the modulo bias is below 2^-50 for small counts).
  int below(int count) { return static_cast<int>(engine_() % static_cast<std::uint64_t>(count)); }
  /// A dyadic rational in [-1, 1), a multiple of 2^-20: sums of a few stay exact.
  double dyadic() {
    const auto k = static_cast<std::int64_t>(engine_() >> 43) - (std::int64_t{1} << 20);
    return static_cast<double>(k) * 0x1.0p-20;
  }
  Vec3 inCube(double half) {
    return {uniform(-half, half), uniform(-half, half), uniform(-half, half)};
  }
  Vec3 dyadicInCube() { return {dyadic(), dyadic(), dyadic()}; }
  /// Uniform on the unit sphere (rejection from the cube).
  Vec3 unitVector() {
    for (;;) {
      const Vec3 v = inCube(1.0);
      const double n2 = lengthSquared(v);
      if (n2 > 1e-4 && n2 <= 1.0) return v / std::sqrt(n2);
    }
  }

 private:
  std::mt19937_64 engine_;
};

namespace detail {

using Pair = std::pair<Triangle, Triangle>;

inline Triangle translated(const Triangle& t, const Vec3& by) {
  return {t.a + by, t.b + by, t.c + by};
}
inline Triangle scaled(const Triangle& t, double factor) {
  return {t.a * factor, t.b * factor, t.c * factor};
}

/// A random rotation (from a random unit quaternion) applied to every vertex, then `shift`.
inline Pair rotated(const Pair& pair, PairRandom& random, const Vec3& shift) {
  double w, x, y, z, n2;
  do {
    w = random.uniform(-1, 1), x = random.uniform(-1, 1), y = random.uniform(-1, 1);
    z = random.uniform(-1, 1);
    n2 = w * w + x * x + y * y + z * z;
  } while (n2 < 1e-4 || n2 > 1.0);
  const double s = 2.0 / n2;
  const Vec3 row0{1 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y)};
  const Vec3 row1{s * (x * y + w * z), 1 - s * (x * x + z * z), s * (y * z - w * x)};
  const Vec3 row2{s * (x * z - w * y), s * (y * z + w * x), 1 - s * (x * x + y * y)};
  auto move = [&](const Vec3& p) { return Vec3{dot(row0, p), dot(row1, p), dot(row2, p)} + shift; };
  auto moveTriangle = [&](const Triangle& t) { return Triangle{move(t.a), move(t.b), move(t.c)}; };
  return {moveTriangle(pair.first), moveTriangle(pair.second)};
}

/// Three vertices within distance `radius` of `center` (a DEM particle's facet, roughly).
inline Triangle triangleAround(PairRandom& random, const Vec3& center, double radius) {
  auto vertex = [&] { return center + random.unitVector() * (radius * random.uniform(0.3, 1.0)); };
  const Vec3 a = vertex(), b = vertex(), c = vertex();
  return {a, b, c};
}

/// Any unit vector orthogonal to the unit vector `n`.
inline Vec3 orthogonal(const Vec3& n) {
  const Vec3 helper = std::fabs(n.x) < 0.6 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  return normalized(cross(n, helper));
}

inline double extent(const Triangle& t, const Vec3& direction, bool largest) {
  const double da = dot(t.a, direction), db = dot(t.b, direction), dc = dot(t.c, direction);
  return largest ? std::max({da, db, dc}) : std::min({da, db, dc});
}

/// Moves `second` along `n` so that a plane orthogonal to `n` separates the two with the given
/// gap (`first` below, `second` above), and sideways by up to `slide` in the plane.
inline Pair separate(const Triangle& first, const Triangle& second, const Vec3& n, double gap,
                     double slide, PairRandom& random) {
  const Vec3 u = orthogonal(n), v = cross(n, u);
  const Vec3 sideways = u * (slide * random.uniform(-1, 1)) + v * (slide * random.uniform(-1, 1));
  const double lift = extent(first, n, true) - extent(second, n, false) + gap;
  return {first, translated(second, n * lift + sideways)};
}

inline Pair randomPair(PairRandom& random) {
  const Triangle first{random.inCube(1), random.inCube(1), random.inCube(1)};
  const Vec3 offset = random.inCube(1);
  return {first, Triangle{random.inCube(1) + offset, random.inCube(1) + offset,
                          random.inCube(1) + offset}};
}

inline Pair nearContactPair(PairRandom& random) {
  const Triangle first = triangleAround(random, {}, 0.5);
  const Triangle second = triangleAround(random, {}, 0.5 * random.uniform(0.5, 1.5));
  const double size = pairSize(first, second);
  return separate(first, second, random.unitVector(), random.uniform(0, 0.2) * size, 0.5 * size,
                  random);
}

inline Pair farPair(PairRandom& random) {
  const Triangle first = triangleAround(random, {}, 0.5);
  const Triangle second = triangleAround(random, {}, 0.5 * random.uniform(0.5, 1.5));
  const double size = pairSize(first, second);
  return {first, translated(second, random.unitVector() * (size * random.uniform(3, 50)))};
}

inline Pair parallelFacesPair(PairRandom& random) {
  auto inPlane = [&](double z) { return Vec3{random.dyadic(), random.dyadic(), z}; };
  const double gap =
      random.below(8) == 0 ? 0.0 : std::ldexp(std::floor(random.uniform(0, 0.3) * 0x1.0p20), -20);
  const Vec3 slide{0.5 * random.dyadic(), 0.5 * random.dyadic(), 0.0};
  const Pair exact{Triangle{inPlane(0), inPlane(0), inPlane(0)},
                   Triangle{inPlane(gap) + slide, inPlane(gap) + slide, inPlane(gap) + slide}};
  if (random.below(2) == 0) return exact;
  return rotated(exact, random, random.inCube(2));
}

/// A plane through the origin spanned by two small integer vectors: points s·u + t·v with s, t on
/// the 2^-20 grid are exact in double, so every such triangle lies exactly in that plane.
struct LatticePlane {
  Vec3 u, v;
  Vec3 at(double s, double t) const { return u * s + v * t; }
};

inline LatticePlane latticePlane(PairRandom& random) {
  for (;;) {
    auto component = [&] { return static_cast<double>(random.below(7) - 3); };
    const LatticePlane plane{{component(), component(), component()},
                             {component(), component(), component()}};
    const Vec3 normal = cross(plane.u, plane.v);
    if (lengthSquared(normal) > 0.5 * lengthSquared(plane.u) * lengthSquared(plane.v))
      return plane;  // not too oblique, so the map (s, t) ↦ point keeps shapes recognisable
  }
}

inline double onGrid(double x) {
  return std::ldexp(std::nearbyint(std::ldexp(x, 20)), -20);
}

inline Pair coplanarPair(PairRandom& random, bool overlapping) {
  const LatticePlane plane = latticePlane(random);
  struct Param {
    double s, t;
  };
  const std::array<Param, 3> a{Param{random.dyadic(), random.dyadic()},
                               Param{random.dyadic(), random.dyadic()},
                               Param{random.dyadic(), random.dyadic()}};
  std::array<Param, 3> b{};
  const int variant = random.below(8);
  if (overlapping && variant == 0) {
    b = {a[1], a[0], Param{onGrid(random.uniform(-1, 1)), onGrid(random.uniform(-1, 1))}};
  } else if (overlapping) {
    // B around a point X inside A, its vertices in three directions 120° ± 25° apart, so X is
    // inside B too.
    const double wa = random.uniform(0.15, 0.7), wb = random.uniform(0.15, 0.85 - wa);
    const Param x{a[0].s + wa * (a[1].s - a[0].s) + wb * (a[2].s - a[0].s),
                  a[0].t + wa * (a[1].t - a[0].t) + wb * (a[2].t - a[0].t)};
    const double start = random.uniform(0, 6.283185307179586);
    for (int i = 0; i < 3; ++i) {
      const double angle = start + 2.0943951023931957 * i + random.uniform(-0.44, 0.44);
      const double radius = random.uniform(0.1, 1.0);
      b[i] = {onGrid(x.s + radius * std::cos(angle)), onGrid(x.t + radius * std::sin(angle))};
    }
  } else {
    // Separated by a line of the plane: B beyond A along direction w, by a gap of 0.001–0.3.
    const double angle = random.uniform(0, 6.283185307179586);
    const double ws = std::cos(angle), wt = std::sin(angle);
    auto along = [&](const Param& p) { return p.s * ws + p.t * wt; };
    double top = std::max({along(a[0]), along(a[1]), along(a[2])});
    std::array<Param, 3> raw{Param{random.uniform(-1, 1), random.uniform(-1, 1)},
                             Param{random.uniform(-1, 1), random.uniform(-1, 1)},
                             Param{random.uniform(-1, 1), random.uniform(-1, 1)}};
    const double bottom = std::min({along(raw[0]), along(raw[1]), along(raw[2])});
    const double lift = top - bottom + random.uniform(0.001, 0.3);
    for (int i = 0; i < 3; ++i)
      b[i] = {onGrid(raw[i].s + lift * ws), onGrid(raw[i].t + lift * wt)};
  }
  const Pair exact{
      Triangle{plane.at(a[0].s, a[0].t), plane.at(a[1].s, a[1].t), plane.at(a[2].s, a[2].t)},
      Triangle{plane.at(b[0].s, b[0].t), plane.at(b[1].s, b[1].t), plane.at(b[2].s, b[2].t)}};
  if (random.below(3) != 0) return exact;
  return rotated(exact, random, random.inCube(5));  // nearly coplanar after rounding
}

inline Pair parallelEdgesPair(PairRandom& random) {
  const Triangle first{random.dyadicInCube(), random.dyadicInCube(), random.dyadicInCube()};
  const std::array<Vec3, 3> v{first.a, first.b, first.c};
  const int i = random.below(3);
  const Vec3 p0 = v[i], p1 = v[(i + 1) % 3];
  Vec3 shift;
  switch (random.below(4)) {
    case 0: {  // collinear, sliding along the edge by a short dyadic multiple: overlapping
      const double k = static_cast<double>(random.below(13) - 6) * 0.25;
      shift = (p1 - p0) * k;
      break;
    }
    case 1:  // parallel, close
      shift = Vec3{random.dyadic(), random.dyadic(), random.dyadic()} * 0.125;
      break;
    default:
      shift = random.dyadicInCube();
      break;
  }
  const Vec3 q0 = p0 + shift, q1 = p1 + shift;
  const Vec3 r = random.dyadicInCube() + shift;
  if (random.below(2) == 0) return {first, Triangle{q0, q1, r}};
  return {first, Triangle{q1, r, q0}};  // the same edge, run the other way
}

inline Pair edgeThroughFacePair(PairRandom& random) {
  const Triangle first = triangleAround(random, {}, 0.5);
  const double wa = random.uniform(0.05, 0.9), wb = random.uniform(0.05, 0.95 - wa);
  const Vec3 x = first.a + (first.b - first.a) * wa + (first.c - first.a) * wb;
  const Vec3 n = normalized(first.areaVector());
  const Vec3 d = normalized(n + random.inCube(0.9));
  const Vec3 top = x + d * random.uniform(0.05, 1.0);
  const Vec3 bottom = random.below(10) == 0 ? x : x - d * random.uniform(0.05, 1.0);  // T or X
  const Vec3 third = x + random.unitVector() * random.uniform(0.1, 1.0);
  return {first, Triangle{top, bottom, third}};
}

inline Pair touchingAtVertexPair(PairRandom& random) {
  const Triangle first{random.dyadicInCube(), random.dyadicInCube(), random.dyadicInCube()};
  Vec3 touch;
  switch (random.below(3)) {
    case 0:
      touch = first.a;
      break;
    case 1:
      touch = (first.b + first.c) * 0.5;
      break;  // an edge's midpoint: exact on the grid
    default:
      touch = first.a * 0.25 + first.b * 0.25 + first.c * 0.5;
      break;  // a face point
  }
  const Vec3 n = normalized(first.areaVector());
  const double side = random.below(2) == 0 ? 1.0 : -1.0;
  auto away = [&] {
    if (random.below(4) == 0) return touch + random.inCube(1);  // may cross A
    return touch + n * (side * random.uniform(0.1, 1.0)) + random.inCube(0.7);
  };
  const Vec3 b = away(), c = away();
  return {first, Triangle{b, touch, c}};
}

inline Triangle sliver(PairRandom& random) {
  const Vec3 a = random.inCube(0.5), b = random.inCube(0.5);
  const double t = random.uniform(-0.2, 1.2);
  const double height = std::pow(10.0, -random.uniform(4, 10)) * distance(a, b);
  const Vec3 perpendicular = normalized(cross(b - a, random.unitVector()));
  return {a, b, a + (b - a) * t + perpendicular * height};
}

inline Pair sliverPair(PairRandom& random) {
  const Triangle first = sliver(random);
  const Triangle second = random.below(2) == 0 ? sliver(random) : triangleAround(random, {}, 0.5);
  if (random.below(4) == 0) return {first, translated(second, random.inCube(0.3))};  // may cross
  const double size = pairSize(first, second);
  return separate(first, second, random.unitVector(), random.uniform(0, 0.2) * size, 0.3 * size,
                  random);
}

/// An exactly degenerate triangle on the dyadic grid: collinear vertices (in any order), a
/// repeated vertex, or (when `allowPoint`) a single point.
inline Triangle zeroArea(PairRandom& random, bool allowPoint) {
  const Vec3 a = random.dyadicInCube(), d = random.dyadicInCube() * 0.5;
  switch (random.below(allowPoint ? 5 : 4)) {
    case 0:
      return {a, a + d, a + d * 2.0};
    case 1:
      return {a + d, a - d * 0.5, a};
    case 2:
      return {a, a, a + d};
    case 3:
      return {a + d, a, a + d};
    default:
      return {a, a, a};
  }
}

inline Pair zeroAreaPair(PairRandom& random) {
  const Triangle first = zeroArea(random, false);
  const int variant = random.below(3);
  const Triangle second =
      variant == 0 ? zeroArea(random, true)
                   : Triangle{random.dyadicInCube(), random.dyadicInCube(), random.dyadicInCube()};
  if (variant == 2) return {first, second};  // overlapping boxes: crossings happen
  const double size = pairSize(first, second);
  auto pair = separate(first, second, random.unitVector(), random.uniform(0, 0.2) * size,
                       0.3 * size, random);
  if (random.below(2) == 0) std::swap(pair.first, pair.second);
  return pair;
}

}  // namespace detail

/// `count` pairs of the family, the same for the same seed on every platform.
inline std::vector<std::pair<Triangle, Triangle>> makePairs(PairFamily family, std::size_t count,
                                                            std::uint64_t seed) {
  // Mix the family into the seed so that families drawn with one seed are independent.
  PairRandom random(seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(family) + 1);
  std::vector<std::pair<Triangle, Triangle>> pairs;
  pairs.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    switch (family) {
      case PairFamily::Random:
        pairs.push_back(detail::randomPair(random));
        break;
      case PairFamily::NearContact:
        pairs.push_back(detail::nearContactPair(random));
        break;
      case PairFamily::Far:
        pairs.push_back(detail::farPair(random));
        break;
      case PairFamily::ParallelFaces:
        pairs.push_back(detail::parallelFacesPair(random));
        break;
      case PairFamily::CoplanarOverlapping:
        pairs.push_back(detail::coplanarPair(random, true));
        break;
      case PairFamily::CoplanarDisjoint:
        pairs.push_back(detail::coplanarPair(random, false));
        break;
      case PairFamily::ParallelEdges:
        pairs.push_back(detail::parallelEdgesPair(random));
        break;
      case PairFamily::EdgeThroughFace:
        pairs.push_back(detail::edgeThroughFacePair(random));
        break;
      case PairFamily::TouchingAtVertex:
        pairs.push_back(detail::touchingAtVertexPair(random));
        break;
      case PairFamily::Sliver:
        pairs.push_back(detail::sliverPair(random));
        break;
      case PairFamily::ZeroArea:
        pairs.push_back(detail::zeroAreaPair(random));
        break;
      case PairFamily::Tiny: {
        const auto pair =
            random.below(2) == 0 ? detail::nearContactPair(random) : detail::randomPair(random);
        pairs.push_back({detail::scaled(pair.first, 1e-6), detail::scaled(pair.second, 1e-6)});
        break;
      }
      case PairFamily::HugeOffset: {
        const auto pair =
            random.below(2) == 0 ? detail::nearContactPair(random) : detail::randomPair(random);
        const Vec3 offset{random.below(2) == 0 ? 1e6 : -1e6, random.uniform(-2e6, 2e6),
                          random.uniform(1e6, 3e6)};
        pairs.push_back(
            {detail::translated(pair.first, offset), detail::translated(pair.second, offset)});
        break;
      }
    }
  }
  return pairs;
}

}  // namespace delta::test
