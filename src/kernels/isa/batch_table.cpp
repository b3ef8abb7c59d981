// The batched triangle kernels of one instruction set: this file is compiled once per ISA
// (src/CMakeLists.txt, delta_isa), with that ISA's flags and DELTA_ISA (its name, the namespace
// of its table) and DELTA_ISA_LANES (W, the kernels' lanes: 1 for the scalar reference; 4 on
// SSE2 and NEON, two interleaved registers of 2 doubles; 8 on AVX2, two of 4; 16 on AVX-512, two
// of 8; 8 on SVE). The kernels are templates over W with everything inlined into the table's
// entries ([[gnu::flatten]]), so each ISA's code is its own (W differs between the ISAs of a
// build).
#include "delta/kernels/detail/batch_kernels.h"

namespace delta::detail::DELTA_ISA {

const BatchKernels& batchKernels() noexcept {
  static constexpr BatchKernels kernels = makeBatchKernels<DELTA_ISA_LANES>();
  return kernels;
}

}  // namespace delta::detail::DELTA_ISA
