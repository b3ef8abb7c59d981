// Runs the `delta` executable as a user would and checks the command-line contract: results on
// stdout, one line on stderr and a non-zero exit code for every error, never a crash.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/version.h"
#include "delta/mesh/primitives.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"

#include "cli_run.h"
#include "io/vtk_read.h"

namespace {

using delta::test::CliRun;
using delta::test::expectOneLineError;
using delta::test::runDelta;
using delta::test::slurp;
using delta::test::TemporaryFolder;

std::string dataPath(const std::string& relative) {
  return std::string(DELTA_DATA_DIR) + "/" + relative;
}

TEST(DeltaCli, PrintsVersionAndCommit) {
  const CliRun run = runDelta("--version");
  EXPECT_EQ(run.exitCode, 0);
  EXPECT_NE(run.out.find(delta::version()), std::string::npos) << run.out;
  EXPECT_NE(run.out.find(delta::gitCommit()), std::string::npos) << run.out;
}

TEST(DeltaCli, InfoOnArmadilloMatchesTheDataSet) {
  if (!std::filesystem::exists(dataPath("meshes/armadillo.off")))
    GTEST_FAIL() << "CGAL's meshes are missing from " << DELTA_DATA_DIR << ": run scripts/setup.sh";
  const CliRun run = runDelta("info --json " + dataPath("meshes/armadillo.off"));
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NE(run.out.find("\"triangles\":52000,"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("\"vertices\":26002,"), std::string::npos) << run.out;
  for (const char* key : {"degenerate_triangles", "bounds", "bounding_sphere", "area", "volume",
                          "closed", "mesh_size", "load_s", "peak_memory_bytes"})
    EXPECT_NE(run.out.find(std::string("\"") + key + "\":"), std::string::npos) << key;
  EXPECT_EQ(run.out.back(), '\n');
  EXPECT_EQ(run.out.find('\n'), run.out.size() - 1) << "--json prints one line";
}

TEST(DeltaCli, InfoOnBuiltInPrimitives) {
  const CliRun box = runDelta("info --json builtin:box");
  ASSERT_EQ(box.exitCode, 0) << box.err;
  EXPECT_NE(box.out.find("\"triangles\":12,"), std::string::npos) << box.out;
  EXPECT_NE(box.out.find("\"volume\":1,"), std::string::npos) << box.out;
  EXPECT_NE(box.out.find("\"closed\":true,"), std::string::npos) << box.out;
  const CliRun quad = runDelta("info --json builtin:quad");
  ASSERT_EQ(quad.exitCode, 0) << quad.err;
  EXPECT_NE(quad.out.find("\"volume\":null,"), std::string::npos) << quad.out;
  EXPECT_NE(quad.out.find("\"closed\":false,"), std::string::npos) << quad.out;
  const CliRun text = runDelta("info builtin:icosphere:3");
  ASSERT_EQ(text.exitCode, 0) << text.err;
  EXPECT_NE(text.out.find("triangles            1280 (0 degenerate)"), std::string::npos)
      << text.out;
}

TEST(DeltaCli, ErrorsAreOneLineAndNonZero) {
  expectOneLineError(runDelta("info /nonexistent/mesh.off"), "/nonexistent/mesh.off");
  expectOneLineError(runDelta("info " + std::string(DELTA_DATA_DIR)), DELTA_DATA_DIR);
  expectOneLineError(runDelta("info builtin:teapot"), "builtin:teapot");
  expectOneLineError(runDelta("info builtin:icosphere:x"), "builtin:icosphere:x");
  expectOneLineError(runDelta("info builtin:icosphere:99"), "");
  expectOneLineError(runDelta("info"), "MESH");
  expectOneLineError(runDelta("frobnicate"), "frobnicate");
  expectOneLineError(runDelta(""), "subcommand");
  expectOneLineError(runDelta("--threads 0 info builtin:box"), "--threads");
}

TEST(DeltaCli, EveryCommandHasHelp) {
  for (const char* command : {"--help", "info --help"}) {
    const CliRun run = runDelta(command);
    EXPECT_EQ(run.exitCode, 0) << command;
    EXPECT_NE(run.out.find("Usage"), std::string::npos) << command << ": " << run.out;
  }
}

TEST(DeltaCli, BenchKernelsJsonHasEverySolver) {
  const CliRun run = runDelta("bench kernels --pairs 400 --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_EQ(run.out.find('\n'), run.out.size() - 1) << "--json prints one line";
  EXPECT_NE(run.out.find("\"pairs\":400,"), std::string::npos) << run.out;
  for (const char* key :
       {"\"solvers\":{", "\"bruteforce\":{", "\"penalty\":{", "\"hybrid\":{",
        "\"pairs_per_s\":", "\"max_rel_error\":", "\"fallback_rate\":", "\"isa\":\""})
    EXPECT_NE(run.out.find(key), std::string::npos) << key << " in " << run.out;
  EXPECT_EQ(run.out.find("\"fcl\""), std::string::npos) << "FCL stays out of the CLI";
}

TEST(DeltaCli, BenchKernelsPrintsATable) {
  const CliRun run = runDelta("bench kernels --pairs 300");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  for (const char* solver : {"bruteforce", "penalty", "hybrid", "pairs/s"})
    EXPECT_NE(run.out.find(solver), std::string::npos) << solver << " in " << run.out;
}

TEST(DeltaCli, BenchKernelsChoosesTheIsa) {
  const CliRun scalar = runDelta("bench kernels --pairs 100 --json --isa scalar");
  ASSERT_EQ(scalar.exitCode, 0) << scalar.err;
  EXPECT_NE(scalar.out.find("\"isa\":\"scalar\""), std::string::npos) << scalar.out;
  ::setenv("DELTA_ISA", "scalar", 1);  // the override the kernels read once per process
  const CliRun fromEnvironment = runDelta("bench kernels --pairs 100 --json");
  ::unsetenv("DELTA_ISA");
  ASSERT_EQ(fromEnvironment.exitCode, 0) << fromEnvironment.err;
  EXPECT_NE(fromEnvironment.out.find("\"isa\":\"scalar\""), std::string::npos)
      << fromEnvironment.out;
}

TEST(DeltaCli, BenchKernelsRejectsBadInput) {
  expectOneLineError(runDelta("bench kernels --pairs 0"), "--pairs");
  expectOneLineError(runDelta("bench kernels --pairs -5"), "--pairs");
  expectOneLineError(runDelta("bench kernels --pairs many"), "--pairs");
  expectOneLineError(runDelta("bench kernels --pairs 99999999999"), "--pairs");
  expectOneLineError(runDelta("bench kernels --isa avx1024"), "avx1024");
  expectOneLineError(runDelta("bench"), "kernels");
  expectOneLineError(runDelta("bench frobnicate"), "frobnicate");
  // Refused before the benchmark runs (expectOneLineError: nothing on stdout).
  expectOneLineError(runDelta("bench kernels --pairs 100 extra"), "'extra'");
  for (const char* command : {"bench --help", "bench kernels --help"}) {
    const CliRun run = runDelta(command);
    EXPECT_EQ(run.exitCode, 0) << command;
    EXPECT_NE(run.out.find("Usage"), std::string::npos) << command << ": " << run.out;
  }
}

}  // namespace

namespace {

TEST(DeltaCli, ContactWithoutEpsilonGivesTheMinimumDistance) {
  const CliRun run =
      runDelta("contact builtin:box builtin:box --translate-b 1.5,0,0 --rotate-b 0,0,1,90 --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  const std::size_t at = run.out.find("\"min_distance\":");
  ASSERT_NE(at, std::string::npos) << run.out;
  EXPECT_NEAR(std::stod(run.out.substr(at + 15)), 0.5, 1e-12) << run.out;  // the turn rounds
  for (const char* key : {"triangle_a", "triangle_b", "load_s", "build_s", "query_s"})
    EXPECT_NE(run.out.find(std::string("\"") + key + "\":"), std::string::npos) << key;
}

TEST(DeltaCli, ContactWritesSortedCsvRows) {
  const std::string csv = (std::filesystem::temp_directory_path() /
                           ("delta_cli_contacts_" + std::to_string(::getpid()) + ".csv"))
                              .string();
  const CliRun run = runDelta(
      "contact builtin:icosphere:2 builtin:icosphere:2 "
      "--translate-b 1.9,0,0 --eps 0.1 --json --out " +
      csv);
  ASSERT_EQ(run.exitCode, 0) << run.err;
  std::ifstream file(csv);
  std::string header, line;
  std::getline(file, header);
  EXPECT_EQ(header,
            "triangle_a,triangle_b,x,y,z,normal_x,normal_y,normal_z,distance,overlap,converged");
  std::vector<std::pair<long, long>> ids;
  while (std::getline(file, line)) {
    long a = -1, b = -1;
    ASSERT_EQ(std::sscanf(line.c_str(), "%ld,%ld,", &a, &b), 2) << line;
    ids.emplace_back(a, b);
  }
  std::filesystem::remove(csv);
  ASSERT_FALSE(ids.empty());
  EXPECT_TRUE(std::is_sorted(ids.begin(), ids.end()));
  EXPECT_NE(run.out.find("\"contacts\":" + std::to_string(ids.size()) + ","), std::string::npos)
      << run.out;
}

TEST(DeltaCli, ContactRejectsBadInputAndWritesNothing) {
  const std::string csv = (std::filesystem::temp_directory_path() /
                           ("delta_cli_bad_" + std::to_string(::getpid()) + ".csv"))
                              .string();
  for (const std::string arguments :
       {"--eps 0", "--eps -1", "--eps nan", "--eps 0.1 --filter 0", "--translate-b 1,2",
        "--rotate-b 0,0,0,30", "--eps 0.1 --method newton", "--filter 0.1"}) {
    expectOneLineError(runDelta("contact builtin:box builtin:box --out " + csv + " " + arguments),
                       "");
    EXPECT_FALSE(std::filesystem::exists(csv)) << arguments;
  }
  expectOneLineError(runDelta("contact builtin:box /nonexistent.off --eps 0.1"),
                     "/nonexistent.off");
  expectOneLineError(runDelta("contact builtin:box builtin:box --eps 0.1 --out a.txt"), "a.txt");
}

/// A file in the temporary folder, named for this process, removed when it goes out of scope.
struct TemporaryFile {
  explicit TemporaryFile(const std::string& name)
      : path((std::filesystem::temp_directory_path() /
              ("delta_cli_" + std::to_string(::getpid()) + "_" + name))
                 .string()) {}
  ~TemporaryFile() { std::filesystem::remove(path); }
  void write(const std::string& text) const { std::ofstream(path) << text; }
  std::string path;
};

std::vector<std::string> lines(const std::string& path) {
  std::ifstream file(path);
  std::vector<std::string> all;
  for (std::string line; std::getline(file, line);)
    all.push_back(line);
  return all;
}

TEST(DeltaCli, AnOutputThatIsAnInputIsRefusedAndTheInputKept) {
  // The readers tell formats by content, so an input may be named .csv or .vtp: --out naming it
  // (or a link to it) replaced it with the output.
  const TemporaryFolder folder("out_is_input");
  const std::string mesh = (folder.path / "mesh.csv").string();
  const std::string points = (folder.path / "points.csv").string();
  const std::string link = (folder.path / "link.vtp").string();
  std::filesystem::copy_file(std::string(DELTA_DATA_DIR) + "/meshes/fandisk.off", mesh);
  { std::ofstream(points) << "0 0 0\n1 1 1\n"; }
  std::filesystem::create_symlink(points, link);
  const std::string meshBefore = slurp(mesh), pointsBefore = slurp(points);
  expectOneLineError(runDelta("contact " + mesh + " builtin:box --eps 0.1 --out " + mesh),
                     "is the input");
  const std::string solid = (folder.path / "box.vtp").string();
  std::filesystem::copy_file(std::string(DELTA_DATA_DIR) + "/meshes/fandisk.off", solid);
  expectOneLineError(runDelta("overlap builtin:box " + solid + " --out " + solid), "is the input");
  EXPECT_EQ(slurp(solid), meshBefore);
  expectOneLineError(runDelta("distance builtin:box --points " + points + " --out " + link),
                     "is the input");
  expectOneLineError(runDelta("distance " + mesh + " --points " + points + " --out " + mesh),
                     "is the input");
  EXPECT_EQ(slurp(mesh), meshBefore);
  EXPECT_EQ(slurp(points), pointsBefore);
  // Another name in the same folder is written.
  const CliRun run = runDelta("distance builtin:box --points " + points + " --out " +
                              (folder.path / "d.csv").string());
  EXPECT_EQ(run.exitCode, 0) << run.err;
}

TEST(DeltaCli, DistanceWritesOneRowPerPointInInputOrder) {
  // builtin:box is the unit cube centred at the origin: faces at ±0.5.
  const TemporaryFile points("points.xyz"), csv("distances.csv");
  points.write("# x y z\n0 0 2\n0 0 0\n\n0.5 0.5 0.5\n0.3 0 0.25\n");
  const CliRun run = runDelta("distance builtin:box --points " + points.path +
                              " --signed --json --out " + csv.path);
  ASSERT_EQ(run.exitCode, 0) << run.err;
  const std::vector<std::string> rows = lines(csv.path);
  ASSERT_EQ(rows.size(), 5u);
  EXPECT_EQ(rows[0], "index,distance,closest_x,closest_y,closest_z,triangle,inside");
  double expected[][2] = {{1.5, 0}, {0.5, 1}, {0, 0}, {0.2, 1}};
  for (std::size_t i = 0; i < 4; ++i) {
    unsigned index = 99, triangle = 99, inside = 9;
    double distance = -1, x, y, z;
    ASSERT_EQ(std::sscanf(rows[i + 1].c_str(), "%u,%lf,%lf,%lf,%lf,%u,%u", &index, &distance, &x,
                          &y, &z, &triangle, &inside),
              7)
        << rows[i + 1];
    EXPECT_EQ(index, i);
    EXPECT_NEAR(distance, expected[i][0], 1e-15) << rows[i + 1];
    EXPECT_EQ(inside, expected[i][1]) << rows[i + 1];
    EXPECT_LT(triangle, 12u);
  }
  EXPECT_NE(run.out.find("\"points\":4,"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("\"inside\":2,"), std::string::npos) << run.out;
  for (const char* key : {"\"load_s\":", "\"build_s\":", "\"query_s\":"})
    EXPECT_NE(run.out.find(key), std::string::npos) << key << run.out;
}

TEST(DeltaCli, DistanceWithEpsilonLeavesFarPointsEmpty) {
  const TemporaryFile points("near.xyz"), csv("near.csv"), vtp("near.vtp");
  points.write("0 0 0.6\n0 0 3\n");
  const CliRun run = runDelta("distance builtin:box --points " + points.path +
                              " --eps 0.25 --json --out " + csv.path);
  ASSERT_EQ(run.exitCode, 0) << run.err;
  const std::vector<std::string> rows = lines(csv.path);
  ASSERT_EQ(rows.size(), 3u);
  EXPECT_EQ(rows[0], "index,distance,closest_x,closest_y,closest_z,triangle");
  EXPECT_EQ(rows[1].rfind("0,0.0999", 0), 0u) << rows[1];
  EXPECT_EQ(rows[2], "1,,,,,");
  EXPECT_NE(run.out.find("\"within\":1,"), std::string::npos) << run.out;
  const CliRun paraview =
      runDelta("distance builtin:icosphere:2 --points builtin:uniform:50 --out " + vtp.path);
  ASSERT_EQ(paraview.exitCode, 0) << paraview.err;
  const std::string xml = slurp(vtp.path);
  EXPECT_NE(xml.find("<VTKFile type=\"PolyData\""), std::string::npos);
  EXPECT_NE(xml.find("NumberOfPoints=\"50\""), std::string::npos);
  EXPECT_NE(xml.find("Name=\"distance\""), std::string::npos);
}

TEST(DeltaCli, DistanceOfManyPointsInSeveralCallsGivesEachPointItsAnswer) {
  // More points than the command's first library call takes (2¹⁶), so that it makes several
  // calls of growing size: with and without ε, every row is the library's answer to the whole
  // set in one call.
  const TemporaryFile csv("many.csv"), vtp("many.vtp");
  const delta::Mesh mesh = delta::primitives::icosphere(3);
  const delta::QueryMesh query(mesh);
  constexpr std::size_t kCount = 150000;
  // builtin:uniform:N:SEED (apps/delta/point_source.cpp): the box grown by a tenth a side.
  std::mt19937_64 random(7);
  const auto unit = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53; };
  const delta::Aabb box = mesh.bounds();
  const delta::Vec3 lower = box.lower - box.extent() * 0.1, size = box.extent() * 1.2;
  std::vector<delta::Vec3> points(kCount);
  for (delta::Vec3& p : points)
    p = {lower.x + size.x * unit(), lower.y + size.y * unit(), lower.z + size.z * unit()};
  for (const char* epsilon : {"", "0.05"}) {
    const std::string withEpsilon = *epsilon ? std::string(" --eps ") + epsilon : "";
    const CliRun run = runDelta("distance builtin:icosphere:3 --points builtin:uniform:150000:7" +
                                withEpsilon + " --quiet --out " + csv.path);
    ASSERT_EQ(run.exitCode, 0) << run.err;
    const std::vector<delta::contactdetection::PointDistance> expected =
        delta::contactdetection::distances(
            query, points,
            {.epsilon = *epsilon ? std::stod(epsilon) : std::numeric_limits<double>::infinity()});
    const std::vector<std::string> rows = lines(csv.path);
    ASSERT_EQ(rows.size(), kCount + 1);
    std::size_t found = 0;
    for (std::size_t i = 0; i < kCount; ++i) {
      const std::string& row = rows[i + 1];
      if (!expected[i].found()) {
        ASSERT_EQ(row, std::to_string(i) + ",,,,,") << withEpsilon;
        continue;
      }
      ++found;
      unsigned index = 0, triangle = 0;
      double distance = -1, x, y, z;
      ASSERT_EQ(std::sscanf(row.c_str(), "%u,%lf,%lf,%lf,%lf,%u", &index, &distance, &x, &y, &z,
                            &triangle),
                6)
          << row;
      ASSERT_EQ(index, i) << row;
      ASSERT_EQ(distance, expected[i].distance) << row;
      ASSERT_EQ(triangle, expected[i].triangle) << row;
      ASSERT_EQ((delta::Vec3{x, y, z}), expected[i].closest) << row;
    }
    EXPECT_GT(found, kCount / 20) << withEpsilon;
    // The same calls into ParaView's file and the summary: each column bit for bit, and the
    // count and extremes of all the calls together.
    const CliRun paraview =
        runDelta("distance builtin:icosphere:3 --points builtin:uniform:150000:7" + withEpsilon +
                 " --json --out " + vtp.path);
    ASSERT_EQ(paraview.exitCode, 0) << paraview.err;
    const std::string file = slurp(vtp.path);
    const std::vector<double> distance = delta::test::readVtkArray<double>(file, "distance");
    const std::vector<double> closest = delta::test::readVtkArray<double>(file, "closest");
    const std::vector<std::int64_t> triangle =
        delta::test::readVtkArray<std::int64_t>(file, "triangle");
    ASSERT_EQ(distance.size(), kCount);
    ASSERT_EQ(closest.size(), 3 * kCount);
    ASSERT_EQ(triangle.size(), kCount);
    double nearest = std::numeric_limits<double>::infinity(), farthest = -nearest;
    for (std::size_t i = 0; i < kCount; ++i) {
      const delta::contactdetection::PointDistance& a = expected[i];
      if (!a.found()) {
        ASSERT_TRUE(std::isnan(distance[i]) && std::isnan(closest[3 * i])) << i;
        ASSERT_EQ(triangle[i], -1) << i;
        continue;
      }
      nearest = std::min(nearest, a.distance);
      farthest = std::max(farthest, a.distance);
      ASSERT_EQ(distance[i], a.distance) << i;
      ASSERT_EQ((delta::Vec3{closest[3 * i], closest[3 * i + 1], closest[3 * i + 2]}), a.closest)
          << i;
      ASSERT_EQ(triangle[i], static_cast<std::int64_t>(a.triangle)) << i;
    }
    const auto number = [&paraview](const std::string& key) {
      const std::size_t at = paraview.out.find("\"" + key + "\":");
      EXPECT_NE(at, std::string::npos) << key << paraview.out;
      return at == std::string::npos
                 ? std::nan("")
                 : std::strtod(paraview.out.c_str() + at + key.size() + 3, nullptr);
    };
    EXPECT_EQ(number("min_distance"), nearest) << paraview.out;
    EXPECT_EQ(number("max_distance"), farthest) << paraview.out;
    if (*epsilon) {
      EXPECT_EQ(number("within"), static_cast<double>(found)) << paraview.out;
    }
  }
}

TEST(DeltaCli, DistanceNamesAPointBeyondTheRangeByItsLine) {
  // Past the first library call's 2¹⁶ points: the query named it by its index in the second
  // call (point 4464); the reader names its line, and no output is written.
  const TemporaryFile points("late.xyz"), csv("late.csv"), vtp("late.vtp");
  std::string text;
  for (int i = 0; i < 70000; ++i)
    text += std::to_string(i % 7 * 0.25) + " 0.5 " + std::to_string(i % 11 * 0.1) + "\n";
  text += "1e250 0 0\n";
  points.write(text);
  for (const std::string* out : {&csv.path, &vtp.path}) {
    expectOneLineError(
        runDelta("distance builtin:box --quiet --points " + points.path + " --out " + *out),
        "line 70001 has a coordinate beyond ±2^200");
    EXPECT_FALSE(std::filesystem::exists(*out)) << *out;
  }
}

TEST(DeltaCli, DistanceRejectsBadInputAndWritesNothing) {
  const TemporaryFile points("bad.xyz"), empty("empty.xyz"), csv("bad.csv");
  points.write("0 0 0\n1 1 1\n1 2 x\n");
  empty.write("# nothing\n");
  const std::string good = "distance builtin:box --points builtin:uniform:10 --out " + csv.path;
  for (const std::string arguments : {" --eps 0", " --eps -1", " --eps nan", " --eps inf"}) {
    expectOneLineError(runDelta(good + arguments), "--eps");
    EXPECT_FALSE(std::filesystem::exists(csv.path)) << arguments;
  }
  expectOneLineError(
      runDelta("distance builtin:box --out " + csv.path + " --points " + points.path), "line 3");
  expectOneLineError(runDelta("distance builtin:box --out " + csv.path + " --points " + empty.path),
                     empty.path);
  expectOneLineError(
      runDelta("distance builtin:quad --signed --out " + csv.path + " --points builtin:uniform:10"),
      "not closed");
  expectOneLineError(runDelta("distance builtin:box --points builtin:uniform:0 --out " + csv.path),
                     "builtin:uniform:0");
  expectOneLineError(runDelta("distance builtin:box --points builtin:grid:3"), "builtin:grid:3");
  EXPECT_FALSE(std::filesystem::exists(csv.path));
  expectOneLineError(runDelta("distance builtin:box --points builtin:uniform:5 --out a.txt"),
                     "a.txt");
  expectOneLineError(runDelta("distance builtin:box"), "--points");
}

}  // namespace
