// Every input the fuzzers (fuzz/, scripts/fuzz.sh) keep as a regression, read through the public
// API in the ordinary test builds too (the sanitized one included): each gives a mesh, points or
// a DEM World, or a delta::Error, never a crash.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/io/mesh_io.h"
#include "delta/io/points.h"
#include "delta/mesh/coordinate_range.h"

#include "promises.h"

namespace delta::io {
namespace {

namespace fs = std::filesystem;

/// tests/fuzz/TARGET, found from this file's path.
fs::path regressionFolder(const std::string& target) {
  return fs::path(__FILE__).parent_path().parent_path() / "fuzz" / target;
}

std::vector<fs::path> regressionInputs(const std::string& target) {
  std::vector<fs::path> inputs;
  for (const fs::directory_entry& entry : fs::directory_iterator(regressionFolder(target)))
    if (entry.is_regular_file()) inputs.push_back(entry.path());
  return inputs;
}

/// A copy of `input` named with `extension` in a fresh temporary folder (the fuzz targets name
/// their file so).
class Renamed {
 public:
  Renamed(const fs::path& input, const std::string& extension)
      : folder_(fs::temp_directory_path() /
                ("delta_fuzz_regression_" +
                 std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
                 input.filename().string())) {
    fs::create_directories(folder_);
    path_ = folder_ / ("input" + extension);
    fs::copy_file(input, path_, fs::copy_options::overwrite_existing);
  }
  ~Renamed() {
    std::error_code ignored;
    fs::remove_all(folder_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path folder_;
  fs::path path_;
};

TEST(FuzzRegressions, EveryMeshInputLoadsOrIsRefused) {
  std::size_t inputs = 0;
  for (const std::string format : {"off", "ply", "obj", "stl"}) {
    for (const fs::path& input : regressionInputs("load_" + format)) {
      SCOPED_TRACE(input.string());
      const Renamed file(input, "." + format);
      try {
        const Mesh mesh = load(file.path());
        EXPECT_GT(mesh.triangleCount(), 0u);
      } catch (const Error& error) {
        EXPECT_NE(std::string(error.what()).find("cannot load"), std::string::npos);
      }
      ++inputs;
    }
  }
  RecordProperty("inputs", static_cast<int>(inputs));
}

TEST(FuzzRegressions, EveryPointsInputLoadsOrIsRefused) {
  const std::vector<fs::path> inputs = regressionInputs("points");
  ASSERT_FALSE(inputs.empty());  // the seeds at least
  for (const fs::path& input : inputs) {
    SCOPED_TRACE(input.string());
    try {
      for (const Vec3& point : loadPoints(input))
        EXPECT_TRUE(inCoordinateRange(point));
    } catch (const Error&) {
    }
  }
}

/// Fails the test for each promise (fuzz/promises.h) an input breaks.
const auto failed = [](const char* promise) { ADD_FAILURE() << "broken: " << promise; };

TEST(FuzzRegressions, EveryCheckpointInputLoadsOrIsRefused) {
  const std::vector<fs::path> inputs = regressionInputs("checkpoint");
  ASSERT_FALSE(inputs.empty());  // the seeds at least
  for (const fs::path& input : inputs) {
    SCOPED_TRACE(input.string());
    try {
      dem::World world = dem::World::load(input);
      fuzz::worldPromises(world, failed);
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find("checkpoint"), std::string::npos) << error.what();
    }
  }
}

TEST(FuzzRegressions, EveryQueriesInputIsAnsweredOrRefused) {
  const std::vector<fs::path> inputs = regressionInputs("queries");
  ASSERT_FALSE(inputs.empty());
  for (const fs::path& input : inputs) {
    SCOPED_TRACE(input.string());
    const Renamed file(input, ".off");
    try {
      fuzz::queryPromises(load(file.path()), failed);
    } catch (const Error&) {
    }
  }
}

}  // namespace
}  // namespace delta::io
