// assimp's readers run in a child process (io/detail/isolated_import.h): files that crash assimp
// in-process give a delta::Error, and this process survives.
#include "io/detail/isolated_import.h"

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "delta/core/error.h"
#include "delta/io/mesh_io.h"

#include "io/test_files.h"
#include "sanitized.h"

// The sanitizers' runtimes (DELTA_TESTS_SANITIZED): their shadow memory rules out an
// address-space limit, and their allocators (AddressSanitizer's, LLVM 14's ThreadSanitizer's) do
// not take their locks around fork(), so a child forked while another thread allocates can wait
// forever.

namespace delta::io {
namespace {

namespace fs = std::filesystem;

const fs::path kAssimp = fs::path(DELTA_DATA_DIR) / "assimp";

/// Mutations of assimp's test models that crash assimp 5.2 in-process with SIGSEGV (found by
/// truncating and flipping bytes, each checked by a standalone fork-per-file run).
std::vector<std::pair<std::string, std::string>> crashingModels() {
  const std::string md5 = readBytes(kAssimp / "MD5/SimpleCube.md5mesh");
  std::string ase = readBytes(kAssimp / "ASE/ThreeCubesGreen.ASE");
  std::mt19937 random(7);  // 8 bytes overwritten at random places
  for (int k = 0; k < 8; ++k) {
    const std::size_t at = random() % ase.size();
    ase[at] = static_cast<char>(random());
  }
  return {{"cut.md5mesh", md5.substr(0, md5.size() * 11 / 20)}, {"flipped.ase", ase}};
}

TEST(IsolatedImport, FilesThatCrashAssimpAreErrors) {
  ASSERT_TRUE(fs::exists(kAssimp / "MD5/SimpleCube.md5mesh"));
  TempDir folder;
  for (const auto& [name, bytes] : crashingModels()) {
    const fs::path path = folder.write(name, bytes);
    const std::string message = loadError(path);
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
    EXPECT_NE(message.find("assimp crashed (signal " + std::to_string(SIGSEGV)), std::string::npos)
        << message;
  }
  // This process survived, and assimp still reads good files.
  const LoadedMesh box = loadWithStatistics(kAssimp / "glTF2/BoxTextured-glTF/BoxTextured.gltf");
  EXPECT_EQ(box.mesh.triangleCount(), 12u);
  EXPECT_EQ(box.statistics.precision, CoordinatePrecision::single);
}

TEST(IsolatedImport, CrashingFilesFromManyThreads) {
#ifdef DELTA_TESTS_SANITIZED
  // A child forked while another thread allocates can wait on a sanitizer allocator's lock that
  // no thread will release (glibc's malloc, in the other builds, resets its locks in the child).
  GTEST_SKIP() << "fork() from several threads can deadlock in the sanitizers' allocators";
#endif
  TempDir folder;
  const auto models = crashingModels();
  const fs::path crashing = folder.write(models[0].first, models[0].second);
  const fs::path box = kAssimp / "glTF2/BoxTextured-glTF/BoxTextured.gltf";
  constexpr int kThreads = 4;
  std::vector<int> ok(kThreads, 0);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t)
    threads.emplace_back([&, t] {
      for (int round = 0; round < 3; ++round) {
        try {
          load(crashing);
          return;
        } catch (const Error&) {
        }
        if (load(box).triangleCount() != 12u) return;
      }
      ok[t] = 1;
    });
  for (std::thread& thread : threads)
    thread.join();
  for (int t = 0; t < kThreads; ++t)
    EXPECT_TRUE(ok[t]) << "thread " << t;
}

detail::TriangleSoup oneTriangle() {
  detail::TriangleSoup soup;
  soup.positions = {{0.1, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  soup.triangles = {{0, 1, 2}};
  soup.statistics.meshes = 1;
  soup.statistics.pointsSkipped = 7;
  return soup;
}

std::string isolatedError(const std::function<detail::TriangleSoup()>& import,
                          const detail::IsolationLimits& limits = {}) {
  try {
    detail::runIsolated(import, limits);
  } catch (const Error& error) {
    return error.what();
  }
  ADD_FAILURE() << "runIsolated did not throw";
  return {};
}

TEST(IsolatedImport, PassesTheSoupAndTheErrorsBack) {
  const detail::TriangleSoup soup = detail::runIsolated(oneTriangle, {});
  EXPECT_EQ(soup.positions, oneTriangle().positions);
  EXPECT_EQ(soup.triangles, oneTriangle().triangles);
  EXPECT_EQ(soup.statistics.pointsSkipped, 7u);
  EXPECT_EQ(soup.statistics.precision, CoordinatePrecision::single);
  EXPECT_EQ(isolatedError([]() -> detail::TriangleSoup { throw Error("a reason"); }), "a reason");
  EXPECT_NE(isolatedError([]() -> detail::TriangleSoup {
              std::abort();
            }).find("signal " + std::to_string(SIGABRT)),
            std::string::npos);
}

TEST(IsolatedImport, StopsAChildThatHangs) {
  const auto start = std::chrono::steady_clock::now();
  const std::string message = isolatedError(
      []() -> detail::TriangleSoup {
        for (;;)
          ::pause();
      },
      {0, 60, 1});
  EXPECT_NE(message.find("did not finish reading it within 1 s"), std::string::npos) << message;
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
}

#ifndef DELTA_TESTS_SANITIZED  // the sanitizers' shadow memory rules out an address-space limit
TEST(IsolatedImport, LimitsTheChildsMemory) {
  const std::string message = isolatedError(
      []() -> detail::TriangleSoup {
        std::vector<char> huge(std::size_t{64} << 30, 'x');  // 64 GiB
        return {};
      },
      {std::uint64_t{1} << 30, 60, 60});
  EXPECT_NE(message.find("out of memory"), std::string::npos) << message;
}
#endif

}  // namespace
}  // namespace delta::io
