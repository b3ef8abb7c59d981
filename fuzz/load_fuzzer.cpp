// delta::io::load on arbitrary bytes in a file named *.off, *.ply, *.obj or *.stl
// (DELTA_FUZZ_EXTENSION): a mesh or a delta::Error, nothing else.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "delta/core/error.h"
#include "delta/io/mesh_io.h"

#include "fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static FuzzFile file(DELTA_FUZZ_EXTENSION);
  try {
    const delta::Mesh mesh = delta::io::load(file.write(data, size));
    // A mesh that loads is valid: every index in range, every coordinate finite.
    for (const delta::TriangleIndices& triangle : mesh.triangles())
      for (const std::uint32_t index : triangle)
        if (index >= mesh.vertexCount()) std::abort();
    for (const delta::Vec3& vertex : mesh.vertices())
      if (!delta::isFinite(vertex)) std::abort();
  } catch (const delta::Error&) {
  }
  return 0;
}
