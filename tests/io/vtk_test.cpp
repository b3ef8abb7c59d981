#include "delta/io/vtk.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
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
  const std::vector<std::int32_t> connectivity = readVtkArray<std::int32_t>(file, "connectivity");
  // Verts come first (empty here), then Polys: the second "connectivity" is the triangles'.
  EXPECT_TRUE(connectivity.empty());
  const std::vector<std::int32_t> offsets = readVtkArray<std::int32_t>(file, "offsets");
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
  EXPECT_EQ(readVtkArray<std::int32_t>(file, "connectivity"), (std::vector<std::int32_t>{0, 1, 2}));
  EXPECT_EQ(readVtkArray<std::int32_t>(file, "offsets"), (std::vector<std::int32_t>{1, 2, 3}));
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

TEST(Vtk, WritesPolylinesBetweenVertsAndPolys) {
  VtkPolyData data;
  data.points = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {5, 5, 5}, {6, 5, 5}};
  data.lines = {{0, 1, 2, 0}, {3, 4}};  // a closed triangle, then an open segment
  data.cellData.push_back({"region", 1, {0, 1}, VtkType::UInt32});
  data.pointData.push_back({"t", 1, {0, 1, 2, 3, 4}});
  const fs::path path = tempFile("lines.vtp");
  writeVtp(data, path, {.compressionLevel = 0});
  const std::string file = readFile(path);
  EXPECT_NE(file.find("NumberOfVerts=\"0\" NumberOfLines=\"2\""), std::string::npos);
  const std::size_t lines = file.find("<Lines>\n");
  ASSERT_NE(lines, std::string::npos);
  EXPECT_LT(file.find("</Verts>"), lines);
  EXPECT_LT(lines, file.find("<Polys>"));
  // The arrays after <Lines> (the offsets in the raw appended data are unchanged by the cut).
  const std::string fromLines = file.substr(lines);
  EXPECT_EQ(readVtkArray<std::int32_t>(fromLines, "connectivity"),
            (std::vector<std::int32_t>{0, 1, 2, 0, 3, 4}));
  EXPECT_EQ(readVtkArray<std::int32_t>(fromLines, "offsets"), (std::vector<std::int32_t>{4, 6}));
  EXPECT_EQ(readVtkArray<std::uint32_t>(file, "region"), (std::vector<std::uint32_t>{0, 1}));
  // Compressed, the same file reads back the same.
  writeVtp(data, path);
  EXPECT_NE(readFile(path).find("NumberOfLines=\"2\""), std::string::npos);
  // A polyline of one point, or one past the points, is refused and the last file stays.
  const std::string before = readFile(path);
  data.lines = {{0}};
  EXPECT_THROW(writeVtp(data, path), Error);
  data.lines = {{0, 5}};
  EXPECT_THROW(writeVtp(data, path), Error);
  data.lines = {{0, 1}};  // one cell now, two cell values
  EXPECT_THROW(writeVtp(data, path), Error);
  EXPECT_EQ(readFile(path), before);
  // Without polylines, no Lines element: such files are as they were before polylines.
  writeVtp(VtkPolyData::fromPoints({{0, 0, 0}}), path);
  EXPECT_EQ(readFile(path).find("<Lines>"), std::string::npos);
  fs::remove(path);
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
  const std::vector<std::int32_t> connectivity = readVtkArray<std::int32_t>(file, "connectivity");
  ASSERT_EQ(connectivity.size(), 16u);
  for (std::size_t v = 0; v < 2; ++v)
    for (std::size_t c = 0; c < 8; ++c)
      EXPECT_EQ(connectivity[8 * v + c], static_cast<std::int32_t>(grid.voxels[v][c]));
  EXPECT_EQ(readVtkArray<std::int32_t>(file, "offsets"), (std::vector<std::int32_t>{8, 16}));
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

/// The UInt64 words of the compression header of the appended array declared with `name`:
/// blocks, block size, last block's size, each block's compressed size.
std::vector<std::uint64_t> compressionHeader(const std::string& file, const std::string& name) {
  const std::regex element("Name=\"" + name + "\"[^>]* offset=\"([0-9]+)\"");
  std::smatch match;
  EXPECT_TRUE(std::regex_search(file, match, element)) << name;
  if (match.empty()) return {};
  const std::string marker = "<AppendedData encoding=\"raw\">\n_";
  const std::size_t at = file.find(marker) + marker.size() + std::stoull(match[1]);
  std::uint64_t blocks = 0;
  std::memcpy(&blocks, file.data() + at, sizeof blocks);
  std::vector<std::uint64_t> header(3 + blocks);
  std::memcpy(header.data(), file.data() + at, header.size() * sizeof(std::uint64_t));
  return header;
}

