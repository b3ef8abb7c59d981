#pragma once

#include <cstdint>

#include "delta/core/vec3.h"
#include "delta/kernels/triangle_batch.h"
#include "delta/mesh/triangle_soa.h"

namespace delta::contactdetection {

/// The closest pair of triangles of two meshes and their closest points.
struct MinimumDistance {
  double distance = 0.0;
  std::uint32_t first = 0;   ///< triangle id in the first mesh
  std::uint32_t second = 0;  ///< triangle id in the second mesh
  Vec3 p;                    ///< on triangle `first`
  Vec3 q;                    ///< on triangle `second`
  bool intersect = false;    ///< the meshes touch or intersect there (distance 0)
};

/// The minimum distance between two flattened meshes, over all triangle pairs, with the pair that
/// attains it. With the hybrid (default) or brute-force solver it is exact (the brute force's
/// answer to 1e-12 of the pair's size); with the penalty solver, approximate. Where several pairs
/// attain the minimum, the one with the smallest (first, second) ids is returned, so the answer
/// is the same for every thread count.
///
/// O(|first|·|second|) kernel calls, in parallel over the first mesh's triangles (core/parallel.h).
/// Throws delta::Error when either mesh has no triangles.
///
/// Threading: reads both meshes only; any number of threads may call it at once.
MinimumDistance minimumDistance(const TriangleSoA& first, const TriangleSoA& second,
                                kernels::Solver solver = kernels::Solver::Hybrid);

}  // namespace delta::contactdetection
