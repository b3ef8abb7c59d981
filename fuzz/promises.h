// What the fuzz targets hold the library to beyond reading without a crash (fuzz/*_fuzzer.cpp),
// and what the test FuzzRegressions.* holds their regression inputs to in the ordinary builds:
// each promise broken is reported to `broken` with its name (the fuzzers abort, a finding; the
// test fails). Any query or step may refuse with a delta::Error instead; nothing may read
// outside a buffer (the sanitizers see to that).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <vector>

#include "delta/core/error.h"
#include "delta/dem/checkpoint.h"
#include "delta/mesh/mesh.h"
#include "delta/query/contacts.h"
#include "delta/query/minimum_distance.h"
#include "delta/query/overlap.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"
#include "delta/query/self_intersections.h"

namespace delta::fuzz {

/// A fuzz target's `broken`: names the promise and aborts (libFuzzer keeps the input).
[[noreturn]] inline void finding(const char* promise) {
  std::fprintf(stderr, "broken promise: %s\n", promise);
  std::abort();
}

/// Meshes larger than this are read, not queried, and Worlds larger not stepped (a query's or a
/// step's cost grows with them).
inline constexpr std::size_t kMostQueriedTriangles = 4096;
inline constexpr std::size_t kMostSteppedTriangles = 20'000;

/// The distances of points around `mesh` (a lattice over its box grown by a tenth, and its
/// first vertices), unsigned and signed by winding numbers, within `epsilon`: finite, with a
/// triangle of the mesh.
template <class Broken>
void distancePromises(const Mesh& source, const QueryMesh& mesh, double epsilon,
                      const Broken& broken) {
  const Aabb box = mesh.bounds();
  const Vec3 lower = box.lower - box.extent() * 0.1, size = box.extent() * 1.2;
  std::vector<Vec3> points;
  for (int i = 0; i < 27; ++i)
    points.push_back(
        lower + Vec3{size.x * (i % 3) * 0.5, size.y * (i / 3 % 3) * 0.5, size.z * (i / 9) * 0.5});
  for (const Vec3& vertex : source.vertices())
    if (points.size() < 64) points.push_back(vertex);
  for (const bool signedDistance : {false, true}) {
    try {
      for (const contactdetection::PointDistance& answer :
           contactdetection::distances(mesh, points,
                                       {.epsilon = epsilon,
                                       .signedDistance = signedDistance,
                                       .sign = contactdetection::Sign::winding})) {
        if (!answer.found()) continue;
        if (!(std::isfinite(answer.distance) && answer.distance >= 0.0))
          broken("a distance is finite and not negative");
        if (!isFinite(answer.closest) || answer.triangle >= mesh.size())
          broken("a closest point is finite, on a triangle of the mesh");
      }
    } catch (const Error&) {
    }
  }
}

/// `a` against `b` (the same mesh moved): contacts within `epsilon`, the minimum distance, and
/// for a closed mesh the overlap, fresh and through a cache (twice: made, then held), alike.
template <class Broken>
void pairPromises(const QueryMesh& a, const QueryMesh& b, double epsilon, const Broken& broken) {
  const std::size_t count = a.size();
  try {
    for (const ContactPoint& contact : contactdetection::contacts(a, b, epsilon))
      if (!isFinite(contact.x) || !std::isfinite(contact.distance) || contact.first >= count ||
          contact.second >= count)
        broken("a contact is finite, between triangles of the meshes");
  } catch (const Error&) {
  }
  try {
    const contactdetection::MinimumDistance nearest = contactdetection::minimumDistance(a, b);
    if (!(std::isfinite(nearest.distance) && nearest.distance >= 0.0) || !isFinite(nearest.p) ||
        nearest.first >= count || nearest.second >= count)
      broken("the minimum distance is finite, between triangles of the meshes");
  } catch (const Error&) {
  }
  if (!a.closed()) return;
  try {
    contactdetection::OverlapCache cache(0.01 * epsilon);
    const double fresh = contactdetection::overlap(a, b).total.volume;
    if (!std::isfinite(fresh)) broken("an overlap volume is finite");
    for (int call = 0; call < 2; ++call)
      if (contactdetection::overlap(a, b, {}, cache).total.volume != fresh)
        broken("an overlap through a cache is the fresh one");
  } catch (const Error&) {
  }
}

/// Every query on `mesh`: distances around it, its self-intersections, and the pair queries
/// against itself turned and shifted by a quarter of its box.
template <class Broken>
void queryPromises(const Mesh& mesh, const Broken& broken) {
  if (mesh.triangleCount() > kMostQueriedTriangles) return;
  try {
    const QueryMesh a(mesh);
    const double diagonal = a.bounds().diagonal();
    distancePromises(mesh, a, std::numeric_limits<double>::infinity(), broken);
    distancePromises(mesh, a, 0.01 * diagonal, broken);
    try {
      for (const auto& [first, second] : selfIntersections(a).pairs)
        if (first >= a.size() || second >= a.size())
          broken("a self-intersection is of triangles of the mesh");
    } catch (const Error&) {
    }
    QueryMesh b(mesh);
    b.setPose({Quaternion::fromAxisAngle({1, 2, 3}, 0.4), a.bounds().extent() * 0.25});
    pairPromises(a, b, 0.01 * diagonal, broken);
  } catch (const Error&) {
  }
}

/// Its own checkpoint reads back with its state digest: a checkpoint a World writes restarts it.
template <class Broken>
void readsBack(const dem::World& world, const Broken& broken) {
  try {
    if (dem::readCheckpoint(dem::checkpointBytes(world)).world.stateDigest() != world.stateDigest())
      broken("a World's checkpoint reads back with its digest");
  } catch (const Error&) {
    broken("a World's checkpoint reads back");
  }
}

/// A World (read from a checkpoint): it reads back, and a few steps end in finite particles
/// and contacts that read back too, or in a delta::Error (World's guards).
template <class Broken>
void worldPromises(dem::World& world, const Broken& broken) {
  std::size_t triangles = 0;
  for (const dem::Particle& particle : world.particles())
    triangles += world.shapes()[particle.shape].mesh().triangleCount();
  for (const dem::Obstacle& obstacle : world.obstacles())
    triangles += obstacle.mesh.triangleCount();
  readsBack(world, broken);
  if (triangles > kMostSteppedTriangles) return;
  try {
    world.run(3);
  } catch (const Error&) {
    return;
  }
  for (const dem::Particle& particle : world.particles())
    if (!isFinite(particle.position) || !isFinite(particle.velocity) ||
        !isFinite(particle.angularMomentum))
      broken("a step ends with finite particles");
  for (const dem::Contact& contact : world.contacts())
    if (!isFinite(contact.point.x) || !isFinite(contact.force) || !isFinite(contact.couple))
      broken("a step ends with finite contacts");
  readsBack(world, broken);
}

}  // namespace delta::fuzz
