// The batched triangle kernels, one lane (W = 1): the scalar reference every ISA is tested
// against. Baseline flags.
#include "delta/kernels/detail/batch_kernels.h"

namespace delta::detail {

const BatchKernels& scalarBatchKernels() noexcept {
  static constexpr BatchKernels kernels = makeBatchKernels<1>();
  return kernels;
}

}  // namespace delta::detail
