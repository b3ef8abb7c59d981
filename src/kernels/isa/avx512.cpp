// The batched triangle kernels on AVX-512 (built with -mavx512f -mavx512dq -mavx512vl -mavx2
// -mfma): W = 16 lanes, two interleaved registers of 8 doubles.
#include "delta/kernels/detail/batch_kernels.h"

namespace delta::detail {

const BatchKernels& avx512BatchKernels() noexcept {
  static constexpr BatchKernels kernels = makeBatchKernels<16>();
  return kernels;
}

}  // namespace delta::detail
