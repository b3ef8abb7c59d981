#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "delta/core/contact_point.h"
#include "delta/core/sphere.h"
#include "delta/query/contacts.h"
#include "delta/query/query_mesh.h"

namespace delta::dem {

/// The contact points a DEM pair uses, and how many triangle pairs were found before filtering.
///
/// Threading: a value type; no shared state.
struct PairContacts {
  std::vector<ContactPoint> points;
  std::size_t trianglePairs = 0;  ///< contactdetection::contacts' count, before filter(h)
};

/// The narrow phase of one DEM pair (the first body's triangles first in every ContactPoint):
///
/// 1. contactdetection::contacts(first, second, ε): every triangle pair closer than 2ε;
/// 2. filter(h): one point per cluster;
/// 3. each kept point that does not overlap keeps its P (on the first mesh) and takes for Q the
///    closest point of the whole second mesh to P (query/point_distance.h). A triangle pair's
///    closest points are not always the surfaces': a vertex above the diagonal of a flat floor
///    made of two triangles is reported, with one of them, against the shared edge, and P − Q
///    leans off the floor's normal by as much as the vertex is off that edge — a sideways push
///    on a resting particle that no frictionless floor would give. The distance never grows,
///    and where Q lies inside a face the direction is that face's normal;
/// 4. filter(h) again, as refined points may meet.
///
/// `compareInSecondFrame` runs step 1 with the meshes swapped (and the answers turned round):
/// contacts() compares in the first mesh's prepared frame, so the mesh with the large triangles
/// (an obstacle) should be the one whose frame is used; a turned particle's frame would give a
/// floor's triangles boxes far larger than themselves.
///
/// Throws delta::Error as contactdetection::contacts and filter do (ε or h not finite and
/// positive).
///
/// With `cache` (not null), step 1 goes through it (contactdetection::ContactCache: the same
/// contacts, bit for bit, from the triangle pairs it kept while the meshes have moved little
/// against each other), serially, and the inside test of step 1 (`overlap` where x lies inside
/// both meshes) waits for the points step 2 keeps (contactdetection::markInside); it must be the
/// pair's own, used with the same `compareInSecondFrame` each time.
///
/// Threading: reads both meshes only; safe to call concurrently (each with its own cache);
/// serial inside an enclosing OpenMP parallel region (core/parallel.h).
PairContacts pairContacts(const QueryMesh& first, const QueryMesh& second, double epsilon,
                          double filterDistance, bool compareInSecondFrame = false,
                          contactdetection::ContactCache* cache = nullptr);

/// pairContacts through `cache` for many pairs at once, step 1 in one kernel batch
/// (contactdetection::ContactBatch, hybrid solver): addPairContacts adds the pair's step 1 to
/// `batch` and returns its index; after batch.run(), batchedPairContacts takes what step 1
/// found there and runs steps 2–4, with the same meshes, ε, h and `compareInSecondFrame`. The
/// points are pairContacts(first, second, ε, h, compareInSecondFrame, &cache)'s, bit for bit.
///
/// Throws as pairContacts (addPairContacts: ε; batchedPairContacts: h).
///
/// Threading: as pairContacts; `batch` is the calling thread's.
std::size_t addPairContacts(contactdetection::ContactBatch& batch, const QueryMesh& first,
                            const QueryMesh& second, double epsilon, bool compareInSecondFrame,
                            contactdetection::ContactCache& cache);
PairContacts batchedPairContacts(contactdetection::ContactBatch& batch, std::size_t index,
                                 const QueryMesh& first, const QueryMesh& second, double epsilon,
                                 double filterDistance, bool compareInSecondFrame);

/// The narrow phase of two sphere particles (kernels::sphereSphere): one point when the gap
/// between the surfaces, |c₁ − c₂| − r₁ − r₂, is below 2ε (strictly), none otherwise. As for
/// every ContactPoint: x is halfway between the surfaces' closest points on the line of centres,
/// `direction` the unit vector from the second centre toward the first (+x for concentric
/// spheres), `distance` = |gap| and `overlap` = gap < 0, so that the contact law's depth
/// (2ε − gap: 2ε + distance where they overlap) is that of two meshes with the same surfaces.
/// `first` = `second` = 0 (spheres have no triangles); `trianglePairs` is the number of points.
/// Does not validate (the World did, once).
///
/// Threading: a pure function; may be called from any number of threads at once.
PairContacts sphereSphereContacts(const Sphere& first, const Sphere& second,
                                  double epsilon) noexcept;
/// The same, into `result`, its buffer reused (a World's pairs allocate nothing once warm).
///
/// Threading: as above; `result` is the caller's.
void sphereSphereContacts(const Sphere& first, const Sphere& second, double epsilon,
                          PairContacts& result);

/// The narrow phase of a sphere (first) and a mesh (second, a particle or an obstacle), with
/// contactdetection::sphereContacts (query/sphere_contacts.h) in the mesh's prepared frame:
///
/// 1. every triangle whose gap to the sphere (|c − Q| − r, Q the triangle's point closest to the
///    centre c) is below 2ε; `distance` = |gap| and `overlap` = gap < 0, so the contact law's
///    depth is 2ε − gap: a sphere and a mesh particle with the same surface behave alike;
/// 2. the points that are not local minima of the distance are dropped: a point whose Q lies
///    (within rounding) on another reported triangle whose own Q is strictly closer. A sphere
///    above a flat floor of two triangles near their shared diagonal gets, from the triangle it
///    is not over, Q on the diagonal, off the floor's normal by as much as the centre is off the
///    diagonal: a sideways push that no frictionless floor gives (pairContacts, step 3, removes
///    the same artefact for meshes). Equally close points (a centre straight above an edge or a
///    vertex) all stay, and step 3 merges them;
/// 3. filter(h);
/// 4. the points moved from the mesh's prepared frame to where it is (its pose).
///
/// `first` = 0, `second` = the triangle id. Throws delta::Error as sphereContacts and filter do
/// (ε or h not finite and positive, a sphere not finite or not of positive radius).
///
/// Threading: reads the mesh only; safe to call concurrently; serial inside an enclosing OpenMP
/// parallel region (core/parallel.h).
PairContacts sphereMeshContacts(const Sphere& sphere, const QueryMesh& mesh, double epsilon,
                                double filterDistance);

/// sphereMeshContacts with the mesh first and the sphere second: the same points turned round
/// (`direction` and `normal` negated, `first` = the triangle id, `second` = 0).
///
/// Threading: as sphereMeshContacts.
PairContacts meshSphereContacts(const QueryMesh& mesh, const Sphere& sphere, double epsilon,
                                double filterDistance);

/// Steps 2 to 4 of sphereMeshContacts, for contacts that one sphere's query found in the mesh's
/// prepared frame (its centre moved there by mesh.inversePose()): a World batches every sphere
/// near an obstacle into one contactdetection::sphereContacts call and finishes each sphere's
/// share here. `found` must be one sphere's points against `mesh.triangles()` (ids < mesh.size(),
/// unchecked), as sphereContacts returns them; `first` is set to 0.
///
/// Threading: as sphereMeshContacts.
PairContacts finishSphereMeshContacts(std::span<const ContactPoint> found, const QueryMesh& mesh,
                                      double filterDistance);
/// The same, into `result`, its buffer reused.
///
/// Threading: as sphereMeshContacts; `result` is the caller's.
void finishSphereMeshContacts(std::span<const ContactPoint> found, const QueryMesh& mesh,
                              double filterDistance, PairContacts& result);
/// finishSphereMeshContacts of a lone point (`found`, as above), which steps 2 and 3 keep as it
/// is: its step 4 alone, into `out` (the only point of the result, without a PairContacts).
///
/// Threading: a pure function; `out` is the caller's.
void finishSphereMeshContact(const ContactPoint& found, const QueryMesh& mesh,
                             ContactPoint& out) noexcept;

}  // namespace delta::dem
