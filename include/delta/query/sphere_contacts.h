#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "delta/core/contact_point.h"
#include "delta/core/sphere.h"
#include "delta/kernels/sphere.h"
#include "delta/mesh/triangle_soa.h"
#include "delta/query/query_mesh.h"

namespace delta::contactdetection {

/// Sphere–mesh contact detection, for DEM codes whose particles are spheres against triangulated
/// walls: every triangle whose surface-to-surface gap to a sphere is below 2ε (strictly, as for
/// mesh–mesh contacts) yields one ContactPoint. The first geometry is the sphere, the second the
/// mesh. Per (sphere, triangle), with kernels::sphereTriangle (triangles are solid and two-sided):
///
/// - Q is the point of the triangle closest to the centre c, and the gap is |c − Q| − r.
/// - `direction` is the unit vector from Q toward c (from the wall toward the sphere's centre).
///   Where c lies on the triangle (within rounding) it is the triangle's unit face normal (the
///   sense of Triangle::areaVector), so a centre on an outward-oriented wall is pushed out of the
///   wall; for a zero-area triangle, a unit vector orthogonal to it (+x for a single point).
/// - P = c − r·direction: the sphere's point closest to the triangle when apart, and its point
///   deepest beyond the triangle when they overlap (Q then lies on the segment from c to P).
/// - `x` = (P + Q) / 2 and `normal` = P − x.
/// - `distance` = |P − Q| = |gap|: the gap when apart (0 when touching), the penetration depth
///   r − |c − Q| when overlapping. It is taken from the kernel's gap, computed in the triangle's
///   frame, so it keeps its accuracy far from the origin where P − Q would cancel.
/// - `overlap` = gap < 0. Apart, `normal` = +(distance / 2)·direction, as for every
///   ContactPoint; overlapping, `normal` = −(distance / 2)·direction: still P − x, but it
///   points into the wall, away from the centre. A DEM force acts along `direction` with a
///   magnitude that grows with the depth `distance`.
/// - `first` = the sphere's index (0 for the one-sphere overload), `second` = the triangle id
///   (0-based, the mesh's triangle order).
///
/// Contacts come sorted by (first, second), the same for any thread count: exactly the
/// triangles for which kernels::sphereTriangle gives a gap below 2ε, with its P, Q and normal.
///
/// Pruning before any kernel runs: a sphere whose box is further than 2ε from the mesh's box
/// gets none; blocks of 64 consecutive triangles whose box does not meet the centre's box grown
/// by r + 2ε are skipped. Both tests are conservative by a few ulps of the coordinates, so
/// rounding never drops a triangle the kernel would report. The blocks follow the mesh's own
/// triangle order: for a mesh listed in no spatial order they span it, and a sphere runs the
/// kernel on most triangles (an audit: icosphere(6) shuffled, 7.5 ms a sphere against 18 µs);
/// the one-sphere overload also checks the mesh and makes the blocks' boxes at each call, O(n).
/// A prepared mesh (the QueryMesh overloads below) does neither.
///
/// Throws delta::Error when ε is not finite and positive, when the mesh has no triangles, or
/// when a sphere's centre is not finite or its radius is not finite and positive (the message
/// names the sphere's index), when a sphere reaches beyond ±2²⁰⁰, the mesh is outside the
/// coordinate range, or a triangle is not one point and less than 2⁻²⁰⁰ across, where the kernel's
/// products underflow (mesh/coordinate_range.h); these are checked before any work, even for an
/// empty span of spheres, which otherwise gives no contacts. Ids are 32-bit: more than 2³² spheres
/// or triangles throw too.
///
/// Threading: reads its inputs only; any number of threads may call it at once on the same
/// mesh and spheres. The one-sphere overload runs on the calling thread; the many-sphere
/// overload runs in parallel over the spheres itself (core/parallel.h), and serially when
/// called inside an enclosing OpenMP parallel region.
std::vector<ContactPoint> sphereContacts(const Sphere& sphere, const TriangleSoA& mesh,
                                         double epsilon);

/// Many spheres (a DEM particle set) against one mesh: the contacts of every sphere as above,
/// `first` being its index in `spheres`, sorted by (sphere index, triangle id).
std::vector<ContactPoint> sphereContacts(std::span<const Sphere> spheres, const TriangleSoA& mesh,
                                         double epsilon);

/// The same contacts, in the same order, as sphereContacts(spheres, mesh.triangles(), ε): the
/// spheres against the mesh where it was prepared (its pose is not applied: give the centres in
/// that frame, as mesh.inversePose() takes them there), found through its tree instead of
/// blocks of consecutive triangles: a node is skipped where the ball (grown by 2ε) misses its
/// box or its oriented slab, a triangle where it misses the triangle's box (distances from the
/// centre, not boxes around the ball, which met every box along a diagonal: a sphere of radius
/// 1e3 beside an icosphere ran 8.7 ms, now 65 µs; the slabs keep a turned CAD cylinder's long
/// slivers out, 5.7 ms → 0.5 µs for a sphere above its cap), each test conservative by a few
/// ulps. A
/// DEM step asks this for every sphere near a wall: a funnel's consecutive triangles run round
/// it, so their blocks' boxes met most spheres and a sphere ran a hundred kernels or more.
///
/// Throws as the overload above (the mesh's range was checked when it was prepared; a triangle
/// less than 2⁻²⁰⁰ across, which a prepared mesh may hold for the point queries, is refused here
/// as the mesh–mesh queries refuse it: an audit found a sphere overlapping a triangle 1e-100
/// across given no contact).
///
/// Threading: as the overload above.
std::vector<ContactPoint> sphereContacts(std::span<const Sphere> spheres, const QueryMesh& mesh,
                                         double epsilon);

/// What sphereContacts(sphere, mesh, ε, cache, out) keeps of one sphere against one prepared
/// mesh from a call to the next (temporal coherence: a DEM sphere resting on a wall is met step
/// after step): the triangles whose gap to the sphere was below 2ε + `skin` where the sphere was
/// when it was made, with those gaps. Until the centre has moved by about the skin (in the
/// mesh's prepared frame), no other triangle can have come within 2ε, so the tree is not
/// descended: only the kept triangles whose gap when kept, less the move since, is still under
/// 2ε go to the kernel (a sphere on a floor of two triangles runs one kernel, not two).
///
/// Threading: a value type; one cache belongs to one sphere and mesh, used by one thread at a
/// time.
class SphereContactCache {
 public:
  /// A kept triangle: its prepared (sorted) index, the kernel's gap when made, and the
  /// triangle made ready for the kernel (its frame and normal computed once, not each call).
  struct KeptTriangle {
    std::uint32_t index;
    double gap;
    kernels::PreparedTriangle triangle;
  };

