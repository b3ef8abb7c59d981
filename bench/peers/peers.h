#pragma once

// The peers of bench/peers/peers_bench.cpp: Embree 3, CGAL's AABB tree and FCL behind small
// interfaces, each in its own file, compiled only when its library was found (DELTA_HAVE_EMBREE,
// DELTA_HAVE_CGAL, DELTA_HAVE_FCL). Every peer is used as its own documentation recommends for
// the query; what each one counts as build time and as memory is stated at its factory.

#include <malloc.h>
#include <omp.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/rotation.h"
#include "delta/core/triangle.h"
#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

namespace delta::bench {

/// Bytes the heap holds right now: glibc's mallinfo2, every arena plus mmapped chunks. The
/// difference across a serial build is what the built structure keeps (used for the peers that
/// have no memory accounting of their own: CGAL, FCL).
inline std::size_t heapBytesInUse() noexcept {
  const struct mallinfo2 info = mallinfo2();
  return info.uordblks + info.hblkhd;
}

/// The benchmark's one parallel loop for the peers (Δ parallelises itself): `body(i)` for every
/// i in [0, count), OpenMP dynamic chunks of 1024 on omp_get_max_threads() threads.
template <typename Body>
void parallelOverPoints(std::size_t count, const Body& body) {
#pragma omp parallel for schedule(dynamic, 1024)
  for (std::size_t i = 0; i < count; ++i)
    body(i);
}

/// A peer's points–mesh distance structure, built once and queried any number of times.
///
/// Threading: the build runs in the constructor (a factory below); distances() runs its own
/// parallel loop (parallelOverPoints); one call at a time.
class PointDistancePeer {
 public:
  virtual ~PointDistancePeer() = default;
  /// Seconds the build took (what counts is stated at each factory).
  virtual double buildSeconds() const noexcept = 0;
  /// Bytes the structure holds, and how they were counted.
  virtual std::size_t memoryBytes() const noexcept = 0;
  virtual const char* memoryMethod() const noexcept = 0;
  /// out[i] = the exact unsigned distance from points[i] to the mesh where it is below `radius`
  /// (+∞ for an unbounded query), +∞ otherwise. `out` is as long as `points`.
  virtual void distances(std::span<const Vec3> points, double radius,
                         std::span<double> out) const = 0;
};

#if defined(DELTA_HAVE_EMBREE)
/// Embree 3: a scene with one triangle geometry (shared user buffers, float vertices, the mesh's
/// triangle order), committed on a device configured with `threads=N`. Queries: rtcPointQuery
/// with a callback that computes the closest point of triangle primID of `mesh` in double
/// (kernels::closestPointOnTriangle) and shrinks the query radius. `mesh` must outlive the peer.
/// Build time is everything after rtcNewDevice up to rtcCommitScene (float conversion, buffers,
/// scene, BVH); memory is what the device memory monitor saw allocated and not freed over that span
/// plus the user buffers.
std::unique_ptr<PointDistancePeer> makeEmbreePeer(const Mesh& mesh, int threads);
const char* embreeVersion() noexcept;
#endif

#if defined(DELTA_HAVE_CGAL)
/// CGAL: AABB_tree of the triangles (Simple_cartesian<double>, a vector of Triangle_3 in the
/// mesh's order) after build() and accelerate_distance_queries(). Unbounded queries:
/// tree.squared_distance(p). Bounded (W2): a point whose cube [p − r, p + r] meets no triangle
/// (tree.do_intersect(Bbox_3)) is further than r; the others get squared_distance and a
/// comparison with r. Build time: the triangle vector, the tree, the KD-tree of hints, serial.
/// Memory: the heap's growth over that build (heapBytesInUse).
std::unique_ptr<PointDistancePeer> makeCgalPeer(const Mesh& mesh);
const char* cgalVersion() noexcept;

/// The exact distance from `p` to `triangle` (tests/kernels/exact_distance.h: CGAL interval
/// filter with an exact rational fallback), independent of Δ's kernels.
double exactDistance(const Vec3& p, const Triangle& triangle);
/// The exact distance of two solid triangles (0 where they meet), as above.
double exactDistance(const Triangle& first, const Triangle& second);
/// Whether two solid triangles share a point, by CGAL's exact predicates.
bool exactIntersect(const Triangle& first, const Triangle& second);
#endif

#if defined(DELTA_HAVE_FCL)
/// FCL 0.7: two BVHModel<OBBRSSd> (one per mesh, each in its own frame) and the second placed by
/// a rigid motion, the first at the identity. Build time: both models (vertex conversion,
/// beginModel/addSubModel/endModel); memory: the heap's growth over it. Queries are serial: FCL
/// has no parallel BVH traversal.
class FclMeshPair {
 public:
  virtual ~FclMeshPair() = default;
  virtual std::size_t memoryBytes() const noexcept = 0;

  struct Distance {
    double distance = 0.0;
    std::uint32_t first = 0;  ///< triangle of the first mesh (FCL's b1)
    std::uint32_t second = 0;
  };
  /// fcl::distance with a default DistanceRequestd (exact: rel_err = abs_err = 0).
  virtual Distance minimumDistance(const RigidTransform& secondMotion) const = 0;

  struct Collision {
    std::size_t contacts = 0;  ///< FCL's contact count (up to 2 points per triangle pair)
    /// The distinct (first, second) triangle pairs FCL found intersecting, sorted.
    std::vector<std::pair<std::uint32_t, std::uint32_t>> pairs;
  };
  /// fcl::collide with CollisionRequestd(maxContacts, enable_contact = true).
  virtual Collision collide(const RigidTransform& secondMotion, std::size_t maxContacts) const = 0;
};
std::unique_ptr<FclMeshPair> makeFclPair(const Mesh& first, const Mesh& second);
const char* fclVersion() noexcept;
#endif

}  // namespace delta::bench
