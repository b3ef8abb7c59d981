// `delta dem` under mpirun (built where CMake found MPI): the same run for 1, 2 and 4 ranks as
// for one process, a ParaView series of one piece per rank, the per-rank summary, and bad
// input reported once.
#ifdef DELTA_MPIEXEC

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_run.h"

namespace delta::test {
namespace {

/// mpirun with `ranks` ranks, as root and on more ranks than cores, one thread a rank.
std::string mpirun(int ranks) {
  return "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1 '" +
         std::string(DELTA_MPIEXEC) + "' -np " + std::to_string(ranks) + " --oversubscribe";
}

/// The columns of log.csv after the header, row by row.
std::vector<std::vector<double>> logRows(const std::filesystem::path& csv) {
  std::istringstream text(slurp(csv));
  std::string line;
  std::getline(text, line);  // header
  std::vector<std::vector<double>> rows;
  while (std::getline(text, line)) {
    std::vector<double> row;
    std::istringstream cells(line);
    std::string cell;
    while (std::getline(cells, cell, ','))
      row.push_back(std::stod(cell));
    rows.push_back(row);
  }
  return rows;
}

TEST(DemMpiCli, SettleRunsTheSameOnOneTwoAndFourRanks) {
  const std::string arguments = "dem settle --steps 3000 --json --quiet";
  const CliRun serial = runDeltaUnder("OMP_NUM_THREADS=1", arguments);
  ASSERT_EQ(serial.exitCode, 0) << serial.err;
  ASSERT_GT(jsonNumber(serial.out, "contacts_per_step"), 0.5);  // contacts happen
  for (const int ranks : {1, 2, 4}) {
    const CliRun run = runDeltaUnder(mpirun(ranks), arguments);
    ASSERT_EQ(run.exitCode, 0) << run.err;
    EXPECT_EQ(jsonNumber(run.out, "ranks"), ranks);
    // Contact counts, depths and times are the one process's exactly: the trajectories are.
    for (const char* key : {"particles", "steps", "time", "contacts_per_step", "max_contacts",
                            "contact_pairs_per_step", "max_depth_ratio"})
      EXPECT_EQ(jsonNumber(run.out, key), jsonNumber(serial.out, key)) << key << ", " << ranks;
    // One load a rank, and every particle owned by one rank.
    const std::regex load(
        "\"rank\":[0-9]+,\"particles\":([0-9]+),\"ghosts\":([0-9]+),"
        "\"neighbours\":[0-9]+");
    double owned = 0.0, ghosts = 0.0;
    int loads = 0;
    for (auto it = std::sregex_iterator(run.out.begin(), run.out.end(), load);
         it != std::sregex_iterator(); ++it, ++loads) {
      owned += std::stod((*it)[1]);
      ghosts += std::stod((*it)[2]);
    }
    EXPECT_EQ(loads, ranks);
    EXPECT_EQ(owned, 100.0);
    if (ranks > 1) {
      EXPECT_GT(ghosts, 0.0);
    }
  }
}

TEST(DemMpiCli, TwoParticlesSplitOverTwoRanksMeasureTheSameRestitution) {
  const std::string arguments = "dem two-particles --restitution 0.5 --json --quiet";
  const CliRun serial = runDelta(arguments);
  const CliRun split = runDeltaUnder(mpirun(2), arguments);
  ASSERT_EQ(serial.exitCode, 0) << serial.err;
  ASSERT_EQ(split.exitCode, 0) << split.err;
  EXPECT_NEAR(jsonNumber(split.out, "restitution"), 0.5, 0.02);
  EXPECT_EQ(jsonNumber(split.out, "restitution"), jsonNumber(serial.out, "restitution"));
  EXPECT_NEAR(jsonNumber(split.out, "energy_change"), jsonNumber(serial.out, "energy_change"),
              1e-12);
  // Each particle on its own rank: both ranks own one.
  EXPECT_NE(split.out.find("\"rank\":0,\"particles\":1,"), std::string::npos) << split.out;
  EXPECT_NE(split.out.find("\"rank\":1,\"particles\":1,"), std::string::npos) << split.out;
}

TEST(DemMpiCli, WritesOnePieceARankJoinedInAParallelSeries) {
  const TemporaryFolder one("mpi_one"), two("mpi_two");
  const std::string arguments = "dem settle --steps 2000 --output-every 1000 --quiet --out ";
  ASSERT_EQ(runDeltaUnder("OMP_NUM_THREADS=1", arguments + "'" + one.path.string() + "'").exitCode,
            0);
  const CliRun run = runDeltaUnder(mpirun(2), arguments + "'" + two.path.string() + "'");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  for (const char* series : {"particles_state", "contacts"}) {
    const std::vector<std::string> frames = seriesFiles(two.path / (std::string(series) + ".pvd"));
    ASSERT_EQ(frames.size(), 3u) << series;  // the start and two frames
    for (std::size_t f = 0; f < frames.size(); ++f) {
      EXPECT_EQ(frames[f], std::string(series) + "_00000" + std::to_string(f) + ".pvtp");
      const std::string joined = slurp(two.path / frames[f]);
      EXPECT_NE(joined.find("PPolyData"), std::string::npos);
      for (int rank = 0; rank < 2; ++rank) {
        const std::string piece = std::string(series) + "_00000" + std::to_string(f) + "_" +
                                  std::to_string(rank) + ".vtp";
        EXPECT_NE(joined.find("Source=\"" + piece + "\""), std::string::npos) << joined;
        EXPECT_TRUE(std::filesystem::is_regular_file(two.path / piece)) << piece;
      }
    }
  }
  EXPECT_TRUE(std::filesystem::is_regular_file(two.path / "obstacles.vtp"));
  EXPECT_TRUE(std::filesystem::is_regular_file(two.path / "shape_0.vtp"));
  // log.csv: the one process's rows, energies to round-off (sums over ranks in another order).
  const std::vector<std::vector<double>> expected = logRows(one.path / "log.csv");
  const std::vector<std::vector<double>> rows = logRows(two.path / "log.csv");
  ASSERT_EQ(rows.size(), 2001u);
  ASSERT_EQ(rows.size(), expected.size());
  for (std::size_t r = 0; r < rows.size(); ++r)
    for (std::size_t c = 0; c < 8; ++c)  // step … contact_pairs; not the timings
      EXPECT_NEAR(rows[r][c], expected[r][c], 1e-12 * (1.0 + std::fabs(expected[r][c])))
          << "row " << r << " column " << c;
}

TEST(DemMpiCli, ReportsBadInputOnceAndFails) {
  const CliRun run = runDeltaUnder(mpirun(2), "dem settle --particles 0 --quiet");
  EXPECT_NE(run.exitCode, 0);
  EXPECT_TRUE(run.out.empty()) << run.out;
  // One line from delta (mpirun may add its own notice that a rank failed).
  std::size_t lines = 0;
  for (std::size_t at = run.err.find("delta: "); at != std::string::npos;
       at = run.err.find("delta: ", at + 1))
    ++lines;
  EXPECT_EQ(lines, 1u) << run.err;
}

}  // namespace
}  // namespace delta::test

#endif  // DELTA_MPIEXEC
