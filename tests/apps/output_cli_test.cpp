// What `delta` writes is complete or reported: standard output checked before exit, every file
// written whole or not at all (io/atomic_file.h), a symlink at --out kept.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "delta/core/contact_point.h"
#include "delta/mesh/primitives.h"
#include "delta/query/contacts.h"

#include "apps/cli_run.h"
#include "io/test_files.h"

namespace delta::test {
namespace {

namespace fs = std::filesystem;
using io::namesIn;

/// A shell prefix that simulates a full disk for the command after it: writes past `kilobytes`
/// fail with EFBIG (SIGXFSZ ignored). The limit also applies to the captured streams, which stay
/// far below it.
std::string fullDiskAfter(int kilobytes) {
  return "trap '' XFSZ; ulimit -f " + std::to_string(2 * kilobytes) + ";";
}

/// Runs `delta ARGUMENTS` with standard output sent to /dev/full; stderr captured.
CliRun runIntoDevFull(const std::string& arguments) {
  const TemporaryFolder streams("devfull");
  const std::string command = std::string("'") + DELTA_CLI + "' " + arguments + " >/dev/full 2>'" +
                              (streams.path / "err").string() + "'";
  const int status = std::system(command.c_str());
  CliRun run;
  run.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  run.err = slurp(streams.path / "err");
  return run;
}

TEST(DeltaCliOutput, AFullStandardOutputIsAnError) {
  for (const std::string arguments :
       {"info builtin:box", "info builtin:box --json", "--version", "info --help",
        "contact builtin:box builtin:box --translate-b 2,0,0",
        "distance builtin:box --points builtin:uniform:10 --quiet"}) {
    const CliRun run = runIntoDevFull(arguments);
    expectOneLineError(run, "cannot write to standard output: No space left on device");
    EXPECT_EQ(run.exitCode, 1) << arguments;
  }
}

TEST(DeltaCliOutput, AFailedCsvOrVtpLeavesThePreviousFile) {
  const TemporaryFolder folder("full_out");
  const std::string contact =
      "contact builtin:icosphere:4 builtin:icosphere:4 --translate-b 1.95,0,0 --eps 0.05 --out ";
  const std::string distance = "distance builtin:icosphere:3 --points builtin:uniform:20000 --out ";
  for (const std::string& command : {contact, distance}) {
    for (const char* name : {"out.csv", "out.vtp"}) {
      const fs::path out = folder.path / name;
      { std::ofstream(out) << "previous\n"; }
      const CliRun run = runDeltaUnder(fullDiskAfter(16), command + "'" + out.string() + "'");
      expectOneLineError(run, "cannot write '" + out.string() + "': File too large");
      EXPECT_EQ(slurp(out), "previous\n") << command << name;
      // Without the limit the same command writes the file whole.
      const CliRun written = runDelta(command + "'" + out.string() + "'");
      ASSERT_EQ(written.exitCode, 0) << written.err;
      EXPECT_GT(fs::file_size(out), 16u * 1024u) << command << name;
      fs::remove(out);
    }
  }
  EXPECT_TRUE(namesIn(folder.path).empty()) << "a temporary file was left behind";
}

TEST(DeltaCliOutput, ASymlinkAtOutIsKeptAndItsTargetUpdated) {
  const TemporaryFolder folder("symlink_out");
  fs::create_directories(folder.path / "results");
  const fs::path target = folder.path / "results" / "contacts.csv";
  { std::ofstream(target) << "previous\n"; }
  const fs::path link = folder.path / "latest.csv";
  fs::create_symlink(target, link);
  const CliRun run =
      runDelta("contact builtin:box builtin:box --translate-b 1.05,0,0 --eps 0.05 --out '" +
               link.string() + "'");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_TRUE(fs::is_symlink(link));
  EXPECT_EQ(fs::read_symlink(link), target);
  const std::string written = slurp(target);
  EXPECT_EQ(written.rfind("triangle_a,triangle_b,", 0), 0u) << written;
  EXPECT_EQ(namesIn(folder.path / "results"), std::vector<std::string>{"contacts.csv"});
  // A write that fails through the link (a full disk) keeps the link and the target's content
  // (the VTK writer used to remove the path, the link itself, after a failed write).
  const fs::path vtpTarget = folder.path / "results" / "contacts.vtp";
  { std::ofstream(vtpTarget) << "previous\n"; }
  const fs::path vtpLink = folder.path / "latest.vtp";
  fs::create_symlink(vtpTarget, vtpLink);
  const CliRun failed = runDeltaUnder(
      fullDiskAfter(16),
      "contact builtin:icosphere:4 builtin:icosphere:4 --translate-b 1.95,0,0 --eps 0.05 --out '" +
          vtpLink.string() + "'");
  expectOneLineError(failed, "File too large");
  EXPECT_TRUE(fs::is_symlink(vtpLink));
  EXPECT_EQ(slurp(vtpTarget), "previous\n");
}

TEST(DeltaCliOutput, IbAndDemOutputFailuresAreErrors) {
  const TemporaryFolder folder("full_series");
  const CliRun ib =
      runDeltaUnder(fullDiskAfter(64), "ib builtin:icosphere:2 --levels 6 --quiet --out '" +
                                           (folder.path / "ib").string() + "'");
  expectOneLineError(ib, "File too large");
  EXPECT_NE(ib.err.find("cannot write '" + (folder.path / "ib").string()), std::string::npos)
      << ib.err;
  const CliRun dem =
      runDeltaUnder(fullDiskAfter(1), "dem settle --particles 8 --steps 10 --quiet --out '" +
                                          (folder.path / "dem").string() + "'");
  expectOneLineError(dem, "File too large");
  EXPECT_NE(dem.err.find((folder.path / "dem").string()), std::string::npos) << dem.err;
  // log.csv, flushed every row: a full disk stops the run at the row that does not fit, with
  // the reason (it was noticed only at the end, without one), and the rows before it are there.
  const std::string log = (folder.path / "log" / "log.csv").string();
  const CliRun logged = runDeltaUnder(
      fullDiskAfter(256), "dem two-particles --steps 6000 --output-every 100000 --quiet --out '" +
                              (folder.path / "log").string() + "'");
  expectOneLineError(logged, "writing '" + log + "' failed: File too large");
  EXPECT_EQ(slurp(log).rfind("step,time,", 0), 0u);
  EXPECT_GT(fs::file_size(log), 200000u);
  for (const char* sub : {"ib", "dem", "log"})
    for (const std::string& name : namesIn(folder.path / sub))
      EXPECT_EQ(name.find(".delta-"), std::string::npos) << "left behind: " << name;
}

/// The `converged` column of `delta contact --out FILE.csv`: the library's flag, row by row.
std::vector<int> convergedColumn(const std::string& csv) {
  std::ifstream file(csv);
  std::string line;
  std::getline(file, line);
  EXPECT_EQ(line.substr(line.rfind(',') + 1), "converged");
  std::vector<int> column;
  while (std::getline(file, line))
    column.push_back(std::stoi(line.substr(line.rfind(',') + 1)));
  return column;
}

TEST(DeltaCliOutput, ContactCsvCarriesThePenaltySolversConvergedFlag) {
  const TemporaryFolder folder("converged");
  const std::string csv = (folder.path / "contacts.csv").string();
  // Two spheres pushed into each other: among the crossing pairs, several that the penalty
  // solver does not certify.
  const std::string meshes =
      "contact builtin:icosphere:2 builtin:icosphere:2 --eps 0.05 --out '" + csv + "' ";
  const CliRun penalty = runDelta(meshes + "--translate-b 1,0.1,0 --method penalty");
  ASSERT_EQ(penalty.exitCode, 0) << penalty.err;
  const std::vector<int> column = convergedColumn(csv);
  Mesh a = primitives::icosphere(2), b = primitives::icosphere(2);
  b.translate({1, 0.1, 0});
  const std::vector<ContactPoint> expected =
      contactdetection::contacts(QueryMesh(a), QueryMesh(b), 0.05, kernels::Solver::Penalty);
  ASSERT_EQ(column.size(), expected.size());
  for (std::size_t i = 0; i < column.size(); ++i)
    EXPECT_EQ(column[i], expected[i].converged ? 1 : 0) << "row " << i;
  EXPECT_NE(std::count(column.begin(), column.end(), 0), 0) << "no unconverged pair to show";
  EXPECT_NE(std::count(column.begin(), column.end(), 1), 0);
  const CliRun hybrid = runDelta(meshes + "--translate-b 1,0.1,0");
  ASSERT_EQ(hybrid.exitCode, 0) << hybrid.err;
  const std::vector<int> exact = convergedColumn(csv);
  EXPECT_FALSE(exact.empty());
  EXPECT_EQ(std::count(exact.begin(), exact.end(), 1), static_cast<long>(exact.size()));
}

TEST(DeltaCliOutput, ContactCsvRowsReadBackToTheLibrarysValues) {
  // More rows than one thread formats at a time (kCsvRowsPerChunk, apps/delta/csv.h), each
  // number in its shortest form: every one reads back to the library's bits.
  const TemporaryFolder folder("contact_rows");
  const std::string csv = (folder.path / "contacts.csv").string();
  const CliRun run = runDelta(
      "contact builtin:icosphere:4 builtin:icosphere:4 --translate-b 1.3,0.2,0.1 --eps 0.02 "
      "--out '" +
      csv + "'");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  Mesh a = primitives::icosphere(4), b = primitives::icosphere(4);
  b.translate({1.3, 0.2, 0.1});
  const std::vector<ContactPoint> expected =
      contactdetection::contacts(QueryMesh(a), QueryMesh(b), 0.02);
  ASSERT_GT(expected.size(), 2048u);
  std::ifstream file(csv);
  std::string line;
  std::getline(file, line);
  std::size_t rows = 0;
  for (; std::getline(file, line); ++rows) {
    ASSERT_LT(rows, expected.size());
    const ContactPoint& c = expected[rows];
    unsigned first = 0, second = 0;
    int overlap = -1, converged = -1;
    Vec3 x, normal;
    double distance = -1.0;
    ASSERT_EQ(
        std::sscanf(line.c_str(), "%u,%u,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%d,%d", &first, &second, &x.x,
                    &x.y, &x.z, &normal.x, &normal.y, &normal.z, &distance, &overlap, &converged),
        11)
        << line;
    ASSERT_EQ(first, c.first) << line;
    ASSERT_EQ(second, c.second) << line;
    ASSERT_EQ(x, c.x) << line;
    ASSERT_EQ(normal, c.normal) << line;
    ASSERT_EQ(distance, c.distance) << line;
    ASSERT_EQ(overlap, c.overlap ? 1 : 0) << line;
    ASSERT_EQ(converged, c.converged ? 1 : 0) << line;
  }
  EXPECT_EQ(rows, expected.size());
}

TEST(DeltaCliOutput, AStoppedRunLeavesThePreviousFileAndNoTemporaryOne) {
  // Stopped by SIGTERM (a batch system's time limit), SIGINT or SIGHUP while `delta distance`
  // writes its rows, the run ends by the signal as before, but its temporary file goes with it
  // (it was left behind, as large as it had got).
  for (const int signal : {SIGTERM, SIGINT, SIGHUP}) {
    const TemporaryFolder folder("stopped_" + std::to_string(signal));
    const fs::path csv = folder.path / "d.csv";
    { std::ofstream(csv) << "previous\n"; }
    const pid_t pid =
        startDelta({"distance", "builtin:icosphere:4", "--points", "builtin:uniform:4000000",
                    "--quiet", "--threads", "1", "--out", csv.string()},
                   folder.path);
    ASSERT_GT(pid, 0);
    const auto temporary = [&folder] {
      for (const auto& entry : fs::directory_iterator(folder.path))
        if (entry.path().filename().string().starts_with(".d.csv.delta-")) return true;
      return false;
    };
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!temporary() && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    ASSERT_TRUE(temporary()) << "the run made no temporary file";
    ::kill(pid, signal);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << "not stopped by the signal: exit " << WEXITSTATUS(status);
    EXPECT_EQ(WTERMSIG(status), signal);
    EXPECT_FALSE(temporary()) << "signal " << signal;
    EXPECT_EQ(slurp(csv), "previous\n");
  }
}

}  // namespace
}  // namespace delta::test
