#include "delta/io/vtk.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <regex>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/mesh/primitives.h"

#include "io/vtk_read.h"

namespace delta::io {
namespace {

namespace fs = std::filesystem;

fs::path tempFile(const std::string& name) {
  return fs::temp_directory_path() / ("delta_vtk_" + std::to_string(::getpid()) + "_" + name);
}

using test::readFile;
using test::readVtkArray;

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
  const std::string file = readFile(path);
  fs::remove(path);
  EXPECT_NE(file.find("<VTKFile type=\"PolyData\""), std::string::npos);
  EXPECT_NE(file.find("NumberOfPoints=\"8\" NumberOfVerts=\"0\""), std::string::npos);
  EXPECT_NE(file.find("NumberOfPolys=\"12\""), std::string::npos);
  EXPECT_EQ(file.substr(file.size() - 28), "\n</AppendedData>\n</VTKFile>\n");
  const std::vector<double> points = readVtkArray<double>(file, "Points");
  ASSERT_EQ(points.size(), 24u);
  for (std::size_t i = 0; i < 8; ++i) {
    EXPECT_EQ(points[3 * i], box.vertices()[i].x);
    EXPECT_EQ(points[3 * i + 2], box.vertices()[i].z);
  }
  EXPECT_EQ(readVtkArray<double>(file, "height"), height.values);
  EXPECT_EQ(readVtkArray<double>(file, "triangle id"), id.values);
  const std::vector<std::int64_t> connectivity = readVtkArray<std::int64_t>(file, "connectivity");
  // Verts come first (empty here), then Polys: the second "connectivity" is the triangles'.
  EXPECT_TRUE(connectivity.empty());
  const std::vector<std::int64_t> offsets = readVtkArray<std::int64_t>(file, "offsets");
  EXPECT_TRUE(offsets.empty());
}

TEST(Vtk, WritesPointsAsVertexCells) {
  VtkPolyData data = VtkPolyData::fromPoints({{0, 0, 0}, {1, 2, 3}, {-1, 0.5, 1e300}});
  data.pointData.push_back({"normal", 3, {0, 0, 1, 0, 1, 0, 1, 0, 0}});
  data.cellData.push_back({"overlap", 1, {0, 1, 0}});
  const fs::path path = tempFile("points.vtp");
  writeVtp(data, path);
  const std::string file = readFile(path);
  fs::remove(path);
  EXPECT_NE(file.find("NumberOfPoints=\"3\" NumberOfVerts=\"3\""), std::string::npos);
  EXPECT_EQ(readVtkArray<std::int64_t>(file, "connectivity"), (std::vector<std::int64_t>{0, 1, 2}));
  EXPECT_EQ(readVtkArray<std::int64_t>(file, "offsets"), (std::vector<std::int64_t>{1, 2, 3}));
  EXPECT_EQ(readVtkArray<double>(file, "Points").back(), 1e300);
  EXPECT_EQ(readVtkArray<double>(file, "normal").size(), 9u);
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

/// The piece of a parallel run: points with a scalar and a vector per point and a scalar per
/// vertex cell.
VtkPolyData piece(std::vector<Vec3> points) {
  VtkPolyData data = VtkPolyData::fromPoints(std::move(points));
  const std::size_t count = data.points.size();
  data.pointData.push_back({"radius", 1, std::vector<double>(count, 0.5)});
  data.pointData.push_back({"velocity", 3, std::vector<double>(3 * count, 1.0)});
  data.cellData.push_back({"rank & part", 1, std::vector<double>(count, 2.0)});
  return data;
}

TEST(Vtk, WritesAParallelPolyDataThatListsItsPieces) {
  const fs::path directory = tempFile("pieces");
  fs::create_directories(directory / "frame");
  const VtkPolyData first = piece({{0, 0, 0}, {1, 0, 0}});
  const VtkPolyData second = piece({});  // a process that owns nothing writes an empty piece
  writeVtp(first, directory / "frame" / "rank_0.vtp");
  writeVtp(second, directory / "frame" / "rank_1.vtp");
  const std::vector<fs::path> pieces = {"frame/rank_0.vtp", directory / "frame" / "rank_1.vtp"};
  const fs::path path = directory / "frame.pvtp";
  writePvtp(first, pieces, path);
  const std::string file = readFile(path);
  EXPECT_EQ(file.rfind("<?xml version=\"1.0\"?>\n<VTKFile type=\"PPolyData\" version=\"1.0\" "
                       "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
                       "<PPolyData GhostLevel=\"0\">\n",
                       0),
            0u)
      << file;
  EXPECT_NE(file.find("<PPointData>\n"
                      "<PDataArray type=\"Float64\" Name=\"radius\" NumberOfComponents=\"1\"/>\n"
                      "<PDataArray type=\"Float64\" Name=\"velocity\" NumberOfComponents=\"3\"/>\n"
                      "</PPointData>\n"),
            std::string::npos)
      << file;
  EXPECT_NE(file.find("<PCellData>\n<PDataArray type=\"Float64\" Name=\"rank &amp; part\" "
                      "NumberOfComponents=\"1\"/>\n</PCellData>\n"),
            std::string::npos)
      << file;
  EXPECT_NE(file.find("<PPoints>\n<PDataArray type=\"Float64\" Name=\"Points\" "
                      "NumberOfComponents=\"3\"/>\n</PPoints>\n"),
            std::string::npos)
      << file;
  const std::string pieceList = "<Piece Source=\"frame/rank_0.vtp\"/>\n<Piece Source=\"" +
                                (directory / "frame" / "rank_1.vtp").generic_string() + "\"/>\n";
  EXPECT_NE(file.find(pieceList), std::string::npos) << file;
  EXPECT_EQ(file.substr(file.size() - 24), "</PPolyData>\n</VTKFile>\n");

  // Each array the .pvtp declares is in the piece, with as many values as its components say.
  const std::string firstPiece = readFile(directory / "frame" / "rank_0.vtp");
  const std::regex declared(
      "<PDataArray type=\"Float64\" Name=\"([^\"]*)\" "
      "NumberOfComponents=\"([0-9]+)\"");
  int arrays = 0;
  for (auto match = std::sregex_iterator(file.begin(), file.end(), declared);
       match != std::sregex_iterator(); ++match, ++arrays) {
    const std::string name = (*match)[1];  // escaped as in the piece: "rank &amp; part"
    const std::size_t components = std::stoul((*match)[2]);
    EXPECT_EQ(readVtkArray<double>(firstPiece, name).size(), 2 * components) << name;
  }
  EXPECT_EQ(arrays, 4);  // three arrays and the points

  writePvtp(VtkPolyData{}, std::vector<fs::path>{"other.vtp"}, path);  // replaces the file
  const std::string replaced = readFile(path);
  EXPECT_NE(replaced.find("<PPointData>\n</PPointData>\n<PCellData>\n</PCellData>\n"),
            std::string::npos)
      << replaced;
  EXPECT_EQ(replaced.find("rank_0"), std::string::npos);
  fs::remove_all(directory);
}

TEST(Vtk, RejectsAParallelPolyDataWithoutPiecesOrUnwritable) {
  const fs::path path = tempFile("bad.pvtp");
  try {
    writePvtp(piece({}), {}, path);
    ADD_FAILURE() << "a .pvtp without pieces was written";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(path.string()), std::string::npos) << error.what();
  }
  EXPECT_FALSE(fs::exists(path));
  VtkPolyData noComponents = piece({});
  noComponents.pointData[0].components = 0;
  const std::vector<fs::path> pieces = {"a.vtp"};
  EXPECT_THROW(writePvtp(noComponents, pieces, path), Error);
  EXPECT_FALSE(fs::exists(path));
  EXPECT_THROW(writePvtp(piece({}), pieces, "/nonexistent/dir/x.pvtp"), Error);
}

/// Two unit voxels side by side along x, sharing a face: 12 points on a 3 × 2 × 2 lattice.
VtkVoxelGrid twoVoxels() {
  VtkVoxelGrid grid;
  for (int z = 0; z < 2; ++z)
    for (int y = 0; y < 2; ++y)
      for (int x = 0; x < 3; ++x)
        grid.points.push_back({double(x), double(y), double(z)});
  const auto at = [](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
    return x + 3 * y + 6 * z;
  };
  for (std::uint32_t left = 0; left < 2; ++left) {
    std::array<std::uint32_t, 8> corners{};
    for (std::uint32_t c = 0; c < 8; ++c)
      corners[c] = at(left + (c & 1), (c >> 1) & 1, (c >> 2) & 1);
    grid.voxels.push_back(corners);
  }
  return grid;
}

TEST(Vtk, WritesVoxelsThatReadBack) {
  VtkVoxelGrid grid = twoVoxels();
  VtkArray height{"height", 1, {}};
  for (const Vec3& p : grid.points)
    height.values.push_back(p.z);
  grid.pointData.push_back(height);
  grid.pointData.push_back({"gradient", 3, std::vector<double>(3 * grid.points.size(), 0.5)});
  grid.cellData.push_back({"level", 1, {3, 4}});
  const fs::path path = tempFile("voxels.vtu");
  writeVtu(grid, path);
  const std::string file = readFile(path);
  fs::remove(path);
  EXPECT_NE(file.find("<VTKFile type=\"UnstructuredGrid\""), std::string::npos);
  EXPECT_NE(file.find("<UnstructuredGrid>\n<Piece NumberOfPoints=\"12\" NumberOfCells=\"2\">"),
            std::string::npos)
      << file.substr(0, 300);
  EXPECT_NE(file.find("<DataArray type=\"UInt8\" Name=\"types\""), std::string::npos);
  EXPECT_EQ(file.substr(file.size() - 28), "\n</AppendedData>\n</VTKFile>\n");
  const std::vector<double> points = readVtkArray<double>(file, "Points");
  ASSERT_EQ(points.size(), 36u);
  for (std::size_t i = 0; i < grid.points.size(); ++i) {
    EXPECT_EQ(points[3 * i], grid.points[i].x);
    EXPECT_EQ(points[3 * i + 1], grid.points[i].y);
    EXPECT_EQ(points[3 * i + 2], grid.points[i].z);
  }
  const std::vector<std::int64_t> connectivity = readVtkArray<std::int64_t>(file, "connectivity");
  ASSERT_EQ(connectivity.size(), 16u);
  for (std::size_t v = 0; v < 2; ++v)
    for (std::size_t c = 0; c < 8; ++c)
      EXPECT_EQ(connectivity[8 * v + c], grid.voxels[v][c]);
  EXPECT_EQ(readVtkArray<std::int64_t>(file, "offsets"), (std::vector<std::int64_t>{8, 16}));
  EXPECT_EQ(readVtkArray<std::uint8_t>(file, "types"), (std::vector<std::uint8_t>{11, 11}));
  EXPECT_EQ(readVtkArray<double>(file, "height"), height.values);
  EXPECT_EQ(readVtkArray<double>(file, "gradient").size(), 36u);
  EXPECT_EQ(readVtkArray<double>(file, "level"), (std::vector<double>{3, 4}));
}

TEST(Vtk, WritesAnEmptyVoxelGrid) {
  const fs::path path = tempFile("empty.vtu");
  writeVtu({}, path);
  const std::string file = readFile(path);
  fs::remove(path);
  EXPECT_NE(file.find("NumberOfPoints=\"0\" NumberOfCells=\"0\""), std::string::npos);
  EXPECT_TRUE(readVtkArray<std::uint8_t>(file, "types").empty());
}

TEST(Vtk, RejectsBadVoxelGridsAndWritesNothing) {
  const fs::path path = tempFile("bad.vtu");
  VtkVoxelGrid grid = twoVoxels();
  grid.pointData.push_back({"short", 1, {1, 2, 3}});
  EXPECT_THROW(writeVtu(grid, path), Error);
  grid.pointData.clear();
  grid.cellData.push_back({"level", 1, {3, 4, 5}});  // three values for two voxels
  EXPECT_THROW(writeVtu(grid, path), Error);
  grid.cellData.clear();
  grid.voxels[1][7] = 12;  // one past the points
  try {
    writeVtu(grid, path);
    ADD_FAILURE() << "a voxel past the points was written";
  } catch (const Error& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find("voxel 1 refers to point 12 of 12"), std::string::npos) << message;
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_THROW(writeVtu(twoVoxels(), "/nonexistent/dir/x.vtu"), Error);
}

TEST(Vtk, WritesATimeSeriesCollection) {
  const fs::path path = tempFile("series.pvd");
  const std::vector<VtkSeriesEntry> entries = {
      {0.0, "frames/a_000000.vtp"}, {0.1, "frames/a_000001.vtp"}, {2.5e-7, "b&\"c\".vtp"}};
  writePvd(entries, path);
  const std::string file = readFile(path);
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
  EXPECT_NE(readFile(path).find("<Collection>\n</Collection>"), std::string::npos);
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
