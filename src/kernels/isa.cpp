#include "delta/kernels/isa.h"

#include <cstdlib>

#include "delta/kernels/detail/batch_dispatch.h"
#include "delta/kernels/detail/batch_views.h"

namespace delta::kernels {
namespace {

constexpr Isa kAll[] = {Isa::Scalar, Isa::Sse2, Isa::Avx2, Isa::Avx512};

bool cpuRuns(Isa isa) noexcept {
#if defined(DELTA_X86_ISAS)
  __builtin_cpu_init();  // harmless when libgcc has done it already
  switch (isa) {
    case Isa::Scalar:
    case Isa::Sse2:
      return true;  // the x86-64 baseline
    case Isa::Avx2:
      return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    case Isa::Avx512:
      // GCC's check includes the OS's support for the register state (XGETBV).
      return __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx2") &&
             __builtin_cpu_supports("fma");
  }
  return false;
#else
  return isa == Isa::Scalar;  // only the scalar table is built off x86-64
#endif
}

Isa chooseDefault() noexcept {
  Isa best = Isa::Scalar;
  for (Isa isa : kAll)
    if (cpuRuns(isa)) best = isa;
  if (const char* requested = std::getenv("DELTA_ISA")) {
    if (const auto isa = parseIsa(requested); isa && cpuRuns(*isa)) best = *isa;
  }
  return best;
}

}  // namespace

const char* name(Isa isa) noexcept {
  switch (isa) {
    case Isa::Scalar:
      return "scalar";
    case Isa::Sse2:
      return "sse2";
    case Isa::Avx2:
      return "avx2";
    case Isa::Avx512:
      return "avx512";
  }
  return "?";
}

std::optional<Isa> parseIsa(std::string_view text) noexcept {
  for (Isa isa : kAll)
    if (text == name(isa)) return isa;
  return std::nullopt;
}

int laneCount(Isa isa) noexcept {
  switch (isa) {
    case Isa::Scalar:
      return 1;
    case Isa::Sse2:
      return 2;
    case Isa::Avx2:
      return 4;
    case Isa::Avx512:
      return 8;
  }
  return 1;
}

bool isSupported(Isa isa) noexcept {
  return cpuRuns(isa);
}

std::vector<Isa> supportedIsas() {
  std::vector<Isa> isas;
  for (Isa isa : kAll)
    if (cpuRuns(isa)) isas.push_back(isa);
  return isas;
}

Isa defaultIsa() noexcept {
  static const Isa chosen = chooseDefault();
  return chosen;
}

Isa supportedIsaAtMost(Isa requested) noexcept {
  Isa result = Isa::Scalar;
  for (Isa isa : kAll)
    if (isa <= requested && cpuRuns(isa)) result = isa;
  return result;
}

}  // namespace delta::kernels

namespace delta::detail {

const BatchKernels& batchKernels(kernels::Isa isa) noexcept {
  switch (kernels::supportedIsaAtMost(isa)) {
#if defined(DELTA_X86_ISAS)
    case kernels::Isa::Sse2:
      return sse2BatchKernels();
    case kernels::Isa::Avx2:
      return avx2BatchKernels();
    case kernels::Isa::Avx512:
      return avx512BatchKernels();
#endif
    default:
      return scalarBatchKernels();
  }
}

}  // namespace delta::detail
