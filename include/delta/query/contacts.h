#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "delta/core/contact_point.h"
#include "delta/kernels/triangle_batch.h"
#include "delta/mesh/triangle_soa.h"
#include "delta/query/pair_cache.h"
#include "delta/query/query_mesh.h"

namespace delta::detail {
struct CachedContacts;
}  // namespace delta::detail

/// The seed's contact-detection API: mesh–mesh contacts and minimum distance, points–mesh
/// distances and contacts, sphere–mesh contacts, and the redundancy filter. The queries validate
/// their input (delta::Error) and read their meshes only; those over many triangles or points run
/// in parallel themselves.
namespace delta::contactdetection {

/// The seed's mesh–mesh contact detection: every pair of triangles (one of each mesh) closer than
/// 2ε yields one ContactPoint — `x` midway between the closest points P (first mesh) and Q
/// (second), `normal` = P − x, `direction` the unit vector from Q toward P, `distance` |P − Q|,
/// `overlap` set where the two triangles intersect, and both triangle ids (0-based, the meshes'
/// triangle order). Contacts come sorted by (first, second) ids, the same for any thread count.
///
/// For touching or intersecting triangles (P = Q) `direction` comes from the faces: the unit
/// vector of n₂ − n₁ (n₁, n₂ the outward unit normals of the first and second triangle, so it
/// points from the second mesh into the first), or n₂, or −n₁ when that vanishes, or +z for two
/// zero-area triangles.
///
/// Pruning before any kernel runs: the meshes' boxes further apart than 2ε return at once; blocks
/// of the second mesh whose box is further than 2ε from a triangle's box are skipped. With the
/// hybrid (default) or brute-force solver the contact set is exact: every pair whose distance,
/// as that solver computes it (within a few ulps of the pair's coordinates), is below 2ε; a pair
/// within those ulps of 2ε may be in one solver's set and not the other's (two triangles exactly
/// 1 apart near 1e6 were at 0.99999999999999989 by the hybrid). With the penalty solver,
/// approximate (a pair may be missed or misplaced where its Newton did not converge).
///
/// Degenerate and overlapping input: zero-area triangles take part like any other (as the
/// segment or point they are); interpenetrating meshes give a contact, marked `overlap`, for
/// every pair of triangles that intersect or touch, with P = Q a point of both; a mesh against
/// itself, or an identical copy in the same place, gives such a contact for every triangle
/// with itself and with each neighbour it shares a vertex or an edge with (and an ordinary one
/// for every other pair closer than 2ε). Meshes further than 2ε apart give none.
///
/// Throws delta::Error when ε is not finite and positive or below 2⁻⁴⁸¹ (about 1.6e-145: there
/// (2ε)² underflows, and a pair closer than 2ε cannot be told from one farther; scale the meshes
/// and ε up by a power of two, which is exact), a mesh has no triangles, or a mesh is
/// outside the coordinate range (mesh/coordinate_range.h: a coordinate beyond ±2²⁰⁰, or every
/// coordinate below 2⁻²⁰⁰; the message names the first or second mesh, its box and the range).
///
/// Threading: reads both meshes only; any number of threads may call it at once, and it runs in
/// parallel over the first mesh's triangles itself (core/parallel.h), serially inside an
/// enclosing OpenMP parallel region.
std::vector<ContactPoint> contacts(const TriangleSoA& first, const TriangleSoA& second,
                                   double epsilon,
                                   kernels::Solver solver = kernels::Solver::Hybrid);

/// The same contacts for prepared meshes, with the full overlap marker: a contact is also marked
/// `overlap` where its point x lies inside both meshes (when both are closed; QueryMesh::closed)
/// — two parallel faces each inside the other mesh, a pair that does not intersect although the
/// meshes interpenetrate there. Inside is decided as by a signed point query
/// (query/point_distance.h): by pseudonormals, or, for a closed mesh that bounds no solid (it
/// crosses itself, selfIntersections, or its parts do not nest, partNesting; found by the first
/// such call), by its winding number; a point on either surface is not inside.
///
/// Found by descending both QueryMesh trees at once to the pairs of leaves whose boxes are within
/// 2ε (work in proportion to the contact region, not to |first|·|second|), then, in parallel over
/// those leaf pairs, each triangle of the first leaf against the second's. Moved meshes
/// (QueryMesh::transform) are compared where they are: the second's boxes and, leaf by leaf, its
/// triangles are carried into the first's prepared frame; nothing is rebuilt.
///
/// Throws and threading as the flattened form; moved meshes are checked where they are and with
/// the second carried into the first's frame (where the kernels meet them).
std::vector<ContactPoint> contacts(const QueryMesh& first, const QueryMesh& second, double epsilon,
                                   kernels::Solver solver = kernels::Solver::Hybrid);

/// Whether contacts() marks `overlap` where a contact's x lies inside both closed meshes itself
/// (`now`, as contacts(first, second, ε) always does), or leaves that to markInside() on the
/// contacts a caller keeps (`later`: a DEM pair keeps about one in five after filter(h), and the
/// test costs two nearest-triangle searches a contact).
enum class InsideTest : std::uint8_t { now, later };

/// What contacts(first, second, ε, cache) keeps of a pair of prepared meshes from one call to
/// the next (temporal coherence, as a DEM pair in contact is met step after step): the triangle
/// pairs closer than 2ε + `skin` where the second mesh was, relative to the first, when it was
/// made. Until the two have moved against each other by about the skin (PairCache,
/// query/pair_cache.h), no other triangle pair can have come within 2ε, so the two trees are not
/// descended again: only the kept pairs go to the kernels, and of those only the ones whose
/// distance when kept, less the move since, is still under 2ε. A larger skin keeps the cache
/// longer and costs a larger descent each time it is made.
///
/// Threading: a value type; one cache belongs to one pair, used by one thread at a time.
class ContactCache : public PairCache {
 public:
  /// A kept triangle pair: prepared (sorted) triangle indices, and the kernels' distance when
  /// made (0 with the penalty solver, whose distances may be too long): less the move since, a
  /// lower bound of the distance now.
  struct KeptPair {
    std::uint32_t first, second;
    double distance;
  };

