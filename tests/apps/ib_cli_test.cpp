// Runs `delta ib` as a user would: the JSON summary on a real mesh, the ParaView files of a static
// and of a moving grid, an open mesh refused for signed distances and accepted with --unsigned,
// and one line on stderr with a non-zero exit code for every bad input. Levels 3 to 5 keep each
// run under a second.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <regex>
#include <string>
#include <utility>
#include <vector>

#include "cli_run.h"
#include "io/vtk_read.h"

namespace {

namespace fs = std::filesystem;

using delta::test::CliRun;
using delta::test::expectOneLineError;
using delta::test::jsonNumber;
using delta::test::runDelta;
using delta::test::seriesFiles;
using delta::test::slurp;
using delta::test::TemporaryFolder;

std::string fandisk() {
  const std::string path = std::string(DELTA_DATA_DIR) + "/meshes/fandisk.off";
  if (!fs::exists(path)) ADD_FAILURE() << "CGAL's meshes are missing: run scripts/setup.sh";
  return path;
}

/// The numbers of the JSON array `key` (non-negative integers).
std::vector<double> jsonArray(const std::string& json, const std::string& key) {
  std::smatch match;
  const std::regex array("\"" + key + "\":\\[([0-9,]*)\\]");
  if (!std::regex_search(json, match, array)) return {};
  std::vector<double> values;
  const std::string items = match[1];
  for (std::size_t start = 0; start < items.size();) {
    const std::size_t comma = std::min(items.find(',', start), items.size());
    values.push_back(std::stod(items.substr(start, comma - start)));
    start = comma + 1;
  }
  return values;
}

/// The NumberOfCells of a .vtu file, after checking that it holds that many voxels.
double vtuCells(const fs::path& path) {
  const std::string file = slurp(path);
  std::smatch match;
  if (!std::regex_search(file, match, std::regex("NumberOfCells=\"([0-9]+)\""))) return NAN;
  const double cells = std::stod(match[1]);
  const std::vector<std::uint8_t> types = delta::test::readVtkArray<std::uint8_t>(file, "types");
  EXPECT_EQ(static_cast<double>(types.size()), cells) << path;
  EXPECT_EQ(std::count(types.begin(), types.end(), std::uint8_t{11}),
            static_cast<std::ptrdiff_t>(types.size()))
      << path << ": every cell a voxel";
  return cells;
}

TEST(IbCli, FandiskJsonCountsCellsAndQueries) {
  const CliRun run = runDelta("ib " + fandisk() + " --levels 5 --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_EQ(run.out.find('\n'), run.out.size() - 1) << "--json prints one line";
  for (const char* key :
       {"levels", "cells", "vertices", "queries", "queries_per_s", "load_s", "build_s",
        "build_queries", "steps", "step_s", "step_queries", "share_in_delta", "query_s"})
    EXPECT_FALSE(std::isnan(jsonNumber(run.out, key))) << key << " in " << run.out;
  EXPECT_NE(run.out.find("\"signed\":true"), std::string::npos) << run.out;
  EXPECT_EQ(jsonNumber(run.out, "levels"), 5.0);
  const std::vector<double> perLevel = jsonArray(run.out, "cells_per_level");
  ASSERT_EQ(perLevel.size(), 6u) << run.out;
  EXPECT_EQ(std::accumulate(perLevel.begin(), perLevel.end(), 0.0), jsonNumber(run.out, "cells"));
  EXPECT_GT(perLevel.back(), 0.0) << "the finest cells line the boundary";
  const double vertices = jsonNumber(run.out, "vertices");
  EXPECT_GT(vertices, 8.0);
  EXPECT_GE(jsonNumber(run.out, "queries"), vertices);
  EXPECT_EQ(jsonNumber(run.out, "build_queries"), jsonNumber(run.out, "queries"));
  EXPECT_GT(jsonNumber(run.out, "queries_per_s"), 0.0);
  EXPECT_EQ(jsonNumber(run.out, "steps"), 0.0);
  EXPECT_EQ(jsonNumber(run.out, "step_s"), 0.0);
  const double share = jsonNumber(run.out, "share_in_delta");
  EXPECT_GT(share, 0.0);
  EXPECT_LE(share, 1.0);
}

TEST(IbCli, TextSummaryAndStaticFiles) {
  const TemporaryFolder folder("ib_static");
  const fs::path out = folder.path / "made" / "here";
  const CliRun run = runDelta("ib builtin:icosphere:2 --levels 4 --out '" + out.string() + "'");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("leaf cells per level:"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("queries/s"), std::string::npos) << run.out;
  EXPECT_GT(vtuCells(out / "grid.vtu"), 0.0);
  EXPECT_TRUE(fs::exists(out / "boundary.vtp"));
  EXPECT_FALSE(fs::exists(out / "grid.pvd")) << "a static grid is one file";
  const std::string grid = slurp(out / "grid.vtu");
  for (const char* array : {"Name=\"signed_distance\"", "Name=\"error_bound\"", "Name=\"level\""})
    EXPECT_NE(grid.find(array), std::string::npos) << array;
  EXPECT_EQ(grid.find("compressor="), std::string::npos) << "raw unless --compression";

  // --compression 1: the same arrays, compressed, the values as they were.
  const fs::path compressed = folder.path / "compressed";
  ASSERT_EQ(runDelta("ib builtin:icosphere:2 --levels 4 --compression 1 --quiet --out '" +
                     compressed.string() + "'")
                .exitCode,
            0);
  const std::string small = slurp(compressed / "grid.vtu");
  EXPECT_NE(small.find("compressor=\"vtkZLibDataCompressor\""), std::string::npos);
  EXPECT_LT(small.size(), grid.size() / 2);
  EXPECT_EQ(delta::test::readVtkArray<double>(small, "signed_distance"),
            delta::test::readVtkArray<double>(grid, "signed_distance"));
  EXPECT_EQ(delta::test::readVtkArray<std::uint8_t>(small, "level"),
            delta::test::readVtkArray<std::uint8_t>(grid, "level"));
  EXPECT_EQ(delta::test::readVtkArray<std::int32_t>(small, "connectivity"),
            delta::test::readVtkArray<std::int32_t>(grid, "connectivity"));
  EXPECT_EQ(vtuCells(compressed / "grid.vtu"), vtuCells(out / "grid.vtu"));
}

TEST(IbCli, MovingBoundaryWritesASeries) {
  const TemporaryFolder folder("ib_moving");
  const CliRun run = runDelta("ib " + fandisk() +
                              " --levels 4 --steps 3 --rotate 0,0,1,10 --translate 0.01,0,0 "
                              "--json --out '" +
                              folder.path.string() + "'");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_EQ(jsonNumber(run.out, "steps"), 3.0);
  EXPECT_GT(jsonNumber(run.out, "step_s"), 0.0);
  EXPECT_GE(jsonNumber(run.out, "queries"), jsonNumber(run.out, "build_queries"));
  const std::vector<std::string> grids = seriesFiles(folder.path / "grid.pvd");
  const std::vector<std::string> boundaries = seriesFiles(folder.path / "boundary.pvd");
  ASSERT_EQ(grids.size(), 4u);
  ASSERT_EQ(boundaries.size(), 4u);
  for (int step = 0; step < 4; ++step) {
    const std::string number = "00000" + std::to_string(step);
    EXPECT_EQ(grids[step], "grid_" + number + ".vtu");
    EXPECT_EQ(boundaries[step], "boundary_" + number + ".vtp");
    EXPECT_TRUE(fs::exists(folder.path / boundaries[step])) << boundaries[step];
    EXPECT_GT(vtuCells(folder.path / grids[step]), 0.0) << grids[step];
  }
  EXPECT_NE(slurp(folder.path / "grid.pvd").find("timestep=\"3\""), std::string::npos);
  EXPECT_EQ(vtuCells(folder.path / grids.back()), jsonNumber(run.out, "cells"))
      << "the last file is the grid the summary counts";
}

TEST(IbCli, AnEarlierRunsOutputIsRefusedUnlessOverwrite) {
  // A static run into a folder that held a moving run's series left its grid.pvd beside the new
  // grid.vtu: ParaView opened the old grid. The folder is now refused unless --overwrite, which
  // removes only `delta ib`'s files.
  const TemporaryFolder folder("ib_earlier");
  const std::string out = " --out '" + folder.path.string() + "'";
  ASSERT_EQ(runDelta("ib builtin:icosphere:2 --levels 3 --steps 2 --quiet" + out).exitCode, 0);
  { std::ofstream(folder.path / "notes.txt") << "mine\n"; }
  const std::string pvd = slurp(folder.path / "grid.pvd");
  expectOneLineError(runDelta("ib builtin:icosphere:2 --levels 3 --quiet" + out),
                     "holds the output of an earlier run (boundary.pvd");
  EXPECT_EQ(slurp(folder.path / "grid.pvd"), pvd);
  EXPECT_FALSE(fs::exists(folder.path / "grid.vtu"));
  const CliRun again = runDelta("ib builtin:icosphere:2 --levels 3 --quiet --overwrite" + out);
  ASSERT_EQ(again.exitCode, 0) << again.err;
  EXPECT_TRUE(fs::exists(folder.path / "grid.vtu"));
  EXPECT_TRUE(fs::exists(folder.path / "boundary.vtp"));
  for (const char* earlier : {"grid.pvd", "boundary.pvd", "grid_000000.vtu", "boundary_000002.vtp"})
    EXPECT_FALSE(fs::exists(folder.path / earlier)) << earlier;
  EXPECT_EQ(slurp(folder.path / "notes.txt"), "mine\n");
  EXPECT_FALSE(fs::exists(folder.path / ".delta.lock")) << "released at the end";
}

TEST(IbCli, OpenMeshNeedsUnsigned) {
  const TemporaryFolder folder("ib_open");
  const fs::path open = folder.path / "open box.off";
  // A unit cube without its top face: ten triangles, four boundary edges.
  std::ofstream(open) << "OFF\n8 10 0\n"
                         "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
                         "3 0 2 1\n3 0 3 2\n"   // bottom
                         "3 0 1 5\n3 0 5 4\n"   // front
                         "3 1 2 6\n3 1 6 5\n"   // right
                         "3 2 3 7\n3 2 7 6\n"   // back
                         "3 3 0 4\n3 3 4 7\n";  // left
  const CliRun refused = runDelta("ib '" + open.string() + "' --levels 3");
  expectOneLineError(refused, "--unsigned");
  EXPECT_NE(refused.err.find(open.string()), std::string::npos) << refused.err;
  EXPECT_NE(refused.err.find("not closed"), std::string::npos) << refused.err;
  const CliRun accepted = runDelta("ib '" + open.string() + "' --levels 3 --unsigned --json");
  ASSERT_EQ(accepted.exitCode, 0) << accepted.err;
  EXPECT_NE(accepted.out.find("\"signed\":false"), std::string::npos) << accepted.out;
  EXPECT_GT(jsonNumber(accepted.out, "cells"), 0.0);
}

TEST(IbCli, HasHelp) {
  const CliRun run = runDelta("ib --help");
  EXPECT_EQ(run.exitCode, 0);
  for (const char* text : {"Usage", "--levels", "--unsigned", "--rotate", "grid.pvd"})
    EXPECT_NE(run.out.find(text), std::string::npos) << text << " in " << run.out;
}

TEST(IbCli, RejectsBadInputAndWritesNothing) {
  const TemporaryFolder folder("ib_bad");
  const fs::path out = folder.path / "out";
  const std::string box = "ib builtin:box --levels 3 --out '" + out.string() + "' ";
  const std::pair<const char*, const char*> cases[] = {
      {"--levels 0", "--levels"},
      {"--levels 21", "--levels"},
      {"--refine-factor 0", "--refine-factor"},
      {"--refine-factor -1", "--refine-factor"},
      {"--refine-factor nan", "--refine-factor"},
      {"--padding -0.5", "--padding"},
      {"--exact-band -1", "--exact-band"},
      {"--steps=-1", "--steps"},
      {"--steps 1 --rotate 0,0,1", "--rotate"},
      {"--steps 1 --rotate 0,0,0,10", "--rotate"},
      {"--steps 1 --rotate 0,0,1,inf", "--rotate"},
      {"--steps 1 --translate 1,2", "--translate"},
      {"--steps 1 --translate 1,x,2", "--translate"},
      {"--rotate 0,0,1,10", "--steps"},
      {"--compression 10", "--compression"},
      {"--compression -1", "--compression"},
  };
  for (const auto& [arguments, needle] : cases) {
    expectOneLineError(runDelta(box + arguments), needle);
    EXPECT_FALSE(fs::exists(out)) << arguments;
  }
  expectOneLineError(runDelta("ib /nonexistent/mesh.off --levels 3"), "/nonexistent/mesh.off");
  std::ofstream(out) << "a file, not a folder";
  expectOneLineError(runDelta(box), out.string());
}

}  // namespace
