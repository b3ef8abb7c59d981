#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace delta::kernels {

/// The instruction sets the batched triangle kernels are compiled for, one translation unit each
/// (src/kernels/isa/), narrowest first. `Scalar` (one lane) is the reference the others are
/// tested against; `Sse2` (2 lanes) is the x86-64 baseline; `Avx2` (4 lanes, with FMA) and
/// `Avx512` (8 lanes, AVX-512F/DQ/VL) run where the CPU has them. One binary runs everywhere:
/// the choice is made at run time.
enum class Isa : std::uint8_t { Scalar, Sse2, Avx2, Avx512 };

/// "scalar", "sse2", "avx2", "avx512".
///
/// Threading (this function and the ones below, unless they say otherwise): a pure function;
/// safe from any thread.
const char* name(Isa isa) noexcept;

/// The inverse of name() (exact, lower case); nullopt for anything else.
std::optional<Isa> parseIsa(std::string_view text) noexcept;

/// Doubles per register: 1, 2, 4 or 8.
int laneCount(Isa isa) noexcept;

/// Whether this build has `isa` compiled in and this CPU (and OS) can run it. Scalar always is.
bool isSupported(Isa isa) noexcept;

/// Every supported ISA, narrowest first (always starts with Scalar). Allocates.
std::vector<Isa> supportedIsas();

/// The ISA the batched kernels (and the point queries' leaf bounds and descent) use when none is
/// named: the widest supported one, chosen once
/// (on the first call). The environment variable DELTA_ISA=scalar|sse2|avx2|avx512, read at that
/// moment, lowers it for tests and benchmarks; a name this CPU cannot run, or an unknown one,
/// is ignored.
///
/// Threading: safe to call from any thread (a function-local static, initialised once).
Isa defaultIsa() noexcept;

/// `requested` if supported, else the widest supported ISA narrower than it.
Isa supportedIsaAtMost(Isa requested) noexcept;

}  // namespace delta::kernels
