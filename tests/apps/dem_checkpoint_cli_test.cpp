// `delta dem --checkpoint-every N`, `--restart FILE` and stopping on SIGINT/SIGTERM: a run
// stopped and continued ends bit for bit where the whole run ends (state_digest), with the same
// log rows and series.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "apps/cli_run.h"
#include "forged_checkpoint.h"

namespace {

using delta::test::CliRun;
using delta::test::expectOneLineError;
using delta::test::jsonNumber;
using delta::test::runDelta;
using delta::test::seriesFiles;
using delta::test::slurp;
using delta::test::startDelta;
using delta::test::TemporaryFolder;

/// The string after "key":" in a JSON line ("" when missing).
std::string jsonString(const std::string& json, const std::string& key) {
  const std::string marker = "\"" + key + "\":\"";
  const std::size_t at = json.find(marker);
  if (at == std::string::npos) return "";
  const std::size_t begin = at + marker.size();
  return json.substr(begin, json.find('"', begin) - begin);
}

/// log.csv's rows without the timing columns (step_seconds, contact_detection_seconds).
std::vector<std::string> logRows(const std::filesystem::path& log) {
  std::istringstream lines(slurp(log));
  std::vector<std::string> rows;
  for (std::string line; std::getline(lines, line);) {
    std::vector<std::string> fields;
    std::istringstream cells(line);
    for (std::string cell; std::getline(cells, cell, ',');)
      fields.push_back(cell);
    std::string row;
    for (std::size_t f = 0; f < fields.size(); ++f)
      if (f != 8 && f != 9) row += fields[f] + ",";
    rows.push_back(row);
  }
  return rows;
}

const std::string kSettle = "dem settle --particles 20 --output-every 50 --json --quiet";

/// kSettle's arguments for `steps` steps with a checkpoint every `every` into `out`.
std::string settleInto(const std::filesystem::path& out, int steps, int every) {
  return kSettle + " --steps " + std::to_string(steps) + " --checkpoint-every " +
         std::to_string(every) + " --out '" + out.string() + "'";
}

TEST(DemCheckpointCli, AStoppedAndRestartedRunEndsBitForBitWhereTheWholeRunEnds) {
  const TemporaryFolder folder("checkpoint_restart");
  const std::filesystem::path whole = folder.path / "whole", parts = folder.path / "parts";
  const CliRun reference = runDelta(kSettle + " --steps 400 --out '" + whole.string() + "'");
  ASSERT_EQ(reference.exitCode, 0) << reference.err;
  const std::string digest = jsonString(reference.out, "state_digest");
  EXPECT_EQ(digest.size(), 16u) << reference.out;

  const CliRun first = runDelta(settleInto(parts, 200, 100));
  ASSERT_EQ(first.exitCode, 0) << first.err;
  EXPECT_EQ(jsonNumber(first.out, "checkpoints"), 2.0) << "steps 100 and 200, the end";
  EXPECT_GT(jsonNumber(first.out, "checkpoint_bytes"), 0.0);
  ASSERT_TRUE(std::filesystem::exists(parts / "checkpoint.delta"));
  EXPECT_NE(jsonString(first.out, "state_digest"), digest);

  // --steps is the total; --out defaults to the checkpoint's folder; 2 threads now.
  const CliRun second =
      runDelta("--threads 2 dem --restart '" + (parts / "checkpoint.delta").string() +
               "' --steps 400 --json --quiet");
  ASSERT_EQ(second.exitCode, 0) << second.err;
  EXPECT_EQ(jsonNumber(second.out, "steps"), 200.0) << second.out;
  EXPECT_EQ(jsonString(second.out, "state_digest"), digest) << second.out;
  EXPECT_EQ(logRows(parts / "log.csv"), logRows(whole / "log.csv"));
  EXPECT_EQ(seriesFiles(parts / "particles_state.pvd"), seriesFiles(whole / "particles_state.pvd"));
  EXPECT_EQ(slurp(parts / "particles_state.pvd"), slurp(whole / "particles_state.pvd"));
  EXPECT_EQ(slurp(parts / "particles_state_000008.vtp"),
            slurp(whole / "particles_state_000008.vtp"));

  // Into another folder: a new series there, the same end.
  const CliRun elsewhere =
      runDelta("dem --restart '" + (parts / "checkpoint.delta").string() + "' --out '" +
               (folder.path / "elsewhere").string() + "' --steps 450 --json --quiet");
  ASSERT_EQ(elsewhere.exitCode, 0) << elsewhere.err;
  EXPECT_EQ(jsonNumber(elsewhere.out, "steps"), 50.0) << elsewhere.out;
}

TEST(DemCheckpointCli, ARestartsTotalIsTheOneItsCheckpointsCarryOn) {
  // A restart to --steps 60 wrote checkpoints that still said 20 steps (the first run's total):
  // a restart of that restart stopped at step 20, with exit 0, or refused a checkpoint beyond it.
  const TemporaryFolder folder("checkpoint_total");
  const std::filesystem::path run = folder.path / "run";
  ASSERT_EQ(runDelta(settleInto(run, 20, 10)).exitCode, 0);
  const std::string checkpoint = (run / "checkpoint.delta").string();
  const CliRun longer = runDelta("dem --restart '" + checkpoint + "' --steps 60 --json --quiet");
  ASSERT_EQ(longer.exitCode, 0) << longer.err;
  const CliRun again = runDelta("dem --restart '" + checkpoint + "' --json --quiet");
  ASSERT_EQ(again.exitCode, 0) << again.err;
  EXPECT_EQ(jsonNumber(again.out, "steps"), 0.0) << again.out;
  EXPECT_EQ(jsonString(again.out, "state_digest"), jsonString(longer.out, "state_digest"));
}

/// Every file `pvd` lists exists beside it.
void expectSeriesComplete(const std::filesystem::path& pvd) {
  const std::vector<std::string> files = seriesFiles(pvd);
  EXPECT_FALSE(files.empty()) << pvd;
  for (const std::string& file : files)
    EXPECT_TRUE(std::filesystem::exists(pvd.parent_path() / file)) << pvd << " lists " << file;
}

TEST(DemCheckpointCli, ARestartContinuesOnlyTheOutputOfItsOwnRun) {
  // A checkpoint kept aside, its folder then used by another run: the restart went on with that
  // run's log rows, frames and shapes, with exit 0. Each run's folder now names the run
  // (.delta.run), and its checkpoints carry the same identity.
  const TemporaryFolder folder("checkpoint_own_run");
  const std::filesystem::path first = folder.path / "first", second = folder.path / "second";
  ASSERT_EQ(runDelta(settleInto(first, 100, 50)).exitCode, 0);
  ASSERT_EQ(runDelta("dem two-particles --steps 150 --output-every 50 --quiet --out '" +
                     second.string() + "'")
                .exitCode,
            0);
  std::filesystem::copy_file(first / "checkpoint.delta", second / "kept.delta");
  const std::string log = slurp(second / "log.csv");
  expectOneLineError(
      runDelta("dem --restart '" + (second / "kept.delta").string() + "' --steps 200 --quiet"),
      "holds the output of another run");
  EXPECT_EQ(slurp(second / "log.csv"), log);
  // Into a new folder it goes on, and the run it continues is the first one's, bit for bit.
  const CliRun whole = runDelta(kSettle + " --steps 200");
  const CliRun moved =
      runDelta("dem --restart '" + (second / "kept.delta").string() + "' --steps 200 --out '" +
               (folder.path / "third").string() + "' --json --quiet");
  ASSERT_EQ(moved.exitCode, 0) << moved.err;
  EXPECT_EQ(jsonString(moved.out, "state_digest"), jsonString(whole.out, "state_digest"));
  expectSeriesComplete(folder.path / "third" / "particles_state.pvd");
  // A checkpoint alone in a folder starts a new series there, listing only frames that exist;
  // under the name Δ gives it too (it was refused as an earlier run's output, and the
  // --overwrite that refusal offered is refused for the checkpoint's own folder).
  for (const std::string name : {"kept.delta", "checkpoint.delta"}) {
    const std::filesystem::path alone = folder.path / ("alone_" + name);
    std::filesystem::create_directories(alone);
    std::filesystem::copy_file(first / "checkpoint.delta", alone / name);
    const CliRun fresh =
        runDelta("dem --restart '" + (alone / name).string() + "' --steps 200 --json --quiet");
    ASSERT_EQ(fresh.exitCode, 0) << name << ": " << fresh.err;
    EXPECT_EQ(jsonString(fresh.out, "state_digest"), jsonString(whole.out, "state_digest"));
    expectSeriesComplete(alone / "particles_state.pvd");
    expectSeriesComplete(alone / "contacts.pvd");
  }
  // The run's own folder is still continued, and the temporary files of its names that a run
  // killed while writing left are removed (others' stay).
  const std::filesystem::path stale = first / ".log.csv.delta-0123456789abcdef";
  const std::filesystem::path foreign = first / ".notes.txt.delta-0123456789abcdef";
  { std::ofstream(stale) << "1,2,3"; }
  { std::ofstream(foreign) << "mine"; }
  const CliRun own = runDelta("dem --restart '" + (first / "checkpoint.delta").string() +
                              "' --steps 200 --json --quiet");
  ASSERT_EQ(own.exitCode, 0) << own.err;
  EXPECT_EQ(logRows(first / "log.csv").size(), 202u);  // the header and steps 0 to 200
  expectSeriesComplete(first / "particles_state.pvd");
  EXPECT_FALSE(std::filesystem::exists(stale));
  EXPECT_TRUE(std::filesystem::exists(foreign));
}

TEST(DemCheckpointCli, ARestartTakesNoStartEnergyThatIsNotANumber) {
  // The log's first row gives energy_change its start; a log edited by hand with "nan" there
  // made every later row's energy_change NaN. The restart's own energy stands in.
  const TemporaryFolder folder("checkpoint_log_nan");
  const std::filesystem::path run = folder.path / "run";
  ASSERT_EQ(runDelta(settleInto(run, 20, 20)).exitCode, 0);
  std::string log = slurp(run / "log.csv");
  const std::size_t row = log.find('\n') + 1;  // the first row: step 0
  std::size_t column = row;
  for (int comma = 0; comma < 5; ++comma)
    column = log.find(',', column) + 1;
  log.replace(column, log.find(',', column) - column, "nan");
  { std::ofstream(run / "log.csv", std::ios::binary) << log; }
  const CliRun restarted = runDelta("dem --restart '" + (run / "checkpoint.delta").string() +
                                    "' --steps 40 --json --quiet");
  ASSERT_EQ(restarted.exitCode, 0) << restarted.err;
  EXPECT_TRUE(std::isfinite(jsonNumber(restarted.out, "energy_change"))) << restarted.out;
  const std::string last = logRows(run / "log.csv").back();
  EXPECT_EQ(last.find("nan"), std::string::npos) << last;
}

TEST(DemCheckpointCli, RefusesBadRestartsWithOneLine) {
  const TemporaryFolder folder("checkpoint_errors");
  const std::filesystem::path foreign = folder.path / "foreign.delta";
  { std::ofstream(foreign) << "solid x\n"; }
  expectOneLineError(runDelta("dem --restart '" + foreign.string() + "'"),
                     "not a Δ DEM checkpoint");
  expectOneLineError(runDelta("dem --restart '" + (folder.path / "none").string() + "'"), "none");
  expectOneLineError(runDelta("dem settle --steps 5 --checkpoint-every 2"), "--out");

  const std::filesystem::path run = folder.path / "run";
  ASSERT_EQ(runDelta(settleInto(run, 20, 10)).exitCode, 0);
  const std::string checkpoint = (run / "checkpoint.delta").string();
  expectOneLineError(runDelta("dem --restart '" + checkpoint + "' --particles 5"), "--particles");
  expectOneLineError(runDelta("dem settle --restart '" + checkpoint + "'"), "SCENARIO");
  expectOneLineError(runDelta("dem --restart '" + checkpoint + "' --steps 10"), "fewer than");
  // What a restart takes from its checkpoint is not silently replaced: --frames, and
  // --overwrite of the folder it continues.
  expectOneLineError(runDelta("dem --restart '" + checkpoint + "' --frames triangles"), "--frames");
  expectOneLineError(runDelta("dem --restart '" + checkpoint + "' --overwrite"), "--overwrite");
  std::string cut = slurp(checkpoint);
  cut.resize(cut.size() / 2);
  { std::ofstream(folder.path / "cut.delta", std::ios::binary) << cut; }
  expectOneLineError(runDelta("dem --restart '" + (folder.path / "cut.delta").string() + "'"),
                     "truncated");
  // The run's note edited, its length and the checksum made to match: a count beyond what
  // --steps takes (2^64 - 1 steps ran for ever) is refused.
  const std::string bytes = slurp(checkpoint);
  const std::size_t note = bytes.rfind("delta dem\n");
  ASSERT_NE(note, std::string::npos);
  for (const char* edited : {"steps = 18446744073709551615", "checkpoint_every = 1000000000001"}) {
    const std::string key = std::string(edited).substr(0, std::string(edited).find(' '));
    std::string text = bytes.substr(note);
    const std::size_t line = text.find("\n" + key + " = ") + 1;
    text.replace(line, text.find('\n', line) - line, edited);
    std::string forged = bytes.substr(0, note - 8);
    for (int b = 0; b < 8; ++b)
      forged += static_cast<char>((text.size() >> (8 * b)) & 0xffu);
    forged += text;
    const std::filesystem::path path = folder.path / "edited.delta";
    { std::ofstream(path, std::ios::binary) << delta::fuzz::withMatchingHeader(forged); }
    expectOneLineError(runDelta("dem --restart '" + path.string() + "' --steps 30"),
                       "not a count from 0 to 1000000000000");
  }
}

/// Stops a long run with `signal` once it has logged some steps; checks its exit code, the
/// checkpoint, and that a restart to a fixed total ends where an uninterrupted run does.
void stopAndRestart(int signal, int expectedExit) {
  const TemporaryFolder folder("checkpoint_signal_" + std::to_string(signal));
  const std::filesystem::path out = folder.path / "out";
  const pid_t pid = startDelta({"dem", "settle", "--particles", "20", "--steps", "1000000",
                                "--output-every", "50", "--quiet", "--out", out.string()},
                               folder.path);
  ASSERT_GT(pid, 0);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (logRows(out / "log.csv").size() < 30 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ::kill(pid, signal);
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
  EXPECT_EQ(WEXITSTATUS(status), expectedExit) << slurp(folder.path / "stderr");
  const std::string err = slurp(folder.path / "stderr");
  EXPECT_NE(err.find("checkpoint.delta"), std::string::npos) << err;
  // One line: no progress line was drawn (--quiet, not a terminal), so none is ended first.
  EXPECT_EQ(err.rfind("delta: stopped by ", 0), 0u) << err;
  EXPECT_EQ(err.find('\n'), err.size() - 1) << err;
  ASSERT_TRUE(std::filesystem::exists(out / "checkpoint.delta"));
  EXPECT_FALSE(std::filesystem::exists(out / ".delta.lock")) << "released on the way out";
  // Every row logged is whole, and the last one is the step the checkpoint holds.
  const std::vector<std::string> rows = logRows(out / "log.csv");
  const std::size_t stopped = std::stoul(rows.back());
  ASSERT_GT(stopped, 0u);
  const std::size_t total = stopped + 60;

  const CliRun restarted = runDelta("dem --restart '" + (out / "checkpoint.delta").string() +
                                    "' --steps " + std::to_string(total) + " --json --quiet");
  ASSERT_EQ(restarted.exitCode, 0) << restarted.err;
  const CliRun whole = runDelta(kSettle + " --steps " + std::to_string(total));
  ASSERT_EQ(whole.exitCode, 0) << whole.err;
  EXPECT_EQ(jsonString(restarted.out, "state_digest"), jsonString(whole.out, "state_digest"));
}

TEST(DemCheckpointCli, SigintFinishesTheStepWritesACheckpointAndExits130) {
  stopAndRestart(SIGINT, 130);
}

TEST(DemCheckpointCli, SigtermFinishesTheStepWritesACheckpointAndExits143) {
  stopAndRestart(SIGTERM, 143);
}

TEST(DemCheckpointCli, SighupFinishesTheStepWritesACheckpointAndExits129) {
  // A closed terminal or a dropped connection: the run was killed without a checkpoint.
  stopAndRestart(SIGHUP, 129);
}

#ifdef DELTA_MPIEXEC
/// mpirun with `ranks` ranks, as root and on more ranks than cores, one thread a rank.
std::string mpirun(int ranks) {
  return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1 '" +
         std::string(DELTA_MPIEXEC) + "' -np " + std::to_string(ranks) + " --oversubscribe";
}

TEST(DemCheckpointCli, ACheckpointOfTwoRanksRestartsOnFourAndOnOneBitForBit) {
  const TemporaryFolder folder("checkpoint_mpi");
  const std::filesystem::path parts = folder.path / "parts";
  const CliRun whole = runDelta(kSettle + " --steps 400");
  ASSERT_EQ(whole.exitCode, 0) << whole.err;
  const std::string digest = jsonString(whole.out, "state_digest");
  const CliRun first = delta::test::runDeltaUnder(mpirun(2), settleInto(parts, 200, 100));
  ASSERT_EQ(first.exitCode, 0) << first.err;
  EXPECT_EQ(jsonNumber(first.out, "checkpoints"), 2.0) << first.out;
  const std::string checkpoint = (parts / "checkpoint.delta").string();
  const CliRun onOne = runDelta("dem --restart '" + checkpoint + "' --steps 400 --out '" +
                                (folder.path / "one").string() + "' --json --quiet");
  ASSERT_EQ(onOne.exitCode, 0) << onOne.err;
  EXPECT_EQ(jsonString(onOne.out, "state_digest"), digest);
  const CliRun onFour = delta::test::runDeltaUnder(
      mpirun(4), "dem --restart '" + checkpoint + "' --steps 400 --json --quiet");
  ASSERT_EQ(onFour.exitCode, 0) << onFour.err;
  EXPECT_EQ(jsonString(onFour.out, "state_digest"), digest) << onFour.out;
  EXPECT_EQ(logRows(parts / "log.csv").size(),
            logRows(folder.path / "one" / "log.csv").size() + 200);
}

TEST(DemCheckpointCli, ASeriesGoesOnWhenTheProcessCountChanges) {
  // The earlier frames were listed in the restart's own form (.vtp in one process, .pvtp under
  // mpirun) whatever the run before wrote: the series named files that did not exist.
  const TemporaryFolder folder("checkpoint_forms");
  const std::filesystem::path ranked = folder.path / "ranked", single = folder.path / "single";
  ASSERT_EQ(delta::test::runDeltaUnder(mpirun(2), settleInto(ranked, 100, 50)).exitCode, 0);
  const CliRun onOne = runDelta("dem --restart '" + (ranked / "checkpoint.delta").string() +
                                "' --steps 200 --json --quiet");
  ASSERT_EQ(onOne.exitCode, 0) << onOne.err;
  expectSeriesComplete(ranked / "particles_state.pvd");
  expectSeriesComplete(ranked / "contacts.pvd");
  EXPECT_EQ(seriesFiles(ranked / "particles_state.pvd").size(), 5u);

  ASSERT_EQ(runDelta(settleInto(single, 100, 50)).exitCode, 0);
  const CliRun onTwo = delta::test::runDeltaUnder(
      mpirun(2),
      "dem --restart '" + (single / "checkpoint.delta").string() + "' --steps 200 --json --quiet");
  ASSERT_EQ(onTwo.exitCode, 0) << onTwo.err;
  expectSeriesComplete(single / "particles_state.pvd");
  expectSeriesComplete(single / "contacts.pvd");
  EXPECT_EQ(jsonString(onTwo.out, "state_digest"), jsonString(onOne.out, "state_digest"));
}
#endif  // DELTA_MPIEXEC

}  // namespace
