// `--sign winding` of `delta distance` and `delta ib`, and `delta info`'s self-intersections
// (issue 22), on CGAL's meshes: ChineseDragon-10kv (open), camel (closed, crossing itself).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "apps/cli_run.h"

namespace delta::test {
namespace {

namespace fs = std::filesystem;

const fs::path kMeshes = fs::path(DELTA_DATA_DIR) / "meshes";

TEST(WindingCli, InfoReportsSelfIntersections) {
  if (!fs::exists(kMeshes / "camel.off")) GTEST_SKIP() << "no data/meshes";
  const CliRun camel = runDelta("info --json " + quoted(kMeshes / "camel.off"));
  ASSERT_EQ(camel.exitCode, 0) << camel.err;
  EXPECT_EQ(jsonNumber(camel.out, "self_intersections"), 20.0) << camel.out;
  const CliRun text = runDelta("info " + quoted(kMeshes / "armadillo.off"));
  ASSERT_EQ(text.exitCode, 0) << text.err;
  EXPECT_NE(text.out.find("self-intersections   0\n"), std::string::npos) << text.out;
}

TEST(WindingCli, MisorientedPartsAreReportedRefusedByPseudonormalsAndSignedByWindingNumber) {
  // Two cubes, ±2 and ±1, both outward: the inner one is a shell inside a shell of the same
  // orientation (winding number 2 inside it), not a cavity.
  const TemporaryFolder folder("misoriented");
  const fs::path off = folder.path / "shells.off";
  {
    std::ofstream file(off);
    file << "OFF\n16 24 0\n";
    for (const int size : {2, 1})
      for (int i = 0; i < 8; ++i)
        file << (i & 1 ? size : -size) << ' ' << (i & 2 ? size : -size) << ' '
             << (i & 4 ? size : -size) << '\n';
    const int faces[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                              {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
    for (const int offset : {0, 8})
      for (const auto& f : faces)
        file << "3 " << f[0] + offset << ' ' << f[1] + offset << ' ' << f[2] + offset << '\n';
  }
  const CliRun info = runDelta("info --json " + quoted(off));
  ASSERT_EQ(info.exitCode, 0) << info.err;
  EXPECT_EQ(jsonNumber(info.out, "parts"), 2.0) << info.out;
  EXPECT_EQ(jsonNumber(info.out, "misoriented_parts"), 1.0) << info.out;
  const CliRun text = runDelta("info " + quoted(off));
  ASSERT_EQ(text.exitCode, 0) << text.err;
  EXPECT_NE(text.out.find("parts                2 (1 misoriented, 0 flat, 0 undecided), 0 pinched"),
            std::string::npos)
      << text.out;
  EXPECT_NE(text.out.find("bounds a solid       no"), std::string::npos) << text.out;
  EXPECT_EQ(jsonNumber(info.out, "pinched_vertices"), 0.0) << info.out;
  EXPECT_NE(info.out.find("\"bounds_solid\":false"), std::string::npos) << info.out;
  expectOneLineError(runDelta("distance " + quoted(off) + " --points builtin:uniform:10 --signed"),
                     "1 of its 2 parts is oriented against");
  const fs::path csv = folder.path / "signs.csv";
  const CliRun run = runDelta("distance " + quoted(off) +
                              " --points builtin:uniform:10 --sign winding --out " + quoted(csv));
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_TRUE(fs::exists(csv));
}

TEST(WindingCli, DistanceSignsOpenAndCrossingMeshes) {
  if (!fs::exists(kMeshes / "camel.off")) GTEST_SKIP() << "no data/meshes";
  const std::string dragon = quoted(kMeshes / "ChineseDragon-10kv.off");
  const std::string camel = quoted(kMeshes / "camel.off");
  expectOneLineError(runDelta("distance " + dragon + " --points builtin:uniform:10 --signed"),
                     "--sign winding");
  expectOneLineError(runDelta("distance " + camel + " --points builtin:uniform:10 --signed"),
                     "crosses itself (20 pairs");
  expectOneLineError(runDelta("distance " + camel + " --points builtin:uniform:10 --sign ray"),
                     "--sign 'ray'");
  const TemporaryFolder folder("winding");
  const fs::path csv = folder.path / "signs.csv";
  const CliRun run =
      runDelta("distance " + dragon +
               " --points builtin:uniform:2000 --sign winding --json --out " + quoted(csv));
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_GT(jsonNumber(run.out, "inside"), 0.0) << run.out;
  EXPECT_GE(jsonNumber(run.out, "ambiguous"), 0.0) << run.out;
  const std::string rows = slurp(csv);
  EXPECT_EQ(
      rows.rfind("index,distance,closest_x,closest_y,closest_z,triangle,inside,ambiguous\n", 0), 0u)
      << rows.substr(0, 100);
  EXPECT_TRUE(rows.ends_with(",0\n") || rows.ends_with(",1\n"));
}

TEST(WindingCli, IbAcceptsAnOpenMeshWithTheWindingSign) {
  if (!fs::exists(kMeshes / "ChineseDragon-10kv.off")) GTEST_SKIP() << "no data/meshes";
  const std::string dragon = quoted(kMeshes / "ChineseDragon-10kv.off");
  expectOneLineError(runDelta("ib " + dragon + " --levels 3"), "--sign winding");
  const CliRun run = runDelta("ib " + dragon + " --levels 4 --sign winding --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("\"sign\":\"winding\""), std::string::npos) << run.out;
  EXPECT_GT(jsonNumber(run.out, "cells"), 0.0);
}

}  // namespace
}  // namespace delta::test
