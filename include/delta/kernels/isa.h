#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace delta::kernels {

/// The instruction sets Δ's vectorised paths (the batched triangle kernels, the point queries'
/// descent, node bounds and exact lanes) are compiled for, narrowest first within each
/// architecture. `Scalar` (one lane) is the reference the others are tested against. On x86-64:
/// `Sse2` (2 lanes, the baseline), `Avx2` (4 lanes, with FMA) and `Avx512` (8 lanes,
/// AVX-512F/DQ/VL). On AArch64: `Neon` (2 lanes, Advanced SIMD, the baseline) and `Sve` (the
/// Scalable Vector Extension, where the CPU has it). A build has its own architecture's; one
/// binary runs on every CPU of it: the choice is made at run time.
enum class Isa : std::uint8_t { Scalar, Sse2, Avx2, Avx512, Neon, Sve };

/// "scalar", "sse2", "avx2", "avx512", "neon", "sve".
///
/// Threading (this function and the ones below, unless they say otherwise): a pure function;
/// safe from any thread.
const char* name(Isa isa) noexcept;

/// The inverse of name() (exact, lower case); nullopt for anything else.
std::optional<Isa> parseIsa(std::string_view text) noexcept;

/// Doubles per register: 1, 2, 4 or 8; for SVE, this CPU's vector length (2 where it has no
/// SVE: the architecture's least).
int laneCount(Isa isa) noexcept;

/// Whether this build has `isa` compiled in and this CPU (and OS) can run it. Scalar always is.
bool isSupported(Isa isa) noexcept;

/// Every supported ISA, narrowest first (always starts with Scalar). Allocates.
std::vector<Isa> supportedIsas();

/// The ISA the batched kernels (and the point queries' leaf bounds and descent) use when none is
/// named: the widest supported one, chosen once (on the first call). The environment variable
/// DELTA_ISA (one of the names above), read at that moment, lowers it for tests and benchmarks;
/// a name this CPU cannot run, or an unknown one, is ignored.
///
/// Threading: safe to call from any thread (a function-local static, initialised once).
Isa defaultIsa() noexcept;

/// `requested` if supported, else the widest supported ISA narrower than it (Scalar for an ISA
/// of another architecture).
Isa supportedIsaAtMost(Isa requested) noexcept;

}  // namespace delta::kernels
