#pragma once

#include "delta/mesh/mesh.h"

namespace delta {

/// The closed unit tetrahedron with outward faces: (0,0,0), (1,0,0), (0,1,0), (0,0,1).
inline const Mesh kTetra({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                         {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});

/// `mesh` scaled about the origin by `factor`.
inline Mesh scaled(Mesh mesh, double factor) {
  mesh.scale(factor);
  return mesh;
}

}  // namespace delta
