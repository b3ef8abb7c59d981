// The batched triangle kernels on SSE2, the x86-64 baseline that every x86-64 CPU runs: W = 4
// lanes, two interleaved registers of 2 doubles.
#include "delta/kernels/detail/batch_kernels.h"

namespace delta::detail {

const BatchKernels& sse2BatchKernels() noexcept {
  static constexpr BatchKernels kernels = makeBatchKernels<4>();
  return kernels;
}

}  // namespace delta::detail
