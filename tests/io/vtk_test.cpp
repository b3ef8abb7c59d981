#include "delta/io/vtk.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/mesh/primitives.h"

namespace delta::io {
namespace {

namespace fs = std::filesystem;

fs::path tempFile(const std::string& name) {
  return fs::temp_directory_path() / ("delta_vtk_" + std::to_string(::getpid()) + "_" + name);
}

std::string slurp(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
}

/// Reads back the appended block of the DataArray named `name` (a minimal reader of what the
/// writer emits: offset attribute, UInt64 byte count, raw little-endian values).
template <typename T>
std::vector<T> readArray(const std::string& file, const std::string& name) {
  const std::regex element("<DataArray[^>]* Name=\"" + name + "\"[^>]* offset=\"([0-9]+)\"");
  std::smatch match;
  EXPECT_TRUE(std::regex_search(file, match, element)) << name;
  if (match.empty()) return {};
  const std::string marker = "<AppendedData encoding=\"raw\">\n_";
  const std::size_t start = file.find(marker) + marker.size();
  const std::size_t at = start + std::stoull(match[1]);
  std::uint64_t bytes = 0;
  std::memcpy(&bytes, file.data() + at, sizeof bytes);
  std::vector<T> values(bytes / sizeof(T));
  if (bytes > 0) std::memcpy(values.data(), file.data() + at + sizeof bytes, bytes);
  return values;
}

TEST(Vtk, WritesAMeshWithDataThatReadsBack) {
  const Mesh box = primitives::box({1, 2, 3}, {0.5, 0, 0});
  VtkPolyData data = VtkPolyData::fromMesh(box);
  VtkArray height{"height", 1, {}};
  for (const Vec3& p : box.vertices())
    height.values.push_back(p.z);
  data.pointData.push_back(height);
  VtkArray id{"triangle id", 1, {}};
  for (std::size_t t = 0; t < box.triangleCount(); ++t)
    id.values.push_back(double(t));
  data.cellData.push_back(id);
  const fs::path path = tempFile("box.vtp");
  writeVtp(data, path);
  const std::string file = slurp(path);
  fs::remove(path);
  EXPECT_NE(file.find("<VTKFile type=\"PolyData\""), std::string::npos);
  EXPECT_NE(file.find("NumberOfPoints=\"8\" NumberOfVerts=\"0\""), std::string::npos);
  EXPECT_NE(file.find("NumberOfPolys=\"12\""), std::string::npos);
  EXPECT_EQ(file.substr(file.size() - 28), "\n</AppendedData>\n</VTKFile>\n");
  const std::vector<double> points = readArray<double>(file, "Points");
  ASSERT_EQ(points.size(), 24u);
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(points[3 * i], box.vertices()[i].x);
    EXPECT_EQ(points[3 * i + 2], box.vertices()[i].z);
  }
  EXPECT_EQ(readArray<double>(file, "height"), height.values);
  EXPECT_EQ(readArray<double>(file, "triangle id"), id.values);
  const std::vector<std::int64_t> connectivity = readArray<std::int64_t>(file, "connectivity");
  // Verts come first (empty here), then Polys: the second "connectivity" is the triangles'.
  EXPECT_TRUE(connectivity.empty());
  const std::vector<std::int64_t> offsets = readArray<std::int64_t>(file, "offsets");
  EXPECT_TRUE(offsets.empty());
}

TEST(Vtk, WritesPointsAsVertexCells) {
  VtkPolyData data = VtkPolyData::fromPoints({{0, 0, 0}, {1, 2, 3}, {-1, 0.5, 1e300}});
  data.pointData.push_back({"normal", 3, {0, 0, 1, 0, 1, 0, 1, 0, 0}});
  data.cellData.push_back({"overlap", 1, {0, 1, 0}});
  const fs::path path = tempFile("points.vtp");
  writeVtp(data, path);
  const std::string file = slurp(path);
  fs::remove(path);
  EXPECT_NE(file.find("NumberOfPoints=\"3\" NumberOfVerts=\"3\""), std::string::npos);
  EXPECT_EQ(readArray<std::int64_t>(file, "connectivity"), (std::vector<std::int64_t>{0, 1, 2}));
  EXPECT_EQ(readArray<std::int64_t>(file, "offsets"), (std::vector<std::int64_t>{1, 2, 3}));
  EXPECT_EQ(readArray<double>(file, "Points").back(), 1e300);
  EXPECT_EQ(readArray<double>(file, "normal").size(), 9u);
}

TEST(Vtk, RejectsMismatchedArraysAndWritesNothing) {
  const fs::path path = tempFile("bad.vtp");
  VtkPolyData data = VtkPolyData::fromPoints({{0, 0, 0}, {1, 0, 0}});
  data.pointData.push_back({"short", 3, {1, 2, 3}});
  EXPECT_THROW(writeVtp(data, path), Error);
  data.pointData.clear();
  data.triangles.push_back({0, 1, 2});  // refers past the points
  EXPECT_THROW(writeVtp(data, path), Error);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_THROW(writeVtp(VtkPolyData::fromPoints({}), "/nonexistent/dir/x.vtp"), Error);
}

TEST(Vtk, WritesATimeSeriesCollection) {
  const fs::path path = tempFile("series.pvd");
  const std::vector<VtkSeriesEntry> entries = {
      {0.0, "frames/a_000000.vtp"}, {0.1, "frames/a_000001.vtp"}, {2.5e-7, "b&\"c\".vtp"}};
  writePvd(entries, path);
  const std::string file = slurp(path);
  fs::remove(path);
  EXPECT_NE(file.find("<VTKFile type=\"Collection\""), std::string::npos) << file;
  EXPECT_NE(
      file.find("<DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"frames/a_000000.vtp\"/>"),
      std::string::npos)
      << file;
  EXPECT_NE(file.find("timestep=\"0.10000000000000001\""), std::string::npos) << file;
  EXPECT_NE(file.find("file=\"b&amp;&quot;c&quot;.vtp\""), std::string::npos) << file;
  EXPECT_EQ(file.substr(file.size() - 25), "</Collection>\n</VTKFile>\n");
  const std::regex dataSet("<DataSet ");
  EXPECT_EQ(std::distance(std::sregex_iterator(file.begin(), file.end(), dataSet),
                          std::sregex_iterator()),
            3);

  writePvd({}, path);  // an empty series still opens
  EXPECT_NE(slurp(path).find("<Collection>\n</Collection>"), std::string::npos);
  fs::remove(path);
}

TEST(Vtk, RejectsANonFiniteTimeOrAnUnwritablePvd) {
  const fs::path path = tempFile("bad.pvd");
  const std::vector<VtkSeriesEntry> bad = {{0.0, "a.vtp"}, {std::nan(""), "b.vtp"}};
  EXPECT_THROW(writePvd(bad, path), Error);
  EXPECT_FALSE(fs::exists(path));
  const std::vector<VtkSeriesEntry> good = {{0.0, "a.vtp"}};
  EXPECT_THROW(writePvd(good, "/nonexistent/dir/x.pvd"), Error);
}

}  // namespace
}  // namespace delta::io
