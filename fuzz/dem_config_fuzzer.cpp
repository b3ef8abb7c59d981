// The `delta dem --config` reader on arbitrary bytes: settings or a delta::Error, nothing else.
#include <cstddef>
#include <cstdint>

#include "delta/core/error.h"

#include "dem_settings.h"
#include "fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static FuzzFile file(".cfg");
  try {
    const delta::cli::DemSettings settings =
        delta::cli::readDemConfig(file.write(data, size).string());
    delta::cli::checkDemCombination(settings);
  } catch (const delta::Error&) {
  }
  return 0;
}
