// The command line over the whole double range (issue 21, "Far coordinates"): every reproducer
// that crashed or printed a non-finite answer now ends with one line on stderr naming the
// coordinates and the supported range, and a non-zero exit; coordinates in range still answer.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "cli_run.h"

namespace {

namespace fs = std::filesystem;

using delta::test::expectOneLineError;
using delta::test::jsonNumber;
using delta::test::runDelta;
using delta::test::TemporaryFolder;

std::string armadillo() {
  const std::string path = std::string(DELTA_DATA_DIR) + "/meshes/armadillo.off";
  if (!fs::exists(path)) ADD_FAILURE() << "CGAL's meshes are missing: run scripts/setup.sh";
  return path;
}

/// A points file of one line.
fs::path pointsFile(const TemporaryFolder& folder, const std::string& name,
                    const std::string& line) {
  const fs::path path = folder.path / name;
  std::ofstream(path) << line << "\n";
  return path;
}

TEST(FarCoordinatesCli, DistanceOfAFarPointIsAnErrorNotASegfault) {
  const TemporaryFolder folder("far_points");
  const fs::path far = pointsFile(folder, "far.xyz", "1e155 0 0");
  for (const std::string& mesh : {armadillo(), std::string("builtin:granulate:1")}) {
    for (const char* options : {"", " --signed", " --eps 0.5", " --json"}) {
      const delta::test::CliRun run =
          runDelta("distance " + mesh + " --points '" + far.string() + "'" + options);
      // Refused by the points file's reader, by its line (the query would name its index).
      expectOneLineError(run, "line 1 has a coordinate beyond ±2^200");
    }
  }
}

TEST(FarCoordinatesCli, PointsAtTheRangesEdgeAnswerFinitely) {
  const TemporaryFolder folder("edge_points");
  const fs::path edge = pointsFile(folder, "edge.xyz", "1e60 0 0");
  const delta::test::CliRun run =
      runDelta("distance builtin:granulate:1 --points '" + edge.string() + "' --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  const double distance = jsonNumber(run.out, "min_distance");
  EXPECT_TRUE(std::isfinite(distance)) << run.out;
  EXPECT_NEAR(distance, 1e60, 1e48);
}

TEST(FarCoordinatesCli, ContactWithAFarMeshIsAnErrorNotInfinity) {
  // Printed "minimum distance inf" with exit 0.
  expectOneLineError(
      runDelta("contact builtin:granulate:1 builtin:granulate:2 --translate-b 1e155,0,0"),
      "±2^200");
  expectOneLineError(runDelta("contact builtin:granulate:1 builtin:granulate:2 --translate-b "
                              "1e155,0,0 --eps 0.1"),
                     "±2^200");
}

TEST(FarCoordinatesCli, ImmersedBoundaryMovedFarIsAnErrorNotASegfault) {
  expectOneLineError(runDelta("ib builtin:granulate:1 --levels 3 --steps 1 --translate 1e155,0,0"),
                     "±2^200");
}

}  // namespace
