#include "delta/io/mesh_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "delta/core/error.h"

#include "io/test_files.h"

namespace delta::io {
namespace {

namespace fs = std::filesystem;

const fs::path kData = DELTA_DATA_DIR;
const fs::path kMeshes = kData / "meshes";
const fs::path kAssimp = kData / "assimp";

/// Missing test data fails a test (it must not pass by skipping).
testing::AssertionResult dataPresent(const fs::path& path) {
  if (fs::exists(path)) return testing::AssertionSuccess();
  return testing::AssertionFailure() << "test data " << path << " is missing: run scripts/setup.sh";
}

/// A closed unit cube: 8 vertices, 12 outward-facing triangles.
Mesh unitCube() {
  return Mesh(
      {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}},
      {{0, 2, 1},
       {0, 3, 2},
       {4, 5, 6},
       {4, 6, 7},
       {0, 1, 5},
       {0, 5, 4},
       {1, 2, 6},
       {1, 6, 5},
       {2, 3, 7},
       {2, 7, 6},
       {3, 0, 4},
       {3, 4, 7}});
}

bool allFinite(const Mesh& mesh) {
  return std::all_of(mesh.vertices().begin(), mesh.vertices().end(),
                     [](const Vec3& v) { return isFinite(v); });
}

bool hasExtension(const fs::path& path, std::initializer_list<std::string> extensions) {
  std::string extension = path.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return std::find(extensions.begin(), extensions.end(), extension) != extensions.end();
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Loading a file is guarded against hangs by ctest's TIMEOUT; this bound, far above the few
// milliseconds each file takes, catches a reader that allocates or loops on a lying header.
constexpr double kSecondsPerFile = 2.0;

// ----- Real meshes -----

TEST(IoLoad, ArmadilloHasItsKnownSize) {
  const fs::path path = kMeshes / "armadillo.off";
  ASSERT_TRUE(dataPresent(path));
  const LoadedMesh loaded = loadWithStatistics(path);
  EXPECT_EQ(loaded.mesh.triangleCount(), 52000u);
  EXPECT_EQ(loaded.mesh.vertexCount(), 26002u);
  EXPECT_EQ(loaded.statistics.meshes, 1u);
  EXPECT_EQ(loaded.statistics.sourceVertices, 26002u);
  EXPECT_EQ(loaded.statistics.pointsSkipped, 0u);
  EXPECT_EQ(loaded.statistics.linesSkipped, 0u);
}

TEST(IoLoad, EveryCgalOffLoadsOrSaysWhy) {
  ASSERT_TRUE(dataPresent(kMeshes));
  std::vector<std::string> loaded;
  for (const fs::directory_entry& entry : fs::directory_iterator(kMeshes)) {
    if (!hasExtension(entry.path(), {".off"})) continue;
    try {
      const Mesh mesh = load(entry.path());
      EXPECT_TRUE(allFinite(mesh)) << entry.path();
      loaded.push_back(entry.path().filename().string());
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(entry.path().string()), std::string::npos);
      std::cout << "[ rejected ] " << error.what() << "\n";
    }
  }
  std::cout << "[   loaded ] " << loaded.size() << " CGAL OFF files\n";
  // Among them files that assimp alone misreads: comments between the elements (cube-shuffled),
  // RGB colours (mesh_with_colors).
  for (const char* name :
       {"armadillo.off", "bunny00.off", "refined_elephant.off", "ChineseDragon-10kv.off",
        "fandisk.off", "cube_quad.off", "P.off", "cube-shuffled.off", "mesh_with_colors.off"})
    EXPECT_NE(std::find(loaded.begin(), loaded.end(), name), loaded.end()) << name;
}

TEST(IoLoad, AssimpModelsLoadOrFailNamingTheFile) {
  ASSERT_TRUE(dataPresent(kAssimp));
  std::vector<std::string> loaded;
  std::vector<std::string> rejected;
  for (const fs::directory_entry& entry : fs::recursive_directory_iterator(kAssimp)) {
    if (!entry.is_regular_file() || !hasExtension(entry.path(), {".off", ".obj", ".stl", ".ply"}))
      continue;
    const std::string name = fs::relative(entry.path(), kAssimp).generic_string();
    const auto start = std::chrono::steady_clock::now();
    try {
      const Mesh mesh = load(entry.path());
      EXPECT_TRUE(allFinite(mesh)) << name;
      loaded.push_back(name);
      std::cout << "[   loaded ] " << name << ": " << mesh.triangleCount() << " triangles\n";
    } catch (const Error& error) {
      EXPECT_NE(std::string(error.what()).find(entry.path().string()), std::string::npos)
          << error.what();
      rejected.push_back(name);
      std::cout << "[ rejected ] " << error.what() << "\n";
    }
    EXPECT_LT(secondsSince(start), kSecondsPerFile) << name;
  }
  for (const char* name : {"STL/Spider_binary.stl", "STL/Spider_ascii.stl", "STL/3DSMaxExport.STL",
                           "PLY/cube.ply", "PLY/cube_binary.ply", "PLY/Wuson.ply", "OBJ/box.obj",
                           "OBJ/spider.obj", "OFF/Cube.off", "OFF/Wuson.off"})
    EXPECT_NE(std::find(loaded.begin(), loaded.end(), name), loaded.end()) << name;
  for (const std::string& name : loaded)
    EXPECT_FALSE(name.starts_with("invalid/")) << name << " is invalid, but it loaded";
  EXPECT_EQ(std::count_if(rejected.begin(), rejected.end(),
                          [](const std::string& name) { return name.starts_with("invalid/"); }),
            6);  // OutOfMemory.off, empty.{obj,off,ply}, malformed.obj, malformed2.obj
}

TEST(IoLoad, ReadsGltfAndGltf2) {
  ASSERT_TRUE(dataPresent(kAssimp));
  for (const char* name :
       {"glTF/BoxTextured-glTF/BoxTextured.gltf", "glTF2/BoxTextured-glTF/BoxTextured.gltf",
        "glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"}) {
    const LoadedMesh box = loadWithStatistics(kAssimp / name);
    EXPECT_EQ(box.mesh.triangleCount(), 12u) << name;
    EXPECT_EQ(box.mesh.vertexCount(), 8u) << name;  // 24 with per-face normals, joined
    EXPECT_EQ(box.statistics.sourceVertices, 24u) << name;
  }
  const Mesh engine = load(kAssimp / "glTF2/2CylinderEngine-glTF-Binary/2CylinderEngine.glb");
  EXPECT_GT(engine.triangleCount(), 10000u);
}

// ----- Merging a scene -----

TEST(IoLoad, PlacesEveryMeshReferenceWithItsNodeTransform) {
  // TwoBoxes.gltf: one box mesh [-0.5, 0.5]³ placed twice, under a root that turns Y-up into
  // Z-up, (x, y, z) ↦ (x, z, -y): as is (bottom) and scaled by 0.5 and moved by (0, 0, 1) (top,
  // [-0.25, 0.25]² × [0.75, 1.25], then turned to y ∈ [0.75, 1.25]).
  const fs::path path = kAssimp / "glTF/TwoBoxes/TwoBoxes.gltf";
  ASSERT_TRUE(dataPresent(path));
  const LoadedMesh boxes = loadWithStatistics(path);
  EXPECT_EQ(boxes.statistics.meshes, 2u);
  EXPECT_EQ(boxes.mesh.triangleCount(), 24u);
  EXPECT_EQ(boxes.mesh.vertexCount(), 16u);
  const Aabb bounds = boxes.mesh.bounds();
  EXPECT_EQ(bounds.lower, (Vec3{-0.5, -0.5, -0.5}));
  EXPECT_EQ(bounds.upper, (Vec3{0.5, 1.25, 0.5}));
  Aabb top;
  for (std::size_t t = 12; t < 24; ++t)
    for (const Vec3& corner :
         {boxes.mesh.triangle(t).a, boxes.mesh.triangle(t).b, boxes.mesh.triangle(t).c})
      top.extend(corner);
  EXPECT_EQ(top.lower, (Vec3{-0.25, 0.75, -0.25}));
  EXPECT_EQ(top.upper, (Vec3{0.25, 1.25, 0.25}));
}

TEST(IoLoad, MergesObjGroupsInFileOrder) {
  TempDir dir;
  const fs::path path = dir.write("groups.obj",
                                  "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
                                  "o b\nv 5 0 0\nv 6 0 0\nv 5 1 0\nv 6 1 0\nf 4 5 7 6\n");
  const LoadedMesh loaded = loadWithStatistics(path);
  EXPECT_EQ(loaded.statistics.meshes, 2u);
  ASSERT_EQ(loaded.mesh.triangleCount(), 3u);  // the quad in two
  EXPECT_EQ(loaded.mesh.triangle(0).b, (Vec3{1, 0, 0}));
  for (std::size_t t = 1; t < 3; ++t)
    EXPECT_GE(loaded.mesh.triangle(t).a.x, 5.0);
  EXPECT_EQ(loaded.mesh.vertexCount(), 7u);
}

TEST(IoLoad, JoinsTheCornersOfABinaryStl) {
  TempDir dir;
  const fs::path path = dir / "cube.stl";
  save(unitCube(), path);
  const LoadedMesh cube = loadWithStatistics(path);
  EXPECT_EQ(cube.mesh.triangleCount(), 12u);
  EXPECT_EQ(cube.mesh.vertexCount(), 8u);
  EXPECT_EQ(cube.statistics.sourceVertices, 36u);
}

TEST(IoLoad, JoinsNegativeAndPositiveZero) {
  TempDir dir;
  const fs::path path = dir.write("zeros.obj",
                                  "v 0 0 0\nv 1 0 0\nv 0 1 0\nv -0 -0 -0\nv 0 0 1\n"
                                  "f 1 2 3\nf 4 3 5\n");
  EXPECT_EQ(load(path).vertexCount(), 4u);
}

// ----- Points and lines -----

TEST(IoLoad, SkipsAndCountsPointsAndLines) {
  ASSERT_TRUE(dataPresent(kAssimp));
  const LoadedMesh mixed = loadWithStatistics(kAssimp / "OBJ/testmixed.obj");
  EXPECT_EQ(mixed.mesh.triangleCount(), 12u);
  EXPECT_EQ(mixed.statistics.pointsSkipped, 24u);
  EXPECT_EQ(mixed.statistics.linesSkipped, 18u);

  const fs::path points = kAssimp / "OBJ/testpoints.obj";
  EXPECT_NE(loadError(points).find("no triangles, only 24 points and 0 lines"), std::string::npos);
  const fs::path lines = kAssimp / "OBJ/testline.obj";
  EXPECT_NE(loadError(lines).find("no triangles, only 0 points and 18 lines"), std::string::npos);
  // Files of vertices only: their vertices count as points.
  EXPECT_NE(loadError(kAssimp / "OBJ/point_cloud.obj").find("only 3 points"), std::string::npos);
  EXPECT_NE(loadError(kAssimp / "PLY/points.ply").find("only 4 points"), std::string::npos);
  for (const char* cloud : {"OBJ/point_cloud.obj", "PLY/points.ply"}) {
    const std::string message = loadError(kAssimp / cloud);
    EXPECT_NE(message.find("no triangles"), std::string::npos) << message;
    EXPECT_NE(message.find((kAssimp / cloud).string()), std::string::npos) << message;
  }
}

// ----- Bad input -----

TEST(IoLoad, NamesTheFileAndTheReason) {
  TempDir dir;
  const fs::path missing = dir / "missing.stl";
  EXPECT_EQ(loadError(missing), "cannot load '" + missing.string() + "': no such file");
  const fs::path folder = dir / "folder.obj";
  fs::create_directory(folder);
  EXPECT_EQ(loadError(folder),
            "cannot load '" + folder.string() + "': it is a directory, not a file");
  const fs::path empty = dir.write("empty.stl", "");
  EXPECT_EQ(loadError(empty), "cannot load '" + empty.string() + "': file is empty");
  const fs::path points = dir.write("points.obj", "v 0 0 0\nv 1 0 0\np 1\np 2\n");
  EXPECT_EQ(loadError(points), "cannot load '" + points.string() +
                                   "': the file has no triangles, only 2 points and 0 lines");
  // A PLY point cloud whose face element is declared empty (CGAL's b9.ply) said "only 0 points".
  const fs::path cloud = dir.write("cloud.ply",
                                   "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                   "property float y\nproperty float z\nelement face 0\n"
                                   "property list uchar int vertex_indices\nend_header\n"
                                   "0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_EQ(loadError(cloud), "cannot load '" + cloud.string() +
                                  "': the file has no triangles, only 3 points and 0 lines");
}

TEST(IoLoad, RejectsCoordinatesThatAreNotFinite) {
  TempDir dir;
  const std::string off = "OFF\n3 1 0\n0 0 0\n1 0 0\n";
  const std::string triangle = "\n3 0 1 2\n";
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n";
  const std::string stl = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n";
  // from_chars parses "nan" and "inf"; 1e400 overflows double.
  const std::vector<fs::path> files = {
      dir.write("nan.off", off + "nan 1 0" + triangle),
      dir.write("inf.off", off + "0 -inf 0" + triangle),
      dir.write("overflow.off", off + "0 1 1e400" + triangle),
      dir.write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 NaN 1\nf 1 2 3\n"),
      dir.write("overflow.ply", ply + "0 1e400 1\n3 0 1 2\n"),
      dir.write("nan.stl", stl + "vertex 0 nan 1\nendloop\nendfacet\nendsolid t\n"),
  };
  for (const fs::path& file : files) {
    const std::string message = loadError(file);
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_NE(message.find("not finite"), std::string::npos) << message;
  }
}

TEST(IoLoad, RejectsABinaryStlOfTheWrongSize) {
  const fs::path spider = kAssimp / "STL/Spider_binary.stl";
  ASSERT_TRUE(dataPresent(spider));
  const std::string bytes = readBytes(spider);
  ASSERT_EQ(bytes.size(), 84u + 50u * 1368u);
  std::string solidHeader = bytes;  // assimp reads a file that starts with "solid" as ascii
  solidHeader.replace(0, 6, "solid ");
  TempDir dir;
  const std::vector<fs::path> files = {
      dir.write("cut_in_a_triangle.stl", bytes.substr(0, 30000)),
      dir.write("cut_between_triangles.stl", bytes.substr(0, 84 + 50 * 600)),
      dir.write("cut_solid_header.stl", solidHeader.substr(0, 30025)),
      dir.write("header_only.stl", bytes.substr(0, 84)),
      dir.write("short.stl", bytes.substr(0, 50)),
      dir.write("padded.stl", bytes + std::string(10, '\0')),
  };
  for (const fs::path& file : files) {
    const std::string message = loadError(file);
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_NE(message.find("bytes"), std::string::npos) << message;
  }
  EXPECT_EQ(load(dir.write("whole.stl", bytes)).triangleCount(), 1368u);
}

/// A decagon, which assimp's OFF reader drops without a word (it reads at most 9 corners).
std::string decagonOff() {
  std::string off = "OFF\n10 1 0\n";
  for (int i = 0; i < 10; ++i)
    off += std::to_string(std::cos(0.2 * 3.14159 * i)) + " " +
           std::to_string(std::sin(0.2 * 3.14159 * i)) + " 0\n";
  return off + "10 0 1 2 3 4 5 6 7 8 9\n";
}

/// Files that assimp 5.2 read without an error into wrong geometry, which Δ's readers refuse
/// (mesh_readers.h). A face of more than 9 corners, which assimp's OFF reader dropped, is read
/// (ReadsADecagonAsEightTriangles).
TEST(IoLoad, RejectsDamagedFilesThatAssimpMisreads) {
  const std::string plyHeader =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  struct Case {
    const char* name;
    std::string content;
    const char* reason;
  };
  const std::vector<Case> cases = {
      {"index_out_of_range.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n",
       "refers to vertex 7"},
      {"negative_index.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 -2\n",
       "face 0 needs 3 vertex indices"},
      {"extra_face.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n", "more lines"},
      {"wrapping_count.off", "OFF\n4294967299 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "32 bits"},
      {"missing_faces.off", "OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
       "the file ends at face 1"},
      {"huge_count.off", "OFF\n353535235358 6 0\n0 0 0\n", "32 bits"},
      {"garbled_vertex.obj", "v 0 0 0\nv 1 x 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n", "line 2"},
      {"empty_face.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf\nf 1 2 3\n", "without vertices"},
      {"missing_value.ply", plyHeader + "0 0 0\n1 0\n0 1 0\n3 0 1 2\n", "fewer values"},
      {"missing_face.ply", plyHeader + "0 0 0\n1 0 0\n0 1 0\n", "ends before element 'face'"},
      {"extra_face.ply", plyHeader + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 2 1\n", "more lines"},
      {"huge_count.ply",
       "ply\nformat ascii 1.0\nelement vertex 300000000\nproperty float x\nproperty float y\n"
       "property float z\nend_header\n0 0 0\n",
       "ends before element 'vertex' 1"},
      {"cut_after_a_facet.stl",
       "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
       "endloop\nendfacet\n",
       "endsolid"},
  };
  TempDir dir;
  for (const Case& c : cases) {
    const fs::path file = dir.write(c.name, c.content);
    const auto start = std::chrono::steady_clock::now();
    const std::string message = loadError(file);
    EXPECT_LT(secondsSince(start), kSecondsPerFile) << c.name;
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_NE(message.find(c.reason), std::string::npos) << message;
  }
}

TEST(IoLoad, ReadsADecagonAsEightTriangles) {
  TempDir dir;
  const LoadedMesh decagon = loadWithStatistics(dir.write("decagon.off", decagonOff()));
  EXPECT_EQ(decagon.mesh.triangleCount(), 8u);
  EXPECT_EQ(decagon.mesh.vertexCount(), 10u);
  for (std::size_t t = 0; t < 8; ++t)
    EXPECT_GT(decagon.mesh.triangle(t).areaVector().z, 0.0) << t;  // orientation kept
}

TEST(IoLoad, RejectsATruncatedBinaryPly) {
  const fs::path cube = kAssimp / "PLY/cube_binary.ply";
  ASSERT_TRUE(dataPresent(cube));
  const std::string bytes = readBytes(cube);
  TempDir dir;
  const fs::path cut = dir.write("cut.ply", bytes.substr(0, bytes.size() - 20));
  EXPECT_NE(loadError(cut).find("binary data ends inside element 'face'"), std::string::npos);
}

TEST(IoLoad, ReadsOffWithCommentsAnywhere) {
  // Assimp's OFF reader alone takes the comment lines below for faces and drops them, with the
  // faces they push past the count, and fails on the comment after a vertex.
  TempDir dir;
  const fs::path path = dir.write("square.off",
                                  "# a comment before the header\nOFF # keyword\n\n4 3 0\n"
                                  "# comments and blank lines before the first vertex\n\n"
                                  "0 0 0\n1 0 0 # a comment after a vertex\n1 1 0\n  \n0 1 0\n"
                                  "# faces\n4 0 1 2 3 255 0 0\n# another comment\n\t\n"
                                  "3 0 2 1\r\n3 1 3 0 # last\n# the end\n");
  const Mesh square = load(path);
  EXPECT_EQ(square.triangleCount(), 4u);
  EXPECT_EQ(square.vertexCount(), 4u);
  // Assimp's triangulation may rotate the corners of a triangle in a mesh with polygons.
  EXPECT_EQ(square.triangle(3).centroid(), (Vec3{1, 1, 0} / 3.0));
  EXPECT_EQ(square.triangle(3).areaVector(), (Vec3{0, 0, 1}));
}

TEST(IoLoad, ReadsOffWithRgbColours) {
  // Assimp's OFF reader alone fails here: it wants a fourth colour value or a comment.
  TempDir dir;
  const fs::path path = dir.write("colours.off",
                                  "COFF\n3 1 0\n0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n"
                                  "3 0 1 2\n");
  EXPECT_EQ(load(path).triangleCount(), 1u);
}

TEST(IoLoad, ReadsCgalOffWithCommentsBetweenTheElements) {
  const fs::path path = kMeshes / "cube-shuffled.off";
  ASSERT_TRUE(dataPresent(path));
  EXPECT_EQ(load(path).triangleCount(), 12u);  // assimp alone gives 10
}

// ----- Threads -----

TEST(IoLoad, LoadsFromManyThreadsAgree) {
  const fs::path armadillo = kMeshes / "armadillo.off";
  const fs::path spider = kAssimp / "STL/Spider_binary.stl";
  ASSERT_TRUE(dataPresent(armadillo));
  ASSERT_TRUE(dataPresent(spider));
  const Mesh expectedArmadillo = load(armadillo);
  const Mesh expectedSpider = load(spider);
  constexpr int kThreads = 4;
  std::vector<int> agreed(kThreads, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      const Mesh a = load(armadillo);
      const Mesh s = load(spider);
      agreed[t] = std::ranges::equal(a.vertices(), expectedArmadillo.vertices()) &&
                  std::ranges::equal(a.triangles(), expectedArmadillo.triangles()) &&
                  std::ranges::equal(s.vertices(), expectedSpider.vertices()) &&
                  std::ranges::equal(s.triangles(), expectedSpider.triangles());
    });
  for (std::thread& thread : threads)
    thread.join();
  for (int t = 0; t < kThreads; ++t)
    EXPECT_TRUE(agreed[t]) << "thread " << t;
}

// ----- Saving -----

/// `x` rounded to single precision. The volatile keeps GCC 12.2 from dropping the round trip: at
/// -O2 its SLP vectoriser turns (double)(float) of two adjacent coordinates into a plain copy.
double roundedToFloat(double x) {
  const volatile float rounded = static_cast<float>(x);
  return rounded;
}

/// `actual`, read back from a file, is `expected` rounded to single precision. OBJ is text:
/// assimp writes 9 significant digits, enough to name the float, which Δ reads exactly as the
/// decimal written (`asText`): that decimal rounds to the float.
void expectRoundedToFloat(const Vec3& actual, const Vec3& expected, bool asText) {
  const auto read = [asText](double x) { return asText ? roundedToFloat(x) : x; };
  EXPECT_EQ(read(actual.x), roundedToFloat(expected.x));
  EXPECT_EQ(read(actual.y), roundedToFloat(expected.y));
  EXPECT_EQ(read(actual.z), roundedToFloat(expected.z));
}

/// A mesh with coordinates that are not floats, some negative, of varied magnitude.
Mesh randomMesh(std::size_t vertexCount, std::size_t triangleCount) {
  std::mt19937_64 random(42);
  std::uniform_real_distribution<double> coordinate(-1e3, 1e3);
  std::vector<Vec3> vertices(vertexCount);
  for (Vec3& v : vertices)
    v = {coordinate(random), coordinate(random) * 1e-4, coordinate(random) * 1e4};
  std::uniform_int_distribution<std::uint32_t> index(0,
                                                     static_cast<std::uint32_t>(vertexCount - 1));
  std::vector<TriangleIndices> triangles(triangleCount);
  for (TriangleIndices& t : triangles)
    t = {index(random), index(random), index(random)};
  return Mesh(std::move(vertices), std::move(triangles));
}

TEST(IoSave, RoundTripKeepsTrianglesInOrder) {
  const Mesh original = randomMesh(500, 1000);
  TempDir dir;
  for (const char* name : {"mesh.stl", "mesh.ply", "mesh.obj", "MESH.STL", "mesh.Ply"}) {
    const fs::path path = dir / name;
    save(original, path);
    const Mesh back = load(path);
    ASSERT_EQ(back.triangleCount(), original.triangleCount()) << name;
    for (std::size_t t = 0; t < original.triangleCount(); ++t) {
      const Triangle expected = original.triangle(t);
      const Triangle actual = back.triangle(t);
      SCOPED_TRACE(std::string(name) + " triangle " + std::to_string(t));
      if (std::string_view(name).ends_with(".obj")) {  // text: every double exactly
        EXPECT_EQ(actual.a, expected.a);
        EXPECT_EQ(actual.b, expected.b);
        EXPECT_EQ(actual.c, expected.c);
        continue;
      }
      expectRoundedToFloat(actual.a, expected.a, false);
      expectRoundedToFloat(actual.b, expected.b, false);
      expectRoundedToFloat(actual.c, expected.c, false);
    }
  }
  EXPECT_FALSE(fs::exists(dir / "mesh.mtl"));
}

TEST(IoSave, AnObjFileHoldsEveryDoubleExactly) {
  // assimp's OBJ exporter wrote nine significant digits: 0.8183823522853823 came back as
  // 0.818382323. Coordinates single precision cannot hold (1e300, 1e-100) come back too.
  const Mesh mesh({{0.8183823522853823, 0.1, 1e300}, {1e-100, -0.0, 5e-324}, {0.0, 1.0, 0.3}},
                  {{0, 1, 2}});
  TempDir dir;
  save(mesh, dir / "exact.obj");
  const Mesh back = load(dir / "exact.obj");
  ASSERT_EQ(back.vertexCount(), 3u);
  for (std::size_t v = 0; v < 3; ++v)
    EXPECT_EQ(std::memcmp(&back.vertices()[v], &mesh.vertices()[v], sizeof(Vec3)), 0) << v;
}

TEST(IoSave, NamesTheFileAndTheReason) {
  TempDir dir;
  const fs::path unknown = dir / "mesh.xyz";
  try {
    save(unitCube(), unknown);
    ADD_FAILURE() << "saving to .xyz did not throw";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find("cannot save '" + unknown.string() + "'"),
              std::string::npos);
    EXPECT_NE(std::string(error.what()).find("unknown extension '.xyz'"), std::string::npos);
  }
  const fs::path unwritable = dir / "no_such_folder" / "mesh.stl";
  try {
    save(unitCube(), unwritable);
    ADD_FAILURE() << "saving into a missing folder did not throw";
  } catch (const Error& error) {
    EXPECT_NE(std::string(error.what()).find(unwritable.string()), std::string::npos);
  }
}

TEST(IoSave, RejectsCoordinatesBeyondSinglePrecision) {
  Mesh huge = unitCube();
  huge.scale(1e300);
  TempDir dir;
  EXPECT_THROW(save(huge, dir / "huge.stl"), Error);
}

TEST(IoSave, RejectsAMeshBelowSinglePrecisionsNormalRange) {
  // A cube of side 1e-100 was written as one vertex at the origin and twelve collapsed faces.
  // (An .obj holds every double: AnObjFileHoldsEveryDoubleExactly.)
  TempDir dir;
  for (const char* name : {"tiny.stl", "tiny.ply"}) {
    Mesh tiny = unitCube();
    tiny.scale(1e-100);
    EXPECT_THROW(save(tiny, dir / name), Error) << name;
    EXPECT_FALSE(std::filesystem::exists(dir / name)) << name;
    // At the bottom of the normal range (side 2^-100), the file holds the cube.
    Mesh small = unitCube();
    small.scale(0x1p-100);
    save(small, dir / name);
    const Mesh back = load(dir / name);
    EXPECT_EQ(back.vertexCount(), small.vertexCount()) << name;
    EXPECT_NEAR(back.bounds().upper.x / small.bounds().upper.x, 1.0, 1e-6) << name;
  }
}

}  // namespace
}  // namespace delta::io
