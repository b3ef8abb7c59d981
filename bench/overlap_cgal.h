#pragma once

// CGAL's corefinement as the peer of Δ's overlap() (bench/overlap_bench.cpp): compiled apart
// (bench/overlap_cgal.cpp, with CGAL's -frounding-math), so that only this file sees CGAL.

#include <memory>

#include "delta/mesh/mesh.h"

namespace delta::bench {

/// The volume of A ∩ B by CGAL::Polygon_mesh_processing::corefine_and_compute_intersection on
/// Surface_meshes with Exact_predicates_inexact_constructions_kernel points, then
/// Polygon_mesh_processing::volume. Corefinement cuts its inputs, so each intersection needs
/// fresh copies of both meshes: copyInputs() makes them (timed on its own), intersectCopies()
/// consumes them. The result goes to a third mesh: measured on the armadillo, that is about 10%
/// faster than writing it into the first copy, which CGAL allows too.
///
/// Threading: one object per thread.
class CgalIntersection {
 public:
  /// Builds the two Surface_meshes (once; not part of any timing).
  CgalIntersection(const Mesh& first, const Mesh& second);
  ~CgalIntersection();
  CgalIntersection(const CgalIntersection&) = delete;
  CgalIntersection& operator=(const CgalIntersection&) = delete;

  /// Copies both meshes into the working pair that intersectCopies() cuts.
  void copyInputs();
  /// Corefines the working pair and returns the volume of the intersection; NaN where CGAL
  /// reports that it could not make it (a non-manifold result).
  double intersectCopies();

 private:
  struct Meshes;
  std::unique_ptr<Meshes> meshes_;
};

}  // namespace delta::bench