TEST(Vtk, CompressesInBlocksAsVtkZLibDataCompressorDoes) {
  // 10,000 doubles are 80,000 bytes: two whole blocks of 32 KiB and a last one of 14,464 bytes;
  // 4,096 doubles fill exactly one block (the last size is then 0); an empty array has none.
  VtkPolyData data = VtkPolyData::fromPoints(std::vector<Vec3>(10000));
  for (std::size_t i = 0; i < data.points.size(); ++i)
    data.points[i] = {std::sin(double(i)), double(i) / 3.0, 1e300 / double(i + 1)};
  VtkArray noise{"noise", 1, {}}, exact{"exact", 1, {}};
  for (std::size_t i = 0; i < 10000; ++i) {
    noise.values.push_back(std::cos(double(i) * 0.37) * 1e-3);
    exact.values.push_back(i % 4096 == 0 ? std::nan("") : -0.0);
  }
  data.pointData = {noise, exact};
  data.cellData.push_back({"id", 1, std::vector<double>(10000, 7.0), VtkType::UInt32});
  const fs::path path = tempFile("blocks.vtp");
  writeVtp(data, path);
  const std::string file = readFile(path);
  fs::remove(path);
  EXPECT_NE(file.find("<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                      "header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\">"),
            std::string::npos)
      << file.substr(0, 200);
  const std::vector<std::uint64_t> header = compressionHeader(file, "noise");
  ASSERT_EQ(header.size(), 6u);
  EXPECT_EQ(header[0], 3u);
  EXPECT_EQ(header[1], kVtkBlockBytes);
  EXPECT_EQ(header[2], 80000u - 2 * kVtkBlockBytes);
  // Every value back, bit for bit (NaN and −0 included), through zlib's own uncompress().
  const std::vector<double> noiseBack = readVtkArray<double>(file, "noise");
  ASSERT_EQ(noiseBack.size(), noise.values.size());
  EXPECT_EQ(std::memcmp(noiseBack.data(), noise.values.data(), 80000), 0);
  const std::vector<double> exactBack = readVtkArray<double>(file, "exact");
  ASSERT_EQ(exactBack.size(), exact.values.size());
  EXPECT_EQ(std::memcmp(exactBack.data(), exact.values.data(), 80000), 0);
  const std::vector<double> points = readVtkArray<double>(file, "Points");
  ASSERT_EQ(points.size(), 30000u);
  EXPECT_EQ(std::memcmp(points.data(), data.points.data(), 240000), 0);
  EXPECT_EQ(readVtkArray<std::uint32_t>(file, "id"), std::vector<std::uint32_t>(10000, 7));
  EXPECT_LT(file.size(), 240000u + 2 * 80000u) << "compressible arrays shrink";

  VtkPolyData triangles;
  triangles.points = {{1, 2, 3}};
  triangles.triangles.assign(1366, {0, 0, 0});
  triangles.cellData.push_back({"filled", 1, std::vector<double>(1366, 0.5)});
  writeVtp(triangles, path);
  const std::string second = readFile(path);
  fs::remove(path);
  const std::vector<std::uint64_t> empty = compressionHeader(second, "connectivity");
  EXPECT_EQ(empty, (std::vector<std::uint64_t>{0, kVtkBlockBytes, 0})) << "the empty Verts";
  EXPECT_TRUE(readVtkArray<std::int32_t>(second, "connectivity").empty());
  // 1,366 doubles: one partial block (a whole one: the next test).
  EXPECT_EQ(compressionHeader(second, "filled")[0], 1u);
  EXPECT_EQ(compressionHeader(second, "filled")[2], 1366u * 8u);
}

TEST(Vtk, AWholeLastBlockHasSizeZeroInTheHeader) {
  VtkVoxelGrid grid = twoVoxels();
  constexpr int kComponents = kVtkBlockBytes / sizeof(double) / 2;  // two voxels fill one block
  grid.cellData.push_back({"block", kComponents, std::vector<double>(2 * kComponents, 1.5)});
  const fs::path path = tempFile("whole.vtu");
  writeVtu(grid, path);
  const std::string file = readFile(path);
  fs::remove(path);
  const std::vector<std::uint64_t> header = compressionHeader(file, "block");
  ASSERT_EQ(header.size(), 4u);
  EXPECT_EQ(header[0], 1u);
  EXPECT_EQ(header[1], kVtkBlockBytes);
  EXPECT_EQ(header[2], 0u) << "the one block is whole";
  EXPECT_EQ(readVtkArray<double>(file, "block"), std::vector<double>(2 * kComponents, 1.5));
}

TEST(Vtk, WritesRawDataWhenAskedAndEveryCompressionLevel) {
  VtkVoxelGrid grid = twoVoxels();
  grid.cellData.push_back({"level", 1, {3, 4}, VtkType::UInt8});
  const fs::path path = tempFile("levels.vtu");
  for (int level = 0; level <= 9; ++level) {
    writeVtu(grid, path, {level});
    const std::string file = readFile(path);
    EXPECT_EQ(file.find("compressor="), level == 0 ? std::string::npos : file.find("compressor="))
        << level;
    EXPECT_EQ(file.find("vtkZLibDataCompressor") == std::string::npos, level == 0) << level;
    EXPECT_EQ(readVtkArray<std::uint8_t>(file, "level"), (std::vector<std::uint8_t>{3, 4}));
    EXPECT_EQ(readVtkArray<std::int32_t>(file, "offsets"), (std::vector<std::int32_t>{8, 16}));
  }
  fs::remove(path);
  for (int level : {-1, 10}) {
    try {
      writeVtu(grid, path, {level});
      ADD_FAILURE() << "level " << level << " was accepted";
    } catch (const Error& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(path.string()), std::string::npos) << message;
      EXPECT_NE(message.find("compression level " + std::to_string(level)), std::string::npos)
          << message;
    }
    EXPECT_FALSE(fs::exists(path));
  }
}

