// Δ's own mesh readers (io/detail/mesh_readers.h): exact coordinates, every format variant, the
// reader chosen by content, and files that are not regular or lie about their size.
#include "io/detail/mesh_readers.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/io/mesh_io.h"

#include "io/detail/soup_builder.h"
#include "io/test_files.h"

namespace delta::io {
namespace {

namespace fs = std::filesystem;

const fs::path kData = DELTA_DATA_DIR;

template <typename Read>
std::string readError(Read read, const std::string& bytes) {
  try {
    read(bytes);
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "reading did not throw delta::Error: " << bytes.substr(0, 80);
  return {};
}

double seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Coordinates whose nearest float differs from their nearest double, and a tetrahedron of edge
// 1e-3 at (1e6, 1e6, 1e6), which single precision (spacing 0.0625 there) collapses to a point.
const std::vector<Vec3> kTrickyVertices = {{0.1, 0.2, 0.30000000000000004},
                                           {1.0000000001, -2.5e-310, 123456789.123456789},
                                           {1e6, 1e6, 1e6},
                                           {1e6 + 1e-3, 1e6, 1e6},
                                           {1e6, 1e6 + 1e-3, 1e6},
                                           {1e6, 1e6, 1e6 + 1e-3}};
const char* const kTrickyText[] = {"0.1 0.2 0.30000000000000004",
                                   "1.0000000001 -2.5e-310 123456789.123456789",
                                   "1e6 1e6 1e6",
                                   "1000000.001 1e6 1e6",
                                   "1e6 1000000.001 1e6",
                                   "1e6 1e6 1000000.001"};

void expectTricky(const Mesh& mesh, const std::string& format) {
  ASSERT_EQ(mesh.vertexCount(), kTrickyVertices.size()) << format;
  const auto bits = [](const Vec3& p) {
    return std::array<std::uint64_t, 3>{std::bit_cast<std::uint64_t>(p.x),
                                        std::bit_cast<std::uint64_t>(p.y),
                                        std::bit_cast<std::uint64_t>(p.z)};
  };
  // An STL's vertices come in order of first appearance, facet after facet.
  for (std::size_t v = 0; v < kTrickyVertices.size(); ++v)
    EXPECT_TRUE(std::ranges::any_of(
        mesh.vertices(), [&](const Vec3& p) { return bits(p) == bits(kTrickyVertices[v]); }))
        << format << " vertex " << v << " is not there bit for bit";
  for (std::size_t t = 1; t < mesh.triangleCount(); ++t)  // the tetrahedron did not collapse
    EXPECT_GT(mesh.triangle(t).area(), 1e-7) << format << " triangle " << t;
}

TEST(MeshReaders, DecimalsAreReadBitForBitInEveryTextFormat) {
  std::string vertexLines, objVertices, plyVertices;
  for (const char* line : kTrickyText) {
    vertexLines += std::string(line) + "\n";
    objVertices += "v " + std::string(line) + "\n";
  }
  // A triangle on the first two vertices and the tetrahedron's four faces.
  const char* faces[] = {"0 1 2", "2 4 3", "2 3 5", "2 5 4", "3 4 5"};
  std::string offFaces, objFaces, plyFaces;
  for (const char* face : faces) {
    offFaces += "3 " + std::string(face) + "\n";
    plyFaces += "3 " + std::string(face) + "\n";
    unsigned a = 0, b = 0, c = 0;
    std::sscanf(face, "%u %u %u", &a, &b, &c);
    objFaces += "f " + std::to_string(a + 1) + " " + std::to_string(b + 1) + " " +
                std::to_string(c + 1) + "\n";
  }
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
      "property float z\nelement face 5\nproperty list uchar int vertex_indices\nend_header\n" +
      vertexLines + plyFaces;
  std::string stl = "solid s\n";
  for (const char* face : faces) {
    unsigned corner[3];
    std::sscanf(face, "%u %u %u", &corner[0], &corner[1], &corner[2]);
    stl += "facet normal 0 0 0\nouter loop\n";
    for (unsigned c : corner)
      stl += "vertex " + std::string(kTrickyText[c]) + "\n";
    stl += "endloop\nendfacet\n";
  }
  stl += "endsolid s\n";
  TempDir dir;
  expectTricky(load(dir.write("t.off", "OFF\n6 5 0\n" + vertexLines + offFaces)), "OFF");
  expectTricky(load(dir.write("t.obj", objVertices + objFaces)), "OBJ");
  expectTricky(load(dir.write("t.ply", ply)), "PLY");
  expectTricky(load(dir.write("t.stl", stl)), "STL");
  EXPECT_EQ(loadWithStatistics(dir / "t.off").statistics.precision, CoordinatePrecision::exact);
}

/// A binary PLY of the tricky vertices, with coordinates of `type` ("double" or "float").
std::string binaryPly(const std::string& type, bool bigEndian) {
  std::string bytes = "ply\nformat " +
                      std::string(bigEndian ? "binary_big_endian" : "binary_little_endian") +
                      " 1.0\ncomment tricky\nelement vertex 6\nproperty " + type + " x\nproperty " +
                      type + " y\nproperty " + type +
                      " z\nproperty uchar red\nelement face 2\n"
                      "property list uint16 int32 vertex_indices\nend_header\n";
  const auto append = [&](const void* value, std::size_t size) {
    std::string raw(static_cast<const char*>(value), size);
    if (bigEndian) std::reverse(raw.begin(), raw.end());  // the host is little-endian
    bytes += raw;
  };
  for (const Vec3& v : kTrickyVertices) {
    for (std::size_t axis = 0; axis < 3; ++axis) {
      if (type == "double") {
        const double x = v[axis];
        append(&x, 8);
      } else {
        const float x = static_cast<float>(v[axis]);
        append(&x, 4);
      }
    }
    bytes += '\x7f';
  }
  const std::uint16_t four = 4, three = 3;
  const std::int32_t quad[] = {2, 3, 5, 4}, triangle[] = {0, 1, 2};
  append(&four, 2);
  for (const std::int32_t i : quad)
    append(&i, 4);
  append(&three, 2);
  for (const std::int32_t i : triangle)
    append(&i, 4);
  return bytes;
}

TEST(MeshReaders, BinaryPlyDoubleAndFloatInBothByteOrders) {
  static_assert(std::endian::native == std::endian::little);
  for (const bool bigEndian : {false, true}) {
    const detail::TriangleSoup doubles = detail::readPly(binaryPly("double", bigEndian));
    ASSERT_EQ(doubles.positions.size(), 6u);
    for (std::size_t v = 0; v < 6; ++v)
      EXPECT_EQ(doubles.positions[v], kTrickyVertices[v]) << v << " big " << bigEndian;
    // The quad (2, 3, 5, 4) first, as a fan, then the triangle.
    ASSERT_EQ(doubles.triangles.size(), 3u);
    EXPECT_EQ(doubles.triangles[0], (TriangleIndices{2, 3, 5}));
    EXPECT_EQ(doubles.triangles[1], (TriangleIndices{2, 5, 4}));
    EXPECT_EQ(doubles.triangles[2], (TriangleIndices{0, 1, 2}));
    const detail::TriangleSoup floats = detail::readPly(binaryPly("float", bigEndian));
    for (std::size_t v = 0; v < 6; ++v)
      for (std::size_t axis = 0; axis < 3; ++axis)
        EXPECT_EQ(floats.positions[v][axis],
                  static_cast<double>(static_cast<float>(kTrickyVertices[v][axis])));
  }
  std::string cut = binaryPly("double", false);
  cut.resize(cut.size() - 3);
  EXPECT_NE(readError(detail::readPly, cut).find("binary data ends inside element 'face' 1"),
            std::string::npos);
}

TEST(MeshReaders, BinaryStlIsFloat32WidenedExactly) {
  std::string bytes(80, ' ');
  const std::uint32_t count = 1;
  bytes.append(reinterpret_cast<const char*>(&count), 4);
  const float values[12] = {0, 0, 1, 0.1f, 0.2f, 0.3f, 1e6f + 0.0625f, 1, 0, 0, 3.4e38f, -1e-40f};
  bytes.append(reinterpret_cast<const char*>(values), sizeof values);
  bytes.append(2, '\0');
  const detail::TriangleSoup soup = detail::readStl(bytes);
  ASSERT_EQ(soup.positions.size(), 3u);
  for (std::size_t corner = 0; corner < 3; ++corner)
    for (std::size_t axis = 0; axis < 3; ++axis)
      EXPECT_EQ(soup.positions[corner][axis], static_cast<double>(values[3 + 3 * corner + axis]));
  EXPECT_EQ(soup.statistics.sourceVertices, 3u);
}

TEST(MeshReaders, ObjFaceFormsAndNegativeIndices) {
  const detail::TriangleSoup soup = detail::readObj(
      "# comment\nmtllib x.mtl\nv 0 0 0\nv 1 0 0 1.0\nv 1 1 0 0.5 0.5 0.5\nv 0 1 0\n"
      "vt 0 0\nvn 0 0 1\nusemtl m\ns off\nf 1/1/1 2/1/1 3//1\nf -4/1 -2 -1\n"
      "g second\nf 1 2 \\\n 4\n");
  ASSERT_EQ(soup.triangles.size(), 3u);
  EXPECT_EQ(soup.triangles[0], (TriangleIndices{0, 1, 2}));
  EXPECT_EQ(soup.triangles[1], (TriangleIndices{0, 2, 3}));
  EXPECT_EQ(soup.triangles[2], (TriangleIndices{0, 1, 3}));
  EXPECT_EQ(soup.statistics.meshes, 2u);
  for (const char* bad :
       {"v 0 0 0\nf 1 2 3\n", "v 0 0 0\nf 0 1 1\n", "v 0 0 0\nf -2 1 1\n", "v 0 0 0\nf 1 x 1\n"})
    EXPECT_NE(readError(detail::readObj, bad).find("line 2"), std::string::npos) << bad;
}

TEST(MeshReaders, NonConvexPolygonsAreEarClippedKeepingOrientation) {
  // An L-shaped hexagon, counter-clockwise; its fan from corner 0 would leave the polygon.
  const std::vector<Vec3> vertices = {{0, 0, 0}, {2, 0, 0}, {2, 1, 0},
                                      {1, 1, 0}, {1, 2, 0}, {0, 2, 0}};
  for (int start = 0; start < 6; ++start) {  // a fan from corner 2, 4 or 5 would fold over
    std::vector<std::uint32_t> corners;
    for (int i = 0; i < 6; ++i)
      corners.push_back(static_cast<std::uint32_t>((start + i) % 6));
    for (const double flip : {1.0, -1.0}) {
      std::vector<Vec3> placed = vertices;
      for (Vec3& v : placed)
        v = {v.x, v.y * flip, 0.0};  // mirrored: clockwise, normal -z
      std::vector<std::uint32_t> order = corners;
      std::vector<TriangleIndices> triangles;
      detail::triangulatePolygon(placed, order, triangles);
      ASSERT_EQ(triangles.size(), 4u);
      double area = 0.0;
      for (const TriangleIndices& t : triangles) {
        const Vec3 normal = cross(placed[t[1]] - placed[t[0]], placed[t[2]] - placed[t[0]]);
        EXPECT_GE(normal.z * flip, 0.0) << "start " << start << " flip " << flip;
        area += 0.5 * normal.z * flip;
      }
      EXPECT_EQ(area, 3.0) << "start " << start << " flip " << flip;  // no overlap, no gap
    }
  }
}

TEST(MeshReaders, LyingCountsAreRefusedBeforeAllocating) {
  const auto start = std::chrono::steady_clock::now();
  EXPECT_NE(readError(detail::readOff, "OFF\n4000000000 1 0\n0 0 0\n").find("at most"),
            std::string::npos);
  EXPECT_NE(readError(detail::readOff, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4000000 0 1 2\n")
                .find("shorter"),
            std::string::npos);
  EXPECT_NE(readError(detail::readPly,
                      "ply\nformat binary_little_endian 1.0\nelement vertex 5000000000\n"
                      "property double x\nproperty double y\nproperty double z\nend_header\n0000")
                .find("does not fit in 32 bits"),
            std::string::npos);
  EXPECT_NE(readError(detail::readPly,
                      "ply\nformat binary_little_endian 1.0\nelement vertex 400000000\n"
                      "property double x\nproperty double y\nproperty double z\nend_header\n0000")
                .find("binary data ends inside element 'vertex' 0"),
            std::string::npos);
  std::string stl(84, '\0');
  stl[83] = '\x7f';  // announces 2^31 triangles in 84 bytes
  EXPECT_NE(readError(detail::readStl, stl).find("truncated"), std::string::npos);
  EXPECT_LT(seconds(start), 1.0);
}

TEST(MeshReaders, OutOfRangeDecimalsNameTheLineAndValue) {
  const std::string message =
      readError(detail::readOff, "OFF\n3 1 0\n0 0 0\n1 1e999 0\n0 1 0\n3 0 1 2\n");
  EXPECT_NE(message.find("line 4"), std::string::npos) << message;
  EXPECT_NE(message.find("'1e999'"), std::string::npos) << message;
  EXPECT_NE(readError(detail::readObj, "v 0 0 0\nv 1e-999 0 0\n").find("line 2"),
            std::string::npos);
  // 1e39 overflowed assimp's floats; it is an ordinary double.
  EXPECT_EQ(detail::readOff("OFF\n3 1 0\n1e39 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").positions[0].x, 1e39);
}

// ----- The reader is chosen by content -----

TEST(MeshReaders, ContentDecidesTheFormat) {
  TempDir dir;
  const std::string off = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 99\n";
  // Assimp read this .dat as OFF and clamped index 99 to 2; Δ's OFF reader refuses it.
  EXPECT_NE(loadError(dir.write("mesh.dat", off)).find("refers to vertex 99"), std::string::npos);
  const std::string good = "OFF\n3 1 0\n0.1 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  for (const char* name : {"mesh.dat", "mesh.stl", "mesh.txt", "mesh"}) {
    const LoadedMesh loaded = loadWithStatistics(dir.write(name, good));
    EXPECT_EQ(loaded.mesh.vertices()[0].x, 0.1) << name;
    EXPECT_EQ(loaded.statistics.precision, CoordinatePrecision::exact) << name;
  }
  EXPECT_EQ(load(dir.write("obj.off", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")).triangleCount(), 1u);
  EXPECT_EQ(detail::detectMeshFormat("solid x\n facet normal 0 0 1\n", 100, ".dat", false),
            detail::MeshFormat::stl);
  EXPECT_EQ(detail::detectMeshFormat("ply\nformat ascii 1.0\n", 100, ".obj", false),
            detail::MeshFormat::ply);
  EXPECT_EQ(detail::detectMeshFormat("v 0 0 0\n", 100, ".nff", true), detail::MeshFormat::other);
  EXPECT_EQ(detail::detectMeshFormat("v 0 0 0\n", 100, ".dat", false), detail::MeshFormat::obj);
  EXPECT_EQ(detail::detectMeshFormat("glTF", 100, ".glb", true), detail::MeshFormat::other);
}

TEST(MeshReaders, AByteOrderMarkAtTheStartIsNotContent) {
  // Some editors start a text file with U+FEFF: "unknown OFF keyword '\ufeffOFF'" named an
  // invisible character. The OFF, OBJ and ASCII PLY readers and the detection skip it, and read
  // the same mesh as without it (a binary PLY's body is found after its header all the same).
  TempDir dir;
  const std::string bom = "\xEF\xBB\xBF";
  const std::vector<std::pair<const char*, std::string>> files = {
      {"a.off", "OFF\n3 1 0\n0.1 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"},
      {"a.obj", "v 0.1 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
      {"a.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
       "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
       "end_header\n0.1 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"}};
  for (const auto& [name, text] : files) {
    const Mesh plain = load(dir.write(std::string("plain_") + name, text));
    const Mesh marked = load(dir.write(std::string("marked_") + name, bom + text));
    ASSERT_EQ(marked.vertexCount(), plain.vertexCount()) << name;
    EXPECT_EQ(marked.vertices()[0], plain.vertices()[0]) << name;
    EXPECT_EQ(marked.triangles()[0], plain.triangles()[0]) << name;
  }
  // Only at the start: elsewhere it is what it was, an error naming the line.
  EXPECT_FALSE(loadError(dir.write("middle.off", "OFF\n" + bom + "3 1 0\n")).empty());
}

TEST(MeshReaders, AssimpOnlyFormatsAreMarkedSinglePrecision) {
  const fs::path box = kData / "assimp" / "glTF2/BoxTextured-glTF/BoxTextured.gltf";
  ASSERT_TRUE(fs::exists(box)) << box;
  EXPECT_EQ(loadWithStatistics(box).statistics.precision, CoordinatePrecision::single);
  EXPECT_STREQ(toString(CoordinatePrecision::single), "single");
  EXPECT_STREQ(toString(CoordinatePrecision::exact), "exact");
}

// ----- Endless and special files -----

TEST(MeshReaders, RefusesFifosDevicesAndSparseGiants) {
  TempDir dir;
  const fs::path fifo = dir / "pipe.off";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  auto start = std::chrono::steady_clock::now();
  EXPECT_NE(loadError(fifo).find("FIFO"), std::string::npos);
  EXPECT_NE(loadError("/dev/zero").find("not a regular file"), std::string::npos);
  EXPECT_LT(seconds(start), 1.0);
  for (const char* name : {"sparse.ply", "sparse.off", "sparse.stl", "sparse.obj", "sparse.dat"}) {
    const fs::path sparse = dir / name;
    {
      const int fd = ::open(sparse.c_str(), O_CREAT | O_WRONLY, 0600);
      ASSERT_GE(fd, 0);
      ASSERT_EQ(::ftruncate(fd, off_t{3} << 30), 0);  // 3 GiB of zeros, no disk used
      ::close(fd);
    }
    start = std::chrono::steady_clock::now();
    const std::string message = loadError(sparse);
    EXPECT_LT(seconds(start), 1.0) << name << ": " << message;
    EXPECT_NE(message.find(sparse.string()), std::string::npos) << message;
    fs::remove(sparse);
  }
}

}  // namespace
}  // namespace delta::io
