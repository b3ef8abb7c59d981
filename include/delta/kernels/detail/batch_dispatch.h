#pragma once

// The glue between the public batch API and the per-ISA tables: views of the inputs, and the
// table of an ISA.

#include <cstddef>

#include "delta/core/triangle.h"
#include "delta/kernels/detail/batch_views.h"
#include "delta/kernels/isa.h"
#include "delta/mesh/triangle_soa.h"

namespace delta::detail {

inline SoaView soaView(const TriangleSoA& soa) noexcept {
  SoaView view{};
  for (int vertex = 0; vertex < 3; ++vertex)
    for (int axis = 0; axis < 3; ++axis)
      view.streams[3 * vertex + axis] = soa.stream(vertex, axis);
  view.paddedSize = soa.paddedSize();
  return view;
}

inline TriangleCoordinates coordinates(const Triangle& t) noexcept {
  return {{t.a.x, t.a.y, t.a.z, t.b.x, t.b.y, t.b.z, t.c.x, t.c.y, t.c.z}};
}

/// The table of `isa`, lowered to a supported one (kernels::supportedIsaAtMost).
const BatchKernels& batchKernels(kernels::Isa isa) noexcept;

/// The pair count of a blocks call and of a one-against-range call (see penaltyDistances).
inline std::size_t blockPairCount(const TriangleSoA& first, const TriangleSoA& second) noexcept {
  return first.size() < second.size() ? first.size() : second.size();
}
inline std::size_t rangePairCount(const TriangleSoA& block, std::size_t begin,
                                  std::size_t end) noexcept {
  if (end > block.size()) end = block.size();
  return begin < end ? end - begin : 0;
}

}  // namespace delta::detail
