#pragma once

#include <cstddef>
#include <cstdint>

#include "query_mesh_data.h"

namespace delta::detail {

#if defined(DELTA_X86_ISAS)
/// kernels::closestPointOnTriangle(point, mesh.triangle(sorted[i])).distanceSquared into out[i]
/// for i < count (1 to 8), bit for bit, in eight AVX-512 lanes (exact_lanes.cpp says why the bits
/// agree). Callable only where the CPU has AVX-512 (F, DQ, VL) and FMA.
void exactDistancesSquared8(const QueryMeshData& mesh, const Vec3& point,
                            const std::uint32_t* sorted, std::size_t count, double* out) noexcept;
/// The same in two runs of four AVX2 lanes (the same bits). Callable only where the CPU has AVX2
/// and FMA.
void exactDistancesSquared8Avx2(const QueryMeshData& mesh, const Vec3& point,
                                const std::uint32_t* sorted, std::size_t count,
                                double* out) noexcept;
#endif

}  // namespace delta::detail
