// `delta dem --out`: a folder valid at any instant (kill -9 included), one run at a time in it,
// no silent mixing with an earlier run; and the summary's energy change and warnings.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_run.h"

namespace {

namespace fs = std::filesystem;

using delta::test::CliRun;
using delta::test::expectOneLineError;
using delta::test::jsonNumber;
using delta::test::quoted;
using delta::test::runDelta;
using delta::test::seriesFiles;
using delta::test::slurp;
using delta::test::TemporaryFolder;

/// Every .pvd in `folder` is a whole VTKFile listing only complete frames; log.csv ends on a
/// whole row of the header's column count.
void expectValidFolder(const fs::path& folder, const std::string& when) {
  for (const fs::directory_entry& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() != ".pvd") continue;
    const std::string pvd = slurp(entry.path());
    EXPECT_NE(pvd.find("<Collection>"), std::string::npos) << when << entry.path();
    EXPECT_NE(pvd.find("</Collection>\n</VTKFile>"), std::string::npos) << when << entry.path();
    for (const std::string& file : seriesFiles(entry.path())) {
      const std::string frame = slurp(folder / file);
      ASSERT_GE(frame.size(), 12u) << when << file;
      EXPECT_EQ(frame.substr(frame.size() - 11), "</VTKFile>\n") << when << file;
    }
  }
  if (!fs::exists(folder / "log.csv")) return;
  std::ifstream log(folder / "log.csv");
  const std::string text = slurp(folder / "log.csv");
  ASSERT_FALSE(text.empty()) << when;
  EXPECT_EQ(text.back(), '\n') << when;
  std::string line;
  std::getline(log, line);
  const auto columns = [](const std::string& row) {
    return std::count(row.begin(), row.end(), ',') + 1;
  };
  const auto header = columns(line);
  EXPECT_EQ(line.substr(line.rfind(',') + 1), "energy_change");
  for (std::size_t row = 1; std::getline(log, line); ++row)
    ASSERT_EQ(columns(line), header) << when << " row " << row << ": " << line;
}

TEST(DemOutputSafety, KilledRunsLeaveValidFolders) {
  std::mt19937 random(23);
  std::uniform_int_distribution<int> milliseconds(200, 1500);
  for (int run = 0; run < 5; ++run) {
    const TemporaryFolder out("killed_" + std::to_string(run));
    const int wait = milliseconds(random);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      const int null = ::open("/dev/null", O_WRONLY);
      ::dup2(null, 1);
      ::dup2(null, 2);
      ::execl(DELTA_CLI, DELTA_CLI, "dem", "settle", "--particles", "27", "--steps", "100000",
              "--output-every", "1", "--frames", "both", "--quiet", "--out", out.path.c_str(),
              static_cast<char*>(nullptr));
      ::_exit(127);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(wait));
    ::kill(child, SIGKILL);
    int status = 0;
    ::waitpid(child, &status, 0);
    ASSERT_TRUE(WIFSIGNALED(status)) << "the run ended before " << wait << " ms";
    expectValidFolder(out.path, "killed after " + std::to_string(wait) + " ms: ");
    // The lock of the killed run is taken over by the next (a note), which refuses the earlier
    // output where the killed run had written any.
    const bool wrote = fs::exists(out.path / "log.csv");
    const CliRun next =
        runDelta("dem settle --particles 8 --steps 2 --quiet --out " + quoted(out.path));
    EXPECT_NE(next.err.find("took over the lock file of delta dem"), std::string::npos) << next.err;
    if (wrote) {
      EXPECT_EQ(next.exitCode, 1) << next.err;
      EXPECT_NE(next.err.find("--overwrite replaces it"), std::string::npos) << next.err;
    }
  }
}

