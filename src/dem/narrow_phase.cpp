#include "delta/dem/narrow_phase.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "delta/kernels/point_triangle.h"
#include "delta/kernels/sphere.h"
#include "delta/query/contacts.h"
#include "delta/query/filter.h"
#include "delta/query/point_distance.h"
#include "delta/query/sphere_contacts.h"

namespace delta::dem {
namespace {

/// Contacts found with the meshes swapped, turned round: P and Q swap, so x stays and both
/// the normal and the direction turn.
std::vector<ContactPoint> turnedRound(std::vector<ContactPoint> contacts) noexcept {
  for (ContactPoint& contact : contacts) {
    contact.normal = -contact.normal;
    contact.direction = -contact.direction;
    std::swap(contact.first, contact.second);
  }
  return contacts;
}

/// The second mesh's closest point to the contact's P: see pairContacts, step 3.
void closestToP(ContactPoint& contact, const QueryMesh& second) {
  if (contact.overlap || !(contact.distance > 0.0)) return;
  const Vec3 p = contact.x + contact.normal;
  contactdetection::PointQuery query;
  query.epsilon = contact.distance * (1.0 + 0x1p-40);  // Q itself is that close
  const contactdetection::PointDistance onSecond = contactdetection::distance(second, p, query);
  if (!onSecond.found() || !(onSecond.distance > 0.0) || !(onSecond.distance <= contact.distance))
    return;
  contact.x = (p + onSecond.closest) * 0.5;
  contact.normal = p - contact.x;
  contact.direction = (p - onSecond.closest) / onSecond.distance;
  contact.distance = onSecond.distance;
  contact.second = onSecond.triangle;
}

/// Rounding allowance of the local-minimum test, in units of the coordinates' magnitude: Q of a
/// shared edge, computed from either triangle, agrees to a few ulps of the coordinates.
constexpr double kOnTriangleUlps = 64.0 * std::numeric_limits<double>::epsilon();

double signedGap(const ContactPoint& contact) noexcept {
  return contact.overlap ? -contact.distance : contact.distance;
}

/// The triangle's point of a sphere–triangle contact: Q = P − 2·normal (normal = P − x).
Vec3 pointOnTriangle(const ContactPoint& contact) noexcept {
  return contact.x - contact.normal;
}

/// Step 2 of sphereMeshContacts: whether the contact's Q lies on another reported triangle whose
/// own closest point is strictly closer to the centre (then Q is no local minimum).
bool dominated(const ContactPoint& contact, std::span<const ContactPoint> found,
               const TriangleSoA& triangles) noexcept {
  const Vec3 q = pointOnTriangle(contact);
  const double gap = signedGap(contact);
  for (const ContactPoint& other : found) {
    if (other.second == contact.second) continue;
    const Triangle triangle = triangles.triangle(other.second);
    const double scale =
        maxAbs(q) + std::sqrt(std::max({lengthSquared(triangle.b - triangle.a),
                                        lengthSquared(triangle.c - triangle.b),
                                        lengthSquared(triangle.a - triangle.c)}));  // finite
    const double tolerance = kOnTriangleUlps * scale;
    if (!(signedGap(other) < gap - tolerance)) continue;
    if (kernels::closestPointOnTriangle(q, triangle).distanceSquared <= tolerance * tolerance)
      return true;
  }
  return false;
}

}  // namespace

PairContacts sphereSphereContacts(const Sphere& first, const Sphere& second,
                                  double epsilon) noexcept {
  PairContacts result;
  sphereSphereContacts(first, second, epsilon, result);
  return result;
}

void sphereSphereContacts(const Sphere& first, const Sphere& second, double epsilon,
                          PairContacts& result) {
  result.points.clear();
  result.trianglePairs = 0;
  const kernels::SphereContactResult r = kernels::sphereSphere(first, second);
  if (!(r.gap < 2.0 * epsilon)) return;
  result.points.push_back(contactdetection::sphereContactPoint(r, 0, 0));
  result.trianglePairs = 1;
}

PairContacts finishSphereMeshContacts(std::span<const ContactPoint> found, const QueryMesh& mesh,
                                      double filterDistance) {
  PairContacts result;
  finishSphereMeshContacts(found, mesh, filterDistance, result);
  return result;
}

void finishSphereMeshContacts(std::span<const ContactPoint> found, const QueryMesh& mesh,
                              double filterDistance, PairContacts& result) {
  std::vector<ContactPoint>& kept = result.points;
  kept.clear();
  result.trianglePairs = found.size();
  if (found.size() == 1) {
    kept.emplace_back();
    finishSphereMeshContact(found.front(), mesh, kept.front());
    return;
  }
  for (const ContactPoint& contact : found)
    if (!dominated(contact, found, mesh.triangles())) kept.push_back(contact);
  if (kept.size() > 1) kept = contactdetection::filter(kept, filterDistance);
  for (ContactPoint& contact : kept)
    finishSphereMeshContact(contact, mesh, contact);
}

void finishSphereMeshContact(const ContactPoint& found, const QueryMesh& mesh,
                             ContactPoint& out) noexcept {
  if (&out != &found) out = found;
  out.first = 0;
  if (!mesh.moved()) return;
  const RigidTransform& pose = mesh.pose();
  out.x = pose.apply(out.x);
  out.normal = pose.rotation.rotate(out.normal);
  out.direction = pose.rotation.rotate(out.direction);
}

PairContacts sphereMeshContacts(const Sphere& sphere, const QueryMesh& mesh, double epsilon,
                                double filterDistance) {
  const Sphere inMeshFrame{mesh.moved() ? mesh.inversePose().apply(sphere.center) : sphere.center,
                           sphere.radius};
  const std::vector<ContactPoint> found =
      contactdetection::sphereContacts(std::span<const Sphere>(&inMeshFrame, 1), mesh, epsilon);
  return finishSphereMeshContacts(found, mesh, filterDistance);
}

PairContacts meshSphereContacts(const QueryMesh& mesh, const Sphere& sphere, double epsilon,
                                double filterDistance) {
  PairContacts result = sphereMeshContacts(sphere, mesh, epsilon, filterDistance);
  result.points = turnedRound(std::move(result.points));
  return result;
}

namespace {

/// Steps 2–4 of pairContacts on what step 1 found (with the meshes swapped when
/// `compareInSecondFrame`); the inside test made on the points step 2 keeps when `insideLater`.
PairContacts finishedPairContacts(std::vector<ContactPoint> found, const QueryMesh& first,
                                  const QueryMesh& second, double epsilon, double filterDistance,
                                  bool compareInSecondFrame, bool insideLater) {
  PairContacts result;
  if (compareInSecondFrame) found = turnedRound(std::move(found));
  result.trianglePairs = found.size();
  if (found.empty()) return result;
  std::vector<ContactPoint> kept = contactdetection::filter(found, filterDistance);
  if (insideLater) contactdetection::markInside(first, second, epsilon, kept);
  for (ContactPoint& contact : kept)
    closestToP(contact, second);
  result.points = kept.size() > 1 ? contactdetection::filter(kept, filterDistance) : kept;
  return result;
}

}  // namespace

PairContacts pairContacts(const QueryMesh& first, const QueryMesh& second, double epsilon,
                          double filterDistance, bool compareInSecondFrame,
                          contactdetection::ContactCache* cache) {
  // Through the cache the inside test waits for the points filter(h) keeps.
  const QueryMesh& one = compareInSecondFrame ? second : first;
  const QueryMesh& other = compareInSecondFrame ? first : second;
  std::vector<ContactPoint> found =
      cache ? contactdetection::contacts(one, other, epsilon, *cache, kernels::Solver::Hybrid,
                                         contactdetection::InsideTest::later)
            : contactdetection::contacts(one, other, epsilon);
  return finishedPairContacts(std::move(found), first, second, epsilon, filterDistance,
                              compareInSecondFrame, cache != nullptr);
}

std::size_t addPairContacts(contactdetection::ContactBatch& batch, const QueryMesh& first,
                            const QueryMesh& second, double epsilon, bool compareInSecondFrame,
                            contactdetection::ContactCache& cache) {
  return compareInSecondFrame
             ? batch.add(second, first, epsilon, cache, contactdetection::InsideTest::later)
             : batch.add(first, second, epsilon, cache, contactdetection::InsideTest::later);
}

PairContacts batchedPairContacts(contactdetection::ContactBatch& batch, std::size_t index,
                                 const QueryMesh& first, const QueryMesh& second, double epsilon,
                                 double filterDistance, bool compareInSecondFrame) {
  return finishedPairContacts(std::move(batch.contacts(index)), first, second, epsilon,
                              filterDistance, compareInSecondFrame, true);
}

}  // namespace delta::dem
