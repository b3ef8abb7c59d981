#pragma once

// SIMD lanes for the batched triangle kernels. Every kernel is a template over its lane count W
// and reads like scalar code on `Real<W>` (W doubles, one triangle pair per lane) and `Mask<W>`
// (W lane masks from comparisons); `select` blends, so the kernels are branch-free.
//
// Real<W> is a Pack of U registers of H doubles each (W = H·U), written with GCC's vector
// extensions: H = 1 is plain scalar code, H = 2 SSE2, 4 AVX2, 8 AVX-512. U > 1 interleaves U
// independent pairs of registers: one Newton iteration is a long chain of dependent operations
// (ending in a division), and interleaving U chains keeps the pipelines busy instead of waiting
// on each result. The shapes (Shape<W> below) are: W = 1 (scalar reference), 4 (SSE2 or NEON,
// 2 × 2), 8 (AVX2 or SVE, 4 × 2), 16 (AVX-512, 8 × 2).
//
// Each W is instantiated in exactly one object (src/kernels/isa/batch_table.cpp, built once per
// ISA), compiled with that instruction set's flags, so no instantiation compiled for a wider ISA
// can leak into another (ISA.NoSharedCodeBetweenInstructionSets checks it).
// Nothing here calls a non-template inline function for the same reason.

#include <cstddef>
#include <cstdint>
#include <utility>