  /// An empty cache (made at the first call) that keeps triangles within 2ε + `skin`; a skin
  /// that is not finite and positive makes every call a fresh query.
  explicit SphereContactCache(double skin = 0.0) noexcept : skin_(skin) {}

  double skin() const noexcept { return skin_; }
  /// The triangles it holds.
  std::size_t size() const noexcept { return triangles_.size(); }
  /// How many calls made it anew, and how many it answered; for statistics.
  std::size_t made() const noexcept { return made_; }
  std::size_t reused() const noexcept { return reused_; }

 private:
  friend void sphereContacts(const Sphere& sphere, const QueryMesh& mesh, double epsilon,
                             SphereContactCache& cache, std::vector<ContactPoint>& out);
  double skin_ = 0.0;
  bool valid_ = false;
  std::shared_ptr<const void> meshData_;  ///< the prepared mesh it was made for, held
  double epsilon_ = 0.0;
  double radius_ = 0.0;
  Vec3 center_;             ///< where the centre was (the mesh's prepared frame) when made
  double budget_ = 0.0;     ///< how far the centre may move: the skin less rounding
  double allowance_ = 0.0;  ///< the rounding allowed for: 2⁻³⁶ of the coordinates
  std::vector<KeptTriangle> triangles_;  ///< by increasing index (the contacts' order)
  std::size_t made_ = 0, reused_ = 0;
};

/// The contacts of one sphere (its centre in the mesh's prepared frame, as for the many-sphere
/// overload; `first` = 0) into `out` (cleared first): sphereContacts(span(&sphere, 1), mesh, ε),
/// the same contacts bit for bit, through `cache`: made (a descent of the tree to 2ε + skin)
/// when empty, made for another mesh, ε or radius, or when the centre has moved by more than
/// its skin allows since; otherwise only the kept triangles that may still be within 2ε go to
/// the kernel.
///
/// Throws as the overload above.
///
/// Threading: runs on the calling thread; the cache and `out` are the caller's.
void sphereContacts(const Sphere& sphere, const QueryMesh& mesh, double epsilon,
                    SphereContactCache& cache, std::vector<ContactPoint>& out);

/// A sphere kernel's answer (kernels::sphereSphere or sphereTriangle) as the ContactPoint
/// conventions above have it: x midway between P and Q, `distance` the gap or, where they
/// overlap, the depth, `first` and `second` the ids given.
///
/// Threading: a pure function.
ContactPoint sphereContactPoint(const kernels::SphereContactResult& result, std::uint32_t first,
                                std::uint32_t second) noexcept;

}  // namespace delta::contactdetection
