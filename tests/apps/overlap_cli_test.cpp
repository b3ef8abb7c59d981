// `delta overlap MESH_A MESH_B` (issue 24) as a user runs it: the volume two closed meshes share,
// its integrals and its curves, in text, JSON and a .vtp file; and the contract's error rule.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "cli_run.h"
#include "io/vtk_read.h"

namespace {

namespace fs = std::filesystem;

using delta::test::CliRun;
using delta::test::expectOneLineError;
using delta::test::jsonNumber;
using delta::test::runDelta;
using delta::test::slurp;
using delta::test::TemporaryFolder;

/// The three numbers of `"key":[x,y,z]` in a JSON line; NaNs when missing.
std::array<double, 3> jsonVector(const std::string& json, const std::string& key) {
  std::array<double, 3> v{NAN, NAN, NAN};
  const std::string marker = "\"" + key + "\":[";
  const std::size_t at = json.find(marker);
  if (at == std::string::npos) return v;
  const char* next = json.c_str() + at + marker.size();
  for (double& value : v) {
    char* end = nullptr;
    value = std::strtod(next, &end);
    if (end == next) return {NAN, NAN, NAN};
    next = end + 1;  // past the comma
  }
  return v;
}

void expectVector(const std::array<double, 3>& got, const std::array<double, 3>& want,
                  double tolerance, const std::string& what) {
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(got[i], want[i], tolerance) << what << " component " << i;
}

/// An OFF file of unit cubes centred at `centers`, one closed component each (outward-facing
/// triangles).
fs::path cubesFile(const TemporaryFolder& folder, const std::string& name,
                   const std::vector<std::array<double, 3>>& centers) {
  const fs::path path = folder.path / name;
  std::ofstream off(path);
  off << "OFF\n" << 8 * centers.size() << ' ' << 12 * centers.size() << " 0\n";
  for (const std::array<double, 3>& center : centers)
    for (int corner = 0; corner < 8; ++corner)
      off << center[0] + ((corner & 1) ? 0.5 : -0.5) << ' '
          << center[1] + ((corner & 2) ? 0.5 : -0.5) << ' '
          << center[2] + ((corner & 4) ? 0.5 : -0.5) << '\n';
  // Corner c = x + 2y + 4z; each face as two triangles, counter-clockwise seen from outside.
  constexpr int kTriangles[12][3] = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6},   // z
                                     {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},   // y
                                     {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};  // x
  for (std::size_t cube = 0; cube < centers.size(); ++cube)
    for (const auto& triangle : kTriangles)
      off << "3 " << 8 * cube + triangle[0] << ' ' << 8 * cube + triangle[1] << ' '
          << 8 * cube + triangle[2] << '\n';
  return path;
}

// A = [-0.5, 0.5]^3 and B = A + (0.5, 0.25, 0.125) share the box [0, 0.5] x [-0.25, 0.5] x
// [-0.375, 0.5]: its volume and centroid; ∂A inside B is A's three upper faces' parts in it; the
// curve is the closed hexagon of the box edges where a face of A meets a face of B.
constexpr double kCubesVolume = 0.5 * 0.75 * 0.875;
const std::string kOffsetCubes = "overlap builtin:box builtin:box --translate-b 0.5,0.25,0.125";

