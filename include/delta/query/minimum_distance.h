#pragma once

#include <cstdint>

#include "delta/core/vec3.h"
#include "delta/kernels/triangle_batch.h"
#include "delta/mesh/triangle_soa.h"
#include "delta/query/query_mesh.h"

namespace delta::contactdetection {

/// The closest pair of triangles of two meshes and their closest points.
///
/// Threading: a value type; no shared state.
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
/// Branch and bound, not all pairs: the second mesh's triangles are sorted along a Morton curve
/// and cut into blocks of 64 (and runs of 16 blocks) with their boxes, and a triangle of the
/// first mesh runs the kernels only on blocks whose box is not further than the least distance
/// found so far (its own, or any triangle's: a bound shared by the threads), nearest blocks
/// first. The bound is always the distance of a pair actually computed, widened against
/// rounding, so no pair attaining the minimum is ever skipped: the answer is that of the
/// all-pairs loop for any thread count. Cost: for each group of 32 triangles of the first mesh,
/// a box test per run of blocks and per block of the near runs, and kernel calls on the few
/// blocks near each triangle where the meshes come closest; in parallel over those groups
/// (core/parallel.h). Allocates a reordered copy of the second mesh (about 80 bytes a
/// triangle, twice that while it is built).
///
/// With the hybrid solver a pair's last bits may depend on the batch it is computed in (see the
/// hybrid's contract: 10⁻¹² of the pair's size), so between pairs whose distances agree to
/// rounding it may name another pair than an all-pairs loop batched otherwise; the distance is
/// the same to that tolerance, and the answer is the same for every thread count.
///
/// Touching or interpenetrating meshes: distance 0, `intersect` true, the intersecting pair with
/// the smallest ids and p = q a point of both. Degenerate triangles take part as the segments
/// or points they are.
///
/// Throws delta::Error when either mesh has no triangles, or is outside the coordinate range
/// (mesh/coordinate_range.h: a coordinate beyond ±2²⁰⁰, or every coordinate below 2⁻²⁰⁰; the
/// message names the first or second mesh, its box and the range): never +∞ or a false
/// "intersect" from overflowed products.
///
/// Threading: reads both meshes only; any number of threads may call it at once (parallel
/// inside, serial inside an enclosing OpenMP parallel region).
MinimumDistance minimumDistance(const TriangleSoA& first, const TriangleSoA& second,
                                kernels::Solver solver = kernels::Solver::Hybrid);

/// The same for prepared meshes, by a best-first descent of both QueryMesh trees at once: node
/// pairs are opened nearest boxes first and the search stops when the nearest remaining boxes
/// are farther than the best pair found — no per-call sorting, the DEM case where meshes are
/// prepared once and then moved (QueryMesh::transform): the second's boxes and, leaf by leaf,
/// its triangles are carried into the first's prepared frame, and `p`, `q` come back where the
/// meshes are. The same exact distance (to the kernels' rounding) and the same tie rule
/// (smallest (first, second) ids among pairs at exactly the minimum), the same answers for
/// touching, interpenetrating and degenerate input. Throws delta::Error only where the moved
/// meshes leave the coordinate range (each where it is, and the second carried into the first's
/// frame: ±2²⁰⁰); a QueryMesh always has triangles.
///
/// Threading: runs on the calling thread; reads both meshes only, so any number of threads may
/// call it at once on the same QueryMeshes.
MinimumDistance minimumDistance(const QueryMesh& first, const QueryMesh& second,
                                kernels::Solver solver = kernels::Solver::Hybrid);

}  // namespace delta::contactdetection
