#include "delta/kernels/isa.h"

#include <cstdlib>

#include "delta/kernels/detail/batch_dispatch.h"
#include "delta/kernels/detail/batch_views.h"

#include "isa_list.h"  // generated: DELTA_ISAS, DELTA_ISA_RUNS_<name> (src/CMakeLists.txt)

#if defined(__aarch64__)
#include <sys/auxv.h>
#include <sys/prctl.h>
#endif

// Each ISA's table, in its own translation unit (kernels/isa/batch_table.cpp).
#define DELTA_DECLARE_TABLE(enumerator, name, lanes) \
  namespace delta::detail::name {                    \
  const BatchKernels& batchKernels() noexcept;       \
  }
DELTA_ISAS(DELTA_DECLARE_TABLE)
#undef DELTA_DECLARE_TABLE

namespace delta::kernels {
namespace {

constexpr Isa kAll[] = {Isa::Scalar, Isa::Sse2, Isa::Avx2, Isa::Avx512, Isa::Neon, Isa::Sve};

/// The architecture an ISA belongs to (Scalar to every one).
enum class Family { Any, X86, Arm };

constexpr Family familyOf(Isa isa) noexcept {
  switch (isa) {
    case Isa::Scalar:
      return Family::Any;
    case Isa::Sse2:
    case Isa::Avx2:
    case Isa::Avx512:
      return Family::X86;
    case Isa::Neon:
    case Isa::Sve:
      return Family::Arm;
  }
  return Family::Any;
}

/// Whether this build has `isa` and this CPU (and OS) runs it: the checks of each ISA's features,
/// as src/CMakeLists.txt names them (GCC's x86 check includes the OS's support for the register
/// state, XGETBV).
bool cpuRuns(Isa isa) noexcept {
#if defined(__x86_64__)
  __builtin_cpu_init();  // harmless when libgcc has done it already
#endif
  switch (isa) {
#define DELTA_RUNS(enumerator, name, lanes) \
  case Isa::enumerator:                     \
    return DELTA_ISA_RUNS_##name;
    DELTA_ISAS(DELTA_RUNS)
#undef DELTA_RUNS
    default:
      return false;  // not in this build
  }
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
    case Isa::Neon:
      return "neon";
    case Isa::Sve:
      return "sve";
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
    case Isa::Neon:
      return 2;
    case Isa::Avx2:
      return 4;
    case Isa::Avx512:
      return 8;
    case Isa::Sve:
#if defined(__aarch64__) && defined(PR_SVE_GET_VL)
      if (cpuRuns(Isa::Sve)) {
        const int vl = prctl(PR_SVE_GET_VL);  // bytes, with flags above PR_SVE_VL_LEN_MASK
        if (vl > 0) return (vl & PR_SVE_VL_LEN_MASK) / 8;
      }
#endif
      return 2;
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
    if (familyOf(isa) == familyOf(requested) && isa <= requested && cpuRuns(isa)) result = isa;
  return result;
}

}  // namespace delta::kernels

namespace delta::detail {

const BatchKernels& batchKernels(kernels::Isa isa) noexcept {
  switch (kernels::supportedIsaAtMost(isa)) {
#define DELTA_TABLE(enumerator, name, lanes) \
  case kernels::Isa::enumerator:             \
    return name::batchKernels();
    DELTA_ISAS(DELTA_TABLE)
#undef DELTA_TABLE
    default:
      return scalar::batchKernels();
  }
}

}  // namespace delta::detail
