// The guide's "Load a mesh and query it" (docs/guide.md): a closed mesh from a file, the signed
// distance of two points to it, and the contacts with a moved copy of it.
//
//   load_and_query MESH        (the test runs it on CGAL's fandisk.off)
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "delta/delta.h"

int main(int argc, char** argv) try {
  if (argc != 2) {
    std::fprintf(stderr, "usage: load_and_query MESH\n");
    return 2;
  }
  // [guide:begin query]
  namespace cd = delta::contactdetection;
  const delta::QueryMesh mesh(delta::io::load(argv[1]));  // checked, then prepared once
  const std::vector<delta::Vec3> points = {{0, 0, 0}, {0, 0, 2}};
  for (const cd::PointDistance& d : cd::distances(mesh, points, {.signedDistance = true}))
    std::printf("signed distance %g, triangle %u\n", d.signedDistance(), d.triangle);
  delta::QueryMesh copy = mesh;  // shares the prepared data; moving it rebuilds nothing
  copy.transform(delta::RigidTransform::translationBy({0.9, 0, 0}));
  const std::vector<delta::ContactPoint> touching = cd::contacts(mesh, copy, 0.001);
  std::printf("%zu contact points closer than 2ε\n", touching.size());
  // [guide:end query]

  // The answers are exact: the same as a loop over every triangle.
  const delta::TriangleSoA& triangles = mesh.triangles();
  const std::vector<cd::PointDistance> answers = cd::distances(mesh, points);
  for (std::size_t p = 0; p < points.size(); ++p) {
    double nearest = answers[p].distance * 2.0 + 1.0;
    for (std::size_t t = 0; t < triangles.size(); ++t)
      nearest = std::min(nearest, std::sqrt(delta::kernels::closestPointOnTriangle(
                                                points[p], triangles.triangle(t))
                                                .distanceSquared));
    if (nearest != answers[p].distance) {
      std::fprintf(stderr, "point %zu: %.17g, but a loop over the triangles gives %.17g\n", p,
                   answers[p].distance, nearest);
      return 1;
    }
  }
  // (0, 0, 2) is far outside a mesh of size 1; a copy moved by 0.9 along x overlaps its end.
  if (cd::distance(mesh, points[1], {.signedDistance = true}).inside || touching.empty()) {
    std::fprintf(stderr, "unexpected: (0, 0, 2) inside, or no contact with the moved copy\n");
    return 1;
  }
  return 0;
} catch (const delta::Error& error) {
  std::fprintf(stderr, "load_and_query: %s\n", error.what());
  return 1;
}
