// delta::io::loadPoints on arbitrary bytes: points within the queries' coordinate range or a
// delta::Error, nothing else.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "delta/core/error.h"
#include "delta/io/points.h"
#include "delta/mesh/coordinate_range.h"

#include "fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static FuzzFile file(".xyz");
  try {
    for (const delta::Vec3& point : delta::io::loadPoints(file.write(data, size)))
      if (!delta::inCoordinateRange(point)) std::abort();
  } catch (const delta::Error&) {
  }
  return 0;
}