namespace delta::detail {

/// The register shape of W lanes: U registers of H doubles.
template <int W>
struct Shape;
template <>
struct Shape<1> {
  static constexpr int H = 1, U = 1;
};
template <>
struct Shape<4> {
  static constexpr int H = 2, U = 2;
};
template <>
struct Shape<8> {
  static constexpr int H = 4, U = 2;
};
template <>
struct Shape<16> {
  static constexpr int H = 8, U = 2;
};

/// One register of H doubles, and its masks (all bits set for true).
template <int H>
struct Register {
  static_assert(H == 1 || H == 2 || H == 4 || H == 8, "registers of 1, 2, 4 or 8 doubles");
  typedef double Real __attribute__((vector_size(H * sizeof(double))));
  typedef std::int64_t Mask __attribute__((vector_size(H * sizeof(double))));
};

template <int H, int U, class Element>
struct PackBase {
  Element v[U];
};

template <int H, int U>
struct MaskPack : PackBase<H, U, typename Register<H>::Mask> {
  bool lane(int i) const noexcept { return this->v[i / H][i % H] != 0; }
  /// Stores the H·U lanes as bytes 0 or 1 (through memory: lane extraction is slower).
  void storeBytes(std::uint8_t* out) const noexcept {
    std::int64_t words[H * U];
    __builtin_memcpy(words, this->v, sizeof words);
    for (int i = 0; i < H * U; ++i)
      out[i] = static_cast<std::uint8_t>(words[i] & 1);
  }
};

template <int H, int U>
struct Pack : PackBase<H, U, typename Register<H>::Real> {
  double lane(int i) const noexcept { return this->v[i / H][i % H]; }
  void setLane(int i, double x) noexcept { this->v[i / H][i % H] = x; }
};

template <int H, int U, class F>
inline Pack<H, U> apply(const Pack<H, U>& a, const Pack<H, U>& b, F f) noexcept {
  Pack<H, U> r;
  for (int k = 0; k < U; ++k)
    r.v[k] = f(a.v[k], b.v[k]);
  return r;
}

/// A register with lane 0 of `first` in every lane (GCC ≥ 12 and Clang both have the shuffle).
template <int H, std::size_t... Lane>
inline typename Register<H>::Real splatFirst(const typename Register<H>::Real& first,
                                             std::index_sequence<Lane...>) noexcept {
  if constexpr (H == 1)
    return first;
  else
    return __builtin_shufflevector(first, first, (static_cast<void>(Lane), 0)...);
}

/// x in every lane: a shuffle of lane 0 (one vbroadcastsd). Filled lane by lane, GCC built
/// AVX-512 broadcasts of a variable through the stack, 16 bytes at a time, and every use then
/// stalled on the wide load of narrow stores.
template <int H, int U>
inline Pack<H, U> broadcast(double x) noexcept {
  const typename Register<H>::Real first = {x};
  Pack<H, U> r;
  for (int k = 0; k < U; ++k)
    r.v[k] = splatFirst<H>(first, std::make_index_sequence<H>{});
  return r;
}

// Arithmetic, lane-wise, with doubles broadcast.
template <int H, int U>
inline Pack<H, U> operator+(const Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return apply(a, b, [](auto x, auto y) { return x + y; });
}
template <int H, int U>
inline Pack<H, U> operator-(const Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return apply(a, b, [](auto x, auto y) { return x - y; });
}
template <int H, int U>
inline Pack<H, U> operator*(const Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return apply(a, b, [](auto x, auto y) { return x * y; });
}
template <int H, int U>
inline Pack<H, U> operator/(const Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return apply(a, b, [](auto x, auto y) { return x / y; });
}
template <int H, int U>
inline Pack<H, U> operator-(const Pack<H, U>& a) noexcept {
  Pack<H, U> r;
  for (int k = 0; k < U; ++k)
    r.v[k] = -a.v[k];
  return r;
}
template <int H, int U>
inline Pack<H, U> operator+(const Pack<H, U>& a, double b) noexcept {
  return a + broadcast<H, U>(b);
}
template <int H, int U>
inline Pack<H, U> operator+(double a, const Pack<H, U>& b) noexcept {
  return broadcast<H, U>(a) + b;
}
template <int H, int U>
inline Pack<H, U> operator-(const Pack<H, U>& a, double b) noexcept {
  return a - broadcast<H, U>(b);
}
template <int H, int U>
inline Pack<H, U> operator-(double a, const Pack<H, U>& b) noexcept {
  return broadcast<H, U>(a) - b;
}
template <int H, int U>
inline Pack<H, U> operator*(double a, const Pack<H, U>& b) noexcept {
  return broadcast<H, U>(a) * b;
}
template <int H, int U>
inline Pack<H, U> operator/(double a, const Pack<H, U>& b) noexcept {
  return broadcast<H, U>(a) / b;
}
template <int H, int U>
inline Pack<H, U>& operator+=(Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return a = a + b;
}
template <int H, int U>
inline Pack<H, U>& operator-=(Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return a = a - b;
}

// Comparisons give masks.
template <int H, int U, class F>
inline MaskPack<H, U> compare(const Pack<H, U>& a, const Pack<H, U>& b, F f) noexcept {
  MaskPack<H, U> r;
  for (int k = 0; k < U; ++k)
    r.v[k] = f(a.v[k], b.v[k]);
  return r;
}
template <int H, int U>
inline MaskPack<H, U> operator<(const Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return compare(a, b, [](auto x, auto y) { return x < y; });
}
template <int H, int U>
inline MaskPack<H, U> operator<=(const Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return compare(a, b, [](auto x, auto y) { return x <= y; });
}
template <int H, int U>
inline MaskPack<H, U> operator>(const Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return b < a;
}
template <int H, int U>
inline MaskPack<H, U> operator>=(const Pack<H, U>& a, const Pack<H, U>& b) noexcept {
  return b <= a;
}
template <int H, int U>
inline MaskPack<H, U> operator<(const Pack<H, U>& a, double b) noexcept {
  return a < broadcast<H, U>(b);
}
template <int H, int U>
inline MaskPack<H, U> operator<=(const Pack<H, U>& a, double b) noexcept {
  return a <= broadcast<H, U>(b);
}
template <int H, int U>
inline MaskPack<H, U> operator>(const Pack<H, U>& a, double b) noexcept {
  return broadcast<H, U>(b) < a;
}
template <int H, int U>
inline MaskPack<H, U> operator>=(const Pack<H, U>& a, double b) noexcept {
  return broadcast<H, U>(b) <= a;
}

// Mask logic.
template <int H, int U, class F>
inline MaskPack<H, U> combine(const MaskPack<H, U>& a, const MaskPack<H, U>& b, F f) noexcept {
  MaskPack<H, U> r;
  for (int k = 0; k < U; ++k)
    r.v[k] = f(a.v[k], b.v[k]);
  return r;
}
template <int H, int U>
inline MaskPack<H, U> operator&(const MaskPack<H, U>& a, const MaskPack<H, U>& b) noexcept {
  return combine(a, b, [](auto x, auto y) { return x & y; });
}
template <int H, int U>
inline MaskPack<H, U> operator|(const MaskPack<H, U>& a, const MaskPack<H, U>& b) noexcept {
  return combine(a, b, [](auto x, auto y) { return x | y; });
}
/// Equal masks (both true or both false).
template <int H, int U>
inline MaskPack<H, U> operator==(const MaskPack<H, U>& a, const MaskPack<H, U>& b) noexcept {
  return combine(a, b, [](auto x, auto y) { return ~(x ^ y); });
}
template <int H, int U>
inline MaskPack<H, U> operator~(const MaskPack<H, U>& a) noexcept {
  MaskPack<H, U> r;
  for (int k = 0; k < U; ++k)
    r.v[k] = ~a.v[k];
  return r;
}
template <int H, int U>
inline MaskPack<H, U>& operator|=(MaskPack<H, U>& a, const MaskPack<H, U>& b) noexcept {
  return a = a | b;
}

template <int W>
using Real = Pack<Shape<W>::H, Shape<W>::U>;
template <int W>
using Mask = MaskPack<Shape<W>::H, Shape<W>::U>;

template <int W>
inline Real<W> splat(double x) noexcept {
  return broadcast<Shape<W>::H, Shape<W>::U>(x);
}

template <int W>
inline Mask<W> noLanes() noexcept {
  Mask<W> r;
  for (int k = 0; k < Shape<W>::U; ++k)
    r.v[k] = r.v[k] ^ r.v[k];
  return r;
}

/// W doubles from `p` (any alignment).
template <int W>
inline Real<W> load(const double* p) noexcept {
  Real<W> r;
  __builtin_memcpy(&r.v[0], p, sizeof r.v);
  return r;
}

template <int W>
inline void store(double* p, const Real<W>& r) noexcept {
  __builtin_memcpy(p, &r.v[0], sizeof r.v);
}

/// a where m, else b.
template <int W>
inline Real<W> select(const Mask<W>& m, const Real<W>& a, const Real<W>& b) noexcept {
  Real<W> r;
  for (int k = 0; k < Shape<W>::U; ++k)
    r.v[k] = m.v[k] ? a.v[k] : b.v[k];
  return r;
}

template <int W>
inline Real<W> min(const Real<W>& a, const Real<W>& b) noexcept {
  return select<W>(a < b, a, b);
}

template <int W>
inline Real<W> max(const Real<W>& a, const Real<W>& b) noexcept {
  return select<W>(a > b, a, b);
}

template <int W>
inline Real<W> clamp01(const Real<W>& a) noexcept {
  return min<W>(max<W>(a, splat<W>(0.0)), splat<W>(1.0));
}

template <int W>
inline Real<W> abs(const Real<W>& a) noexcept {
  return select<W>(a < 0.0, -a, a);
}

/// Lane-wise square root (vsqrtpd: the ISA units build with -fno-math-errno).
template <int W>
inline Real<W> sqrt(const Real<W>& a) noexcept {
  Real<W> r;
  for (int i = 0; i < W; ++i)
    r.setLane(i, __builtin_sqrt(a.lane(i)));
  return r;
}

/// Whether every lane of `m` is set.
template <int W>
inline bool allLanes(const Mask<W>& m) noexcept {
  bool all = true;
  for (int i = 0; i < W; ++i)
    all = all && m.lane(i);
  return all;
}

/// Whether any lane of `m` is set.
template <int W>
inline bool anyLane(const Mask<W>& m) noexcept {
  bool any = false;
  for (int i = 0; i < W; ++i)
    any = any || m.lane(i);
  return any;
}

/// A point or vector per lane.
template <int W>
struct Vec3Lanes {
  Real<W> x, y, z;
};

template <int W>
inline Vec3Lanes<W> operator+(const Vec3Lanes<W>& a, const Vec3Lanes<W>& b) noexcept {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
template <int W>
inline Vec3Lanes<W> operator-(const Vec3Lanes<W>& a, const Vec3Lanes<W>& b) noexcept {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
template <int W>
inline Vec3Lanes<W> operator*(const Real<W>& s, const Vec3Lanes<W>& a) noexcept {
  return {s * a.x, s * a.y, s * a.z};
}
template <int W>
inline Real<W> dot(const Vec3Lanes<W>& a, const Vec3Lanes<W>& b) noexcept {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
template <int W>
inline Vec3Lanes<W> cross(const Vec3Lanes<W>& a, const Vec3Lanes<W>& b) noexcept {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <int W>
inline Vec3Lanes<W> select(const Mask<W>& m, const Vec3Lanes<W>& a,
                           const Vec3Lanes<W>& b) noexcept {
  return {select<W>(m, a.x, b.x), select<W>(m, a.y, b.y), select<W>(m, a.z, b.z)};
}

}  // namespace delta::detail
