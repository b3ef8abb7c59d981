#include "delta/kernels/hybrid.h"

#include <cstdint>
#include <cstring>

#include "delta/kernels/detail/batch_dispatch.h"
#include "delta/kernels/detail/hybrid_candidates.h"
#include "delta/kernels/triangle_triangle.h"

#include "detail/exact_store.h"

namespace delta::kernels {

static_assert(kHybridIterations == detail::HybridSchedule::kIterations);

namespace {

/// The narrowest table that computes as `kernels` does, bit for bit: on x86-64, AVX-512's and
/// AVX2's fuse a·b + c into one rounding, SSE2's and the scalar's round twice, and within each
/// pair the lanes compute alike. A lone pair on one scalar lane costs 0.4 µs, a whole register
/// about 0.8 µs: the scalar table where it agrees, AVX2's eight lanes for AVX-512's sixteen. On
/// AArch64 every table may fuse, each as its compiler saw fit: the table itself.
const detail::BatchKernels& loneKernels(const detail::BatchKernels& kernels) noexcept {
#if defined(__x86_64__)
  static const detail::BatchKernels* const avx512 =
      isSupported(Isa::Avx512) ? &detail::batchKernels(Isa::Avx512) : nullptr;
  static const detail::BatchKernels* const avx2 =
      isSupported(Isa::Avx2) ? &detail::batchKernels(Isa::Avx2) : nullptr;
  if (&kernels == avx512) return *avx2;
  if (&kernels == avx2) return kernels;
  return detail::batchKernels(Isa::Scalar);
#else
  return kernels;
#endif
}

/// Pairs gathered from the first stage's failures, in small SoA blocks on the stack, for the
/// second (exhaustive) stage; results scattered back. No heap allocation.
class Recheck {
 public:
  static constexpr std::size_t kCapacity = 64;  // a multiple of every ISA's register width

  Recheck() noexcept {
    for (int s = 0; s < 9; ++s) {
      firstView_.streams[s] = first_[s];
      secondView_.streams[s] = second_[s];
    }
    firstView_.paddedSize = secondView_.paddedSize = kCapacity;
    out_.distanceSquared = results_[0];
    for (int axis = 0; axis < 3; ++axis) {
      out_.p[axis] = results_[1 + axis];
      out_.q[axis] = results_[4 + axis];
    }
    out_.errorBound = results_[7];
    out_.newtonStep = results_[8];
    out_.intersect = intersect_;
    out_.converged = converged_;
  }

  bool full() const noexcept { return count_ == kCapacity; }
  bool empty() const noexcept { return count_ == 0; }

  void add(std::size_t index, const Triangle& a, const Triangle& b) noexcept {
    put(first_, a);
    put(second_, b);
    index_[count_++] = index;
  }

  /// Runs the second stage on the gathered pairs and writes the pairs it certifies into `out`;
  /// calls `fallback(i)` for each pair i it cannot certify.
  template <class Fallback>
  void run(const detail::BatchKernels& kernels, const detail::PairStreams& out,
           const Fallback& fallback) noexcept {
    // Lanes beyond count_, up to a whole register of the widest ISA (16), repeat the first pair:
    // finite input, never stored.
    const std::size_t padded = (count_ + 15) / 16 * 16;
    for (std::size_t i = count_; i < padded; ++i)
      for (int s = 0; s < 9; ++s) {
        first_[s][i] = first_[s][0];
        second_[s][i] = second_[s][0];
      }
    // A lone pair (small one-against-range batches often leave exactly one) runs on the
    // narrowest table of the same arithmetic (loneKernels), so that its bits do not depend on
    // the batch it came in.
    const detail::BatchKernels& stage = count_ == 1 ? loneKernels(kernels) : kernels;
    stage.exhaustiveBlocks(firstView_, secondView_, count_, out_);
    for (std::size_t k = 0; k < count_; ++k) {
      const std::size_t i = index_[k];
      if (converged_[k] == 0) {
        fallback(i);
        continue;
      }
      out.distanceSquared[i] = results_[0][k];
      for (int axis = 0; axis < 3; ++axis) {
        out.p[axis][i] = results_[1 + axis][k];
        out.q[axis][i] = results_[4 + axis][k];
      }
      out.errorBound[i] = 0.0;
      out.intersect[i] = intersect_[k];
      out.converged[i] = 1;
    }
    count_ = 0;
  }