TEST(DemOutputSafety, ASecondRunIntoAFolderInUseIsRefused) {
  const TemporaryFolder out("in_use");
  const int lock = ::open((out.path / ".delta.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(lock, 0);
  ASSERT_EQ(::flock(lock, LOCK_EX | LOCK_NB), 0);
  const std::string holder = "4242 somehost delta dem\n";
  ASSERT_EQ(::write(lock, holder.data(), holder.size()), static_cast<ssize_t>(holder.size()));
  expectOneLineError(runDelta("dem settle --particles 8 --steps 2 --out " + quoted(out.path)),
                     "is in use by delta dem, pid 4242 on somehost");
  ::close(lock);  // as if that run ended
  const CliRun after =
      runDelta("dem settle --particles 8 --steps 2 --quiet --out " + quoted(out.path));
  EXPECT_EQ(after.exitCode, 0) << after.err;
  EXPECT_NE(after.err.find("took over the lock file of delta dem, pid 4242"), std::string::npos)
      << after.err;
  EXPECT_FALSE(fs::exists(out.path / ".delta.lock"));  // removed at the end
}

TEST(DemOutputSafety, AnEarlierRunIsRefusedUnlessOverwrite) {
  const TemporaryFolder out("earlier");
  const std::string run = "dem settle --particles 8 --steps 4 --output-every 1 --quiet --out ";
  ASSERT_EQ(runDelta(run + quoted(out.path)).exitCode, 0);
  { std::ofstream(out.path / "notes.txt") << "mine\n"; }
  expectOneLineError(
      runDelta("dem settle --particles 8 --steps 2 --quiet --out " + quoted(out.path)),
      "holds the output of an earlier run (contacts.pvd");
  EXPECT_EQ(seriesFiles(out.path / "contacts.pvd").size(), 5u);  // untouched
  const CliRun again =
      runDelta("dem settle --particles 8 --steps 2 --output-every 1 --quiet --overwrite --out " +
               quoted(out.path));
  ASSERT_EQ(again.exitCode, 0) << again.err;
  EXPECT_EQ(seriesFiles(out.path / "contacts.pvd").size(), 3u);
  EXPECT_FALSE(fs::exists(out.path / "contacts_000004.vtp"));  // the earlier run's, removed
  EXPECT_EQ(slurp(out.path / "notes.txt"), "mine\n");          // not Δ's: kept
}

TEST(DemOutputSafety, ReportsTheEnergyChangeAndNoWarnings) {
  const TemporaryFolder out("energy");
  const CliRun run =
      runDelta("dem settle --particles 8 --steps 50 --restitution 1 --friction 0 --json --out " +
               quoted(out.path));
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_TRUE(run.err.empty()) << run.err;
  EXPECT_NE(run.out.find("\"warnings\":[]"), std::string::npos) << run.out;
  const double absolute = jsonNumber(run.out, "energy_change_absolute");
  ASSERT_TRUE(std::isfinite(absolute)) << run.out;
  EXPECT_TRUE(std::isfinite(jsonNumber(run.out, "energy_change"))) << run.out;
  // log.csv's last energy_change is the summary's.
  const std::string log = slurp(out.path / "log.csv");
  const std::string last = log.substr(log.rfind('\n', log.size() - 2) + 1);
  EXPECT_DOUBLE_EQ(std::stod(last.substr(last.rfind(',') + 1)), absolute);
  expectValidFolder(out.path, "");
}

TEST(DemOutputSafety, ParticleRadiusScalesTheShellWithTheParticle) {
  // ε and h are fractions of the particle size: a micrometre particle rebounds as a centimetre
  // one does (it once kept ε and rebounded 529 radii apart).
  const std::string run = "dem two-particles --particle-mesh builtin:icosphere:2 --json";
  const CliRun large = runDelta(run);
  const CliRun tiny = runDelta(run + " --particle-radius 1e-6");
  ASSERT_EQ(large.exitCode, 0) << large.err;
  ASSERT_EQ(tiny.exitCode, 0) << tiny.err;
  EXPECT_NEAR(jsonNumber(tiny.out, "restitution"), jsonNumber(large.out, "restitution"), 1e-3)
      << tiny.out;
  EXPECT_NEAR(jsonNumber(tiny.out, "steps"), jsonNumber(large.out, "steps"), 1.0);  // rounding
  EXPECT_NE(tiny.out.find("\"warnings\":[]"), std::string::npos) << tiny.out;
}

}  // namespace