  /// An empty cache (made at the first call) that keeps pairs within 2ε + `skin`; a skin that is
  /// not finite and positive makes every call a fresh query.
  explicit ContactCache(double skin = 0.0) noexcept : PairCache(skin) {}

  /// The triangle pairs it holds (0: empty, or a pair further than 2ε + skin apart).
  std::size_t size() const noexcept { return pairs_.size(); }
  /// Asks the processor to fetch what the next call reads first (a caller's loop over its
  /// pairs calls it one pair ahead: the kept pairs are touched once a step, cold).
  void prefetch() const noexcept { __builtin_prefetch(pairs_.data()); }

 private:
  friend struct detail::CachedContacts;
  double epsilon_ = 0.0;
  kernels::Solver solver_ = kernels::Solver::Hybrid;
  std::vector<KeptPair> pairs_;  ///< by increasing distance, in one block (one cache miss)
  /// The first's distance (+∞: none), beside the rest: a pair still apart by it costs no read
  /// of the kept pairs.
  double nearest_ = 0.0;
};

/// contacts(first, second, ε, solver), the same contacts bit for bit, through `cache`: made
/// (from a descent of both trees to 2ε + skin) when empty, made for other meshes, ε or solver,
/// or when the second mesh has moved against the first by more than its skin allows since;
/// otherwise only the triangle pairs it holds are handed to the kernels, in one batch (a pair's
/// answer does not depend on the batch it is in: kernels/hybrid.h). Runs serially.
///
/// With InsideTest::later, `overlap` is set only where two triangles intersect or touch.
///
/// Throws as contacts(first, second, ε, solver).
///
/// Threading: as contacts(); `cache` is the caller's, one thread at a time.
std::vector<ContactPoint> contacts(const QueryMesh& first, const QueryMesh& second, double epsilon,
                                   ContactCache& cache,
                                   kernels::Solver solver = kernels::Solver::Hybrid,
                                   InsideTest inside = InsideTest::now);

/// Many pairs' contacts through their caches, the kernels run once for all of them: each pair
/// gets what contacts(first, second, ε, cache, solver, inside) gives it, bit for bit, but the
/// triangle pairs of every pair whose cache holds go to the kernels in one batch. A pair at rest
/// keeps a few (about five on a DEM hopper): alone, they leave most of a batch's lanes idle and
/// pay the kernels' call each. A pair whose cache does not hold is answered when added, as by
/// contacts().
///
///     batch.clear();
///     for (...) batch.add(first, second, epsilon, cache);
///     batch.run();
///     for (...) use(batch.contacts(k));  // k: the index add() returned
///
/// Throws as contacts(first, second, ε, cache, solver, inside), from add().
///
/// Threading: a batch is used by one thread at a time; the meshes and caches added must stay
/// as they are, and alive, until run() has returned.
class ContactBatch {
 public:
  explicit ContactBatch(kernels::Solver solver = kernels::Solver::Hybrid);
  ~ContactBatch();
  ContactBatch(ContactBatch&&) noexcept;
  ContactBatch& operator=(ContactBatch&&) noexcept;

  /// Adds a pair; returns its index (0, 1, … in the order added since clear()).
  std::size_t add(const QueryMesh& first, const QueryMesh& second, double epsilon,
                  ContactCache& cache, InsideTest inside = InsideTest::now);
  /// Runs the kernels on the pairs gathered since the last run() and finishes them; pairs may
  /// be added after it, for another run().
  void run();
  /// The contacts of the pair added as `index` (the caller may move them out). Throws
  /// delta::Error for an index not added since clear(), or a pair added since the last run().
  std::vector<ContactPoint>& contacts(std::size_t index);
  /// The pairs added since clear().
  std::size_t size() const noexcept;
  /// Forgets every pair added (keeps its memory for the next).
  void clear() noexcept;

 private:
  struct Entry;
  struct State;
  kernels::Solver solver_;
  std::unique_ptr<State> state_;
};

/// The inside test contacts() makes, on contacts found with InsideTest::later (in the world
/// frame, as contacts() gives them, from the same meshes in the same order): each contact not
/// yet marked `overlap` is marked where its x lies inside both meshes; nothing when either is
/// not closed. Decided in each mesh's prepared frame (x carried there by its inverse pose), so
/// a mark can differ from contacts()'s own, made in the first mesh's frame, only where x lies
/// on a surface within rounding.
///
/// Throws delta::Error when ε is not finite and positive.
///
/// Threading: reads both meshes only; any number of threads may call it at once; parallel over
/// the contacts itself, serially inside an enclosing parallel loop.
void markInside(const QueryMesh& first, const QueryMesh& second, double epsilon,
                std::span<ContactPoint> contacts);

}  // namespace delta::contactdetection
