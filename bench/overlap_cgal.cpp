#include "overlap_cgal.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/corefinement.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Surface_mesh.h>

#include <limits>
#include <memory>
#include <vector>

namespace delta::bench {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using SurfaceMesh = CGAL::Surface_mesh<Kernel::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

SurfaceMesh toSurfaceMesh(const Mesh& mesh) {
  SurfaceMesh surface;
  surface.reserve(static_cast<SurfaceMesh::size_type>(mesh.vertexCount()),
                  static_cast<SurfaceMesh::size_type>(3 * mesh.triangleCount() / 2),
                  static_cast<SurfaceMesh::size_type>(mesh.triangleCount()));
  std::vector<SurfaceMesh::Vertex_index> vertices;
  vertices.reserve(mesh.vertexCount());
  for (const Vec3& v : mesh.vertices())
    vertices.push_back(surface.add_vertex({v.x, v.y, v.z}));
  for (const TriangleIndices& t : mesh.triangles())
    surface.add_face(vertices[t[0]], vertices[t[1]], vertices[t[2]]);
  return surface;
}

}  // namespace

struct CgalIntersection::Meshes {
  Meshes(const Mesh& a, const Mesh& b) : first(toSurfaceMesh(a)), second(toSurfaceMesh(b)) {}

  SurfaceMesh first, second;                // as given
  SurfaceMesh workingFirst, workingSecond;  // the copies corefinement cuts
  SurfaceMesh result;
};

CgalIntersection::CgalIntersection(const Mesh& first, const Mesh& second)
    : meshes_(std::make_unique<Meshes>(first, second)) {}

CgalIntersection::~CgalIntersection() = default;

void CgalIntersection::copyInputs() {
  meshes_->workingFirst = meshes_->first;
  meshes_->workingSecond = meshes_->second;
  meshes_->result.clear();
}

double CgalIntersection::intersectCopies() {
  if (!PMP::corefine_and_compute_intersection(meshes_->workingFirst, meshes_->workingSecond,
                                              meshes_->result))
    return std::numeric_limits<double>::quiet_NaN();
  return CGAL::to_double(PMP::volume(meshes_->result));
}

}  // namespace delta::bench