TEST(Vtk, WritesIntegerArraysExactlyAndDeclaresTheirTypes) {
  VtkPolyData data = VtkPolyData::fromPoints({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}});
  data.pointData = {
      {"flag", 1, {0, 1, 255}, VtkType::UInt8},
      {"id", 1, {0, 4294967295.0, 7}, VtkType::UInt32},
      {"signed", 1, {-2147483648.0, 2147483647.0, -0.0}, VtkType::Int32},
      {"big", 2, {-9007199254740992.0, 9007199254740992.0, -1, 1, 0, 3}, VtkType::Int64},
      {"value", 1, {0.1, -2.5, 1e-300}}};
  const fs::path directory = tempFile("integers");
  fs::create_directories(directory);
  writeVtp(data, directory / "piece.vtp");
  const std::string file = readFile(directory / "piece.vtp");
  EXPECT_EQ(readVtkArray<std::uint8_t>(file, "flag"), (std::vector<std::uint8_t>{0, 1, 255}));
  EXPECT_EQ(readVtkArray<std::uint32_t>(file, "id"),
            (std::vector<std::uint32_t>{0, 4294967295u, 7}));
  EXPECT_EQ(readVtkArray<std::int32_t>(file, "signed"),
            (std::vector<std::int32_t>{-2147483647 - 1, 2147483647, 0}));
  EXPECT_EQ(readVtkArray<std::int64_t>(file, "big"),
            (std::vector<std::int64_t>{-9007199254740992, 9007199254740992, -1, 1, 0, 3}));
  EXPECT_EQ(readVtkArray<double>(file, "value"), (std::vector<double>{0.1, -2.5, 1e-300}));
  EXPECT_EQ(std::string(vtkTypeName(VtkType::UInt32)), "UInt32");

  // The .pvtp declares each array's type as the pieces store it.
  const std::vector<fs::path> pieces = {"piece.vtp"};
  writePvtp(data, pieces, directory / "all.pvtp");
  const std::string joined = readFile(directory / "all.pvtp");
  for (const char* declared :
       {"<PDataArray type=\"UInt8\" Name=\"flag\" NumberOfComponents=\"1\"/>",
        "<PDataArray type=\"UInt32\" Name=\"id\" NumberOfComponents=\"1\"/>",
        "<PDataArray type=\"Int32\" Name=\"signed\" NumberOfComponents=\"1\"/>",
        "<PDataArray type=\"Int64\" Name=\"big\" NumberOfComponents=\"2\"/>",
        "<PDataArray type=\"Float64\" Name=\"value\" NumberOfComponents=\"1\"/>"})
    EXPECT_NE(joined.find(declared), std::string::npos) << declared << " in " << joined;
  fs::remove_all(directory);
}

TEST(Vtk, RefusesToRoundAValueIntoAnIntegerType) {
  struct Case {
    VtkType type;
    double value;
    const char* shown;
  };
  const Case cases[] = {{VtkType::UInt8, 2.5, "2.5"},
                        {VtkType::UInt8, -1.0, "-1"},
                        {VtkType::UInt8, 256.0, "256"},
                        {VtkType::Int32, 2147483648.0, "2147483648"},
                        {VtkType::UInt32, 4294967296.0, "4294967296"},
                        {VtkType::Int64, 9223372036854775808.0, "9.2233720368547758e+18"},
                        {VtkType::Int64, std::nan(""), "nan"},
                        {VtkType::Int32, INFINITY, "inf"}};
  const fs::path path = tempFile("rounded.vtp");
  for (const Case& c : cases) {
    VtkPolyData data = VtkPolyData::fromPoints({{0, 0, 0}, {1, 0, 0}});
    data.cellData.push_back({"particle", 1, {0.0, c.value}, c.type});
    try {
      writeVtp(data, path);
      ADD_FAILURE() << c.shown << " was written as " << vtkTypeName(c.type);
    } catch (const Error& error) {
      const std::string message = error.what();
      EXPECT_NE(message.find(path.string()), std::string::npos) << message;
      EXPECT_NE(message.find("cell array 'particle' holds "), std::string::npos) << message;
      EXPECT_NE(message.find("(element 1)"), std::string::npos) << message;
      EXPECT_NE(message.find(std::string("not an ") + vtkTypeName(c.type)), std::string::npos)
          << message;
    }
    EXPECT_FALSE(fs::exists(path)) << c.shown;
  }
}

}  // namespace
}  // namespace delta::io
