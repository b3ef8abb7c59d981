#include "delta/kernels/pair_results.h"

#include <algorithm>

namespace delta::kernels {

void PairResults::reserve(std::size_t capacity) {
  if (capacity <= capacity_) return;
  constexpr std::size_t kLine = 64 / sizeof(double);
  const std::size_t stride = (capacity + kLine - 1) / kLine * kLine;
  AlignedDoubles doubles(kCount * stride);
  std::vector<std::uint8_t> flags(2 * capacity);
  for (int s = 0; s < kCount; ++s)
    std::copy_n(doubles_.data() + s * stride_, size_, doubles.data() + s * stride);
  std::copy_n(flags_.data(), size_, flags.data());
  std::copy_n(flags_.data() + capacity_, size_, flags.data() + capacity);
  doubles_ = std::move(doubles);
  flags_ = std::move(flags);
  capacity_ = capacity;
  stride_ = stride;
}

detail::PairStreams PairResults::prepare(std::size_t count) noexcept {
  size_ = std::min(count, capacity_);
  double* base = doubles_.data();
  detail::PairStreams out{};
  out.distanceSquared = base + kDistanceSquared * stride_;
  for (int axis = 0; axis < 3; ++axis) {
    out.p[axis] = base + (kPx + axis) * stride_;
    out.q[axis] = base + (kQx + axis) * stride_;
  }
  out.errorBound = base + kErrorBound * stride_;
  out.newtonStep = base + kNewtonStep * stride_;
  out.intersect = flags_.data();
  out.converged = flags_.data() + capacity_;
  return out;
}

}  // namespace delta::kernels