 private:
  void put(double (&streams)[9][kCapacity], const Triangle& t) noexcept {
    const Vec3* vertices[3] = {&t.a, &t.b, &t.c};
    for (int v = 0; v < 3; ++v)
      for (int axis = 0; axis < 3; ++axis)
        streams[3 * v + axis][count_] = (*vertices[v])[static_cast<std::size_t>(axis)];
  }

  alignas(64) double first_[9][kCapacity];
  alignas(64) double second_[9][kCapacity];
  alignas(64) double results_[9][kCapacity];
  std::uint8_t intersect_[kCapacity];
  std::uint8_t converged_[kCapacity];
  std::size_t index_[kCapacity];
  std::size_t count_ = 0;
  detail::SoaView firstView_{}, secondView_{};
  detail::PairStreams out_{};
};

/// The hybrid's second and third stages after its first: pairs not certified go through the
/// exhaustive SIMD stage, and those it cannot certify either through the scalar brute force.
/// `pairOf(i)` gives the two triangles of pair i.
template <class PairOf>
BatchStatistics finish(const detail::BatchKernels& kernels, const detail::PairStreams& out,
                       std::size_t count, const PairOf& pairOf) noexcept {
  BatchStatistics statistics;
  statistics.pairs = count;
  const auto bruteForce = [&](std::size_t i) {
    const auto [first, second] = pairOf(i);
    detail::storeExact(out, i, triangleDistanceBruteForce(first, second));
    ++statistics.fallbacks;
  };
  Recheck recheck;
  const std::uint8_t* converged = out.converged;
  constexpr std::uint64_t kAllConverged = 0x0101010101010101ull;
  for (std::size_t group = 0; group < count; group += 8) {
    const std::size_t end = group + 8 < count ? group + 8 : count;
    if (end - group == 8) {  // skip eight certified pairs at a time (the common case)
      std::uint64_t flags;
      std::memcpy(&flags, converged + group, sizeof flags);
      if (flags == kAllConverged) continue;
    }
    for (std::size_t i = group; i < end; ++i) {
      if (converged[i] != 0) continue;
      const auto [first, second] = pairOf(i);
      recheck.add(i, first, second);
      ++statistics.rechecked;
      if (recheck.full()) recheck.run(kernels, out, bruteForce);
    }
  }
  if (!recheck.empty()) recheck.run(kernels, out, bruteForce);
  return statistics;
}

struct TrianglePair {
  Triangle first, second;
};

}  // namespace

BatchStatistics hybridDistances(const TriangleSoA& first, const TriangleSoA& second,
                                PairResults& results, Isa isa) noexcept {
  const detail::PairStreams out = results.prepare(detail::blockPairCount(first, second));
  const detail::BatchKernels& kernels = detail::batchKernels(isa);
  kernels.hybridBlocks(detail::soaView(first), detail::soaView(second), results.size(), out);
  return finish(kernels, out, results.size(), [&](std::size_t i) {
    return TrianglePair{first.triangle(i), second.triangle(i)};
  });
}

BatchStatistics hybridDistances(const Triangle& one, const TriangleSoA& block, std::size_t begin,
                                std::size_t end, PairResults& results, Isa isa) noexcept {
  const detail::PairStreams out = results.prepare(detail::rangePairCount(block, begin, end));
  const detail::BatchKernels& kernels = detail::batchKernels(isa);
  kernels.hybridOne(detail::coordinates(one), detail::soaView(block), begin, results.size(), out);
  return finish(kernels, out, results.size(), [&](std::size_t i) {
    return TrianglePair{one, block.triangle(begin + i)};
  });
}

}  // namespace delta::kernels
