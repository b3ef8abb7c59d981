// The queries on whatever mesh a file gives (read as *.off; the reader is picked by content, so
// the others come too), held to promises.h's queryPromises: the mesh's distances from points
// around it, its self-intersections, and contacts, minimum distance and (closed) overlap against
// itself turned and shifted by a quarter of its box. Meshes between single precision's range
// and the coordinate range (2¹²⁸ to 2²⁰⁰) are where the queries' float bounds lose theirs: the
// overlap query read past a mesh's triangles there (tests/fuzz/queries/, found through a DEM
// checkpoint).
#include <cstddef>
#include <cstdint>

#include "delta/core/error.h"
#include "delta/io/mesh_io.h"

#include "fuzz_file.h"
#include "promises.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static FuzzFile file(".off");
  try {
    const delta::Mesh mesh = delta::io::load(file.write(data, size));
    delta::fuzz::queryPromises(mesh, delta::fuzz::finding);
  } catch (const delta::Error&) {
  }
  return 0;
}
