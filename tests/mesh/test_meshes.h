#pragma once

// Small meshes the mesh layer's tests share.

#include <vector>

#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

namespace delta::test {

/// The unit tetrahedron (0, e_x, e_y, e_z), outward-oriented: volume 1/6.
inline Mesh unitTetrahedron() {
  return Mesh({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
              {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

/// `mesh` with one more vertex, at `where`, that no triangle uses (a Mesh keeps such vertices).
inline Mesh withUnusedVertex(const Mesh& mesh, const Vec3& where) {
  std::vector<Vec3> vertices(mesh.vertices().begin(), mesh.vertices().end());
  vertices.push_back(where);
  return Mesh(std::move(vertices), {mesh.triangles().begin(), mesh.triangles().end()});
}

}  // namespace delta::test
