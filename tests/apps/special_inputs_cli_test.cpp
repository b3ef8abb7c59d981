// Endless and special files given to the `delta` tool (mesh files, --points, --config), and the
// note on meshes that assimp rounded to single precision: each ends at once in one line on
// stderr, never a wait or a read of gigabytes.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>

#include "apps/cli_run.h"

namespace delta::test {
namespace {

namespace fs = std::filesystem;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/// A sparse file of 3 GiB of zeros (no disk used).
void makeSparse(const fs::path& path) {
  const int fd = ::open(path.c_str(), O_CREAT | O_WRONLY | O_TRUNC, 0600);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::ftruncate(fd, off_t{3} << 30), 0);
  ::close(fd);
}

TEST(SpecialInputsCli, FifosDevicesAndSparseFilesAreRefusedAtOnce) {
  const TemporaryFolder folder("special");
  const fs::path fifo = folder.path / "pipe";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const fs::path sparsePly = folder.path / "sparse.ply";
  makeSparse(sparsePly);
  const fs::path sparsePoints = folder.path / "sparse.xyz";
  makeSparse(sparsePoints);
  const fs::path sparseConfig = folder.path / "sparse.cfg";
  makeSparse(sparseConfig);
  struct Case {
    std::string arguments;
    std::string needle;
  };
  const Case cases[] = {
      {"info '" + fifo.string() + "'", "FIFO"},
      {"info /dev/zero", "not a regular file"},
      {"info '" + sparsePly.string() + "'", "does not start with 'ply'"},
      {"distance builtin:box --points '" + fifo.string() + "'", "FIFO"},
      {"distance builtin:box --points /dev/zero", "not a regular file"},
      {"distance builtin:box --points '" + sparsePoints.string() + "'", "longer than 4096"},
      {"dem --config '" + fifo.string() + "'", "FIFO"},
      {"dem --config /dev/zero", "not a regular file"},
      {"dem --config '" + sparseConfig.string() + "'", "at most 1048576"},
  };
  for (const Case& c : cases) {
    const auto start = std::chrono::steady_clock::now();
    const CliRun run = runDelta(c.arguments);
    SCOPED_TRACE(c.arguments);
    expectOneLineError(run, c.needle);
    EXPECT_LT(secondsSince(start), 5.0);
  }
}

TEST(SpecialInputsCli, InfoReportsPrecisionAndAssimpFormatsAreNoted) {
  const fs::path gltf =
      fs::path(DELTA_DATA_DIR) / "assimp" / "glTF2/BoxTextured-glTF/BoxTextured.gltf";
  const fs::path off = fs::path(DELTA_DATA_DIR) / "meshes" / "fandisk.off";
  ASSERT_TRUE(fs::exists(gltf) && fs::exists(off));
  const CliRun single = runDelta("info '" + gltf.string() + "' --json");
  ASSERT_EQ(single.exitCode, 0) << single.err;
  EXPECT_NE(single.out.find("\"precision\":\"single\""), std::string::npos) << single.out;
  EXPECT_NE(single.err.find("single precision"), std::string::npos) << single.err;
  EXPECT_EQ(single.err.find('\n'), single.err.size() - 1) << "one line: " << single.err;
  const CliRun exact = runDelta("info '" + off.string() + "' --json");
  ASSERT_EQ(exact.exitCode, 0) << exact.err;
  EXPECT_NE(exact.out.find("\"precision\":\"exact\""), std::string::npos) << exact.out;
  EXPECT_TRUE(exact.err.empty()) << exact.err;
}

}  // namespace
}  // namespace delta::test
