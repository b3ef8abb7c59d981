// The DEM checkpoint reader (World::load: `delta dem --restart`, Python's World.load and
// unpickling) on arbitrary bytes: a World or a delta::Error, nothing else. The bytes are read
// twice: as the file they are (the header's checks), and with the header's payload size and
// CRC-32 made to match them (or, where they do not start with the magic, as the payload of a
// version 2 header made for them), so that the fuzzer reaches the payload's parser, which the
// checksum would otherwise keep it from. A World read is then held to what every World
// promises (promises.h's worldPromises): its own checkpoint reads back with the same state
// digest, and a few steps end in finite particles and contacts or a delta::Error.
//
// Seeds (tests/fuzz/checkpoint/): `DIR/checkpoint.delta` of two granulates on a box's floor,
// with contacts (and under the point law friction springs) in the step checkpointed:
//   delta dem settle --particles 2 --steps 600 --checkpoint-every 600 --out DIR
//   delta dem settle --particles 2 --contact-model volume --steps 560 --checkpoint-every 560 \
//       --out DIR
#include <cstddef>
#include <cstdint>
#include <string>

#include "delta/core/error.h"
#include "delta/dem/checkpoint.h"

#include "forged_checkpoint.h"
#include "fuzz_file.h"
#include "promises.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static FuzzFile file(".delta");
  try {
    delta::dem::World world = delta::dem::World::load(file.write(data, size));
    delta::fuzz::worldPromises(world, delta::fuzz::finding);
  } catch (const delta::Error&) {
  }
  const std::string forged =
      delta::fuzz::withMatchingHeader({reinterpret_cast<const char*>(data), size});
  try {
    delta::dem::Checkpoint checkpoint = delta::dem::readCheckpoint(forged, "fuzz");
    delta::fuzz::worldPromises(checkpoint.world, delta::fuzz::finding);
  } catch (const delta::Error&) {
  }
  return 0;
}