TEST(OverlapCli, TwoOffsetCubesShareTheBoxOfTheirIntersection) {
  const CliRun run = runDelta(kOffsetCubes + " --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_TRUE(run.err.empty()) << run.err;
  EXPECT_EQ(run.out.find('\n'), run.out.size() - 1) << "--json prints one line";
  EXPECT_EQ(run.out.front(), '{');
  EXPECT_EQ(run.out[run.out.size() - 2], '}');
  for (const char* never : {"nan", "inf", "null"})
    EXPECT_EQ(run.out.find(never), std::string::npos) << never << " in " << run.out;
  EXPECT_NEAR(jsonNumber(run.out, "volume"), kCubesVolume, 1e-14);
  expectVector(jsonVector(run.out, "centroid"), {0.25, 0.125, 0.0625}, 1e-14, "centroid");
  expectVector(jsonVector(run.out, "area_vector"), {0.75 * 0.875, 0.5 * 0.875, 0.5 * 0.75}, 1e-14,
               "area_vector");
  expectVector(jsonVector(run.out, "area_vector_b"), {-0.75 * 0.875, -0.5 * 0.875, -0.5 * 0.75},
               1e-14, "area_vector_b");
  EXPECT_NEAR(jsonNumber(run.out, "curve_length"), 2 * (0.5 + 0.75 + 0.875), 1e-13);
  EXPECT_EQ(jsonNumber(run.out, "curves"), 1.0);
  EXPECT_GE(jsonNumber(run.out, "segments"), 6.0);
  EXPECT_EQ(jsonNumber(run.out, "touching"), 0.0);
  for (const char* phase : {"load_s", "build_s", "query_s"})
    EXPECT_GE(jsonNumber(run.out, phase), 0.0) << phase;
  // One region, with the same integrals as the total.
  const std::size_t regions = run.out.find("\"regions\":[{");
  ASSERT_NE(regions, std::string::npos) << run.out;
  EXPECT_EQ(run.out.find("\"regions\":[", regions + 1), std::string::npos);
  const std::string region = run.out.substr(regions, run.out.find('}', regions) - regions + 1);
  EXPECT_NEAR(jsonNumber(region, "volume"), kCubesVolume, 1e-14) << region;
  expectVector(jsonVector(region, "centroid"), {0.25, 0.125, 0.0625}, 1e-14, "region centroid");
  for (const char* key : {"area_vector", "area_vector_b", "moment"})
    EXPECT_TRUE(std::isfinite(jsonVector(region, key)[0])) << key << " in " << region;
  EXPECT_NEAR(jsonNumber(region, "curve_length"), 4.25, 1e-13);
  EXPECT_GT(jsonNumber(region, "triangles"), 0.0);
}

TEST(OverlapCli, PrintsTextByDefaultAndNothingWithQuiet) {
  const CliRun text = runDelta(kOffsetCubes);
  ASSERT_EQ(text.exitCode, 0) << text.err;
  const std::size_t at = text.out.find("overlap volume ");
  ASSERT_NE(at, std::string::npos) << text.out;
  EXPECT_NEAR(std::strtod(text.out.c_str() + at + 15, nullptr), kCubesVolume, 1e-14);
  for (const char* part : {"in 1 region", "centroid (", "1 intersection curve", "load "})
    EXPECT_NE(text.out.find(part), std::string::npos) << part << " in " << text.out;
  const CliRun quiet = runDelta(kOffsetCubes + " --quiet");
  EXPECT_EQ(quiet.exitCode, 0) << quiet.err;
  EXPECT_TRUE(quiet.out.empty()) << quiet.out;
}

TEST(OverlapCli, HasHelpAndIsListed) {
  const CliRun help = runDelta("overlap --help");
  EXPECT_EQ(help.exitCode, 0) << help.err;
  for (const char* part : {"Usage", "MESH_A", "--translate-b", "--rotate-b", "--out", "--json"})
    EXPECT_NE(help.out.find(part), std::string::npos) << part << " in " << help.out;
  EXPECT_NE(runDelta("--help").out.find("overlap"), std::string::npos);
}

TEST(OverlapCli, ApartMeshesShareNothing) {
  const CliRun run = runDelta("overlap builtin:box builtin:icosphere:2 --translate-b 3,0,0 --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_EQ(jsonNumber(run.out, "volume"), 0.0);
  EXPECT_NE(run.out.find("\"regions\":[]"), std::string::npos) << run.out;
  EXPECT_EQ(jsonNumber(run.out, "curves"), 0.0);
  EXPECT_EQ(run.out.find("nan"), std::string::npos) << run.out;
  const CliRun text = runDelta("overlap builtin:box builtin:box --translate-b 3,0,0");
  ASSERT_EQ(text.exitCode, 0) << text.err;
  EXPECT_NE(text.out.find("no overlap"), std::string::npos) << text.out;
}

// --rotate-b turns B about the centre of its box, not the origin: a cube centred at (10, 0, 0)
// turned 45° about z and brought to (0, 0, 0.25) meets A in a regular octagon (apothem 1/2) 0.75
// high.
TEST(OverlapCli, RotatesBAboutTheCentreOfItsBoxThenTranslates) {
  const TemporaryFolder folder("overlap_rotate");
  const fs::path far = cubesFile(folder, "far.off", {{10, 0, 0}});
  const CliRun run = runDelta("overlap builtin:box '" + far.string() +
                              "' --rotate-b 0,0,1,45 --translate-b -10,0,0.25 --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  const double octagon = 8 * 0.25 * std::tan(std::numbers::pi / 8);
  EXPECT_NEAR(jsonNumber(run.out, "volume"), 0.75 * octagon, 1e-12) << run.out;
  expectVector(jsonVector(run.out, "centroid"), {0, 0, 0.125}, 1e-12, "centroid");
}

// B of two cubes, one through each side of A: two regions, listed largest first.
TEST(OverlapCli, ListsSeveralRegionsLargestFirst) {
  const TemporaryFolder folder("overlap_regions");
  const fs::path two = cubesFile(folder, "two.off", {{0.9, 0.1, 0.05}, {-0.8, -0.1, 0.07}});
  const double small = 0.1 * 0.9 * 0.95, large = 0.2 * 0.9 * 0.93;
  const CliRun run = runDelta("overlap builtin:box '" + two.string() + "' --json");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_NEAR(jsonNumber(run.out, "volume"), small + large, 1e-14) << run.out;
  const std::size_t first = run.out.find("\"regions\":[{");
  ASSERT_NE(first, std::string::npos) << run.out;
  const std::size_t second = run.out.find("},{", first);
  ASSERT_NE(second, std::string::npos) << run.out;
  EXPECT_NEAR(jsonNumber(run.out.substr(first), "volume"), large, 1e-14);
  EXPECT_NEAR(jsonNumber(run.out.substr(second), "volume"), small, 1e-14);
  expectVector(jsonVector(run.out.substr(first), "centroid"), {-0.4, -0.05, 0.035}, 1e-14,
               "larger region's centroid");
  EXPECT_EQ(jsonNumber(run.out, "curves"), 2.0);
  const CliRun text = runDelta("overlap builtin:box '" + two.string() + "'");
  ASSERT_EQ(text.exitCode, 0) << text.err;
  for (const char* part : {"in 2 regions", "2 intersection curves", "region 0: volume 0.167",
                           "region 1: volume 0.085"})
    EXPECT_NE(text.out.find(part), std::string::npos) << part << " in " << text.out;
}

TEST(OverlapCli, WritesTheCurvesAsPolylinesParaViewOpens) {
  const TemporaryFolder folder("overlap_out");
  const fs::path vtp = folder.path / "curves.vtp";
  const CliRun run = runDelta(kOffsetCubes + " --quiet --out '" + vtp.string() + "'");
  ASSERT_EQ(run.exitCode, 0) << run.err;
  EXPECT_TRUE(run.out.empty()) << run.out;
  ASSERT_TRUE(fs::exists(vtp));
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(folder.path))
    ++files;
  EXPECT_EQ(files, 1u) << "a temporary file was left behind";
  const std::string file = slurp(vtp);
  EXPECT_NE(file.find("<VTKFile type=\"PolyData\""), std::string::npos);
  EXPECT_NE(file.find("NumberOfLines=\"1\""), std::string::npos);
  using delta::test::readVtkArray;
  const std::vector<double> points = readVtkArray<double>(file, "Points");
  ASSERT_GE(points.size(), 18u);  // six corners of the hexagon at least
  ASSERT_EQ(points.size() % 3, 0u);
  const std::size_t count = points.size() / 3;
  // Every point lies on an edge of the shared box where a face of A meets a face of B.
  for (std::size_t i = 0; i < count; ++i) {
    const double x = points[3 * i], y = points[3 * i + 1], z = points[3 * i + 2];
    const int onA =
        (std::abs(x - 0.5) < 1e-12) + (std::abs(y - 0.5) < 1e-12) + (std::abs(z - 0.5) < 1e-12);
    const int onB =
        (std::abs(x - 0.0) < 1e-12) + (std::abs(y + 0.25) < 1e-12) + (std::abs(z + 0.375) < 1e-12);
    EXPECT_GE(onA, 1) << "point " << i << ": " << x << ' ' << y << ' ' << z;
    EXPECT_GE(onB, 1) << "point " << i << ": " << x << ' ' << y << ' ' << z;
  }
  EXPECT_EQ(readVtkArray<std::uint32_t>(file, "region"), std::vector<std::uint32_t>{0});
  EXPECT_EQ(readVtkArray<std::uint8_t>(file, "closed"), std::vector<std::uint8_t>{1});
  const std::vector<double> length = readVtkArray<double>(file, "length");
  ASSERT_EQ(length.size(), 1u);
  EXPECT_NEAR(length[0], 4.25, 1e-13);
  EXPECT_EQ(readVtkArray<std::uint32_t>(file, "triangle_a").size(), count);
  for (const std::uint32_t id : readVtkArray<std::uint32_t>(file, "triangle_b"))
    EXPECT_LT(id, 12u);
}

TEST(OverlapCli, RefusesOpenMeshesBadMotionsAndMissingFiles) {
  const TemporaryFolder folder("overlap_bad");
  const fs::path vtp = folder.path / "curves.vtp";
  const std::string out = " --out '" + vtp.string() + "'";
  // An open mesh (a quad), either side.
  expectOneLineError(runDelta("overlap builtin:quad builtin:box" + out), "builtin:quad");
  expectOneLineError(runDelta("overlap builtin:box builtin:quad --json" + out), "builtin:quad");
  for (const std::string bad : {"1,2", "1,x,3", "nan,0,0", "1,2,3,4", ","})
    expectOneLineError(runDelta("overlap builtin:box builtin:box" + out + " --translate-b " + bad),
                       "--translate-b");
  expectOneLineError(runDelta("overlap builtin:box builtin:box --rotate-b 0,0,0,30" + out),
                     "--rotate-b");
  expectOneLineError(runDelta("overlap builtin:box builtin:box --rotate-b 0,0,1"), "--rotate-b");
  expectOneLineError(runDelta("overlap builtin:box /nonexistent/b.off" + out),
                     "/nonexistent/b.off");
  expectOneLineError(runDelta("overlap /nonexistent/a.off builtin:box --json"),
                     "/nonexistent/a.off");
  expectOneLineError(runDelta("overlap builtin:box builtin:box --out curves.csv"), "curves.csv");
  expectOneLineError(runDelta("overlap builtin:box"), "MESH_B");
  EXPECT_FALSE(fs::exists(vtp)) << "nothing is written for a refused run";
  // An output that cannot be written: one line naming it, and no answer printed.
  expectOneLineError(runDelta(kOffsetCubes + " --json --out /nonexistent/dir/c.vtp"),
                     "/nonexistent/dir/c.vtp");
}

}  // namespace
