// The batched triangle kernels on AVX2 with FMA (built with -mavx2 -mfma): W = 8 lanes, two
// interleaved registers of 4 doubles.
#include "delta/kernels/detail/batch_kernels.h"

namespace delta::detail {

const BatchKernels& avx2BatchKernels() noexcept {
  static constexpr BatchKernels kernels = makeBatchKernels<8>();
  return kernels;
}

}  // namespace delta::detail
