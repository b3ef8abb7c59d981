#pragma once

// The vector intrinsics of the ISA this translation unit is compiled for (a point table,
// query/isa/point_table.cpp): <immintrin.h> on x86-64, <arm_neon.h> on AArch64.

#if defined(__x86_64__)
// GCC 12 warns of the undefined pass-through registers inside its own AVX-512 intrinsics (where
// they are inlined, with locations in this header's include of them).
#if defined(__clang__)
#include <immintrin.h>
#else
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
#include <immintrin.h>
#pragma GCC diagnostic pop
#endif
#elif defined(__aarch64__) && defined(__ARM_NEON)
#include <arm_neon.h>
#endif
