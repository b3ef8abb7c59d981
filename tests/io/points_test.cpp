#include "delta/io/points.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/mesh/coordinate_range.h"

namespace delta::io {
namespace {

namespace fs = std::filesystem;

fs::path writeFile(const std::string& name, const std::string& text) {
  const fs::path path =
      fs::temp_directory_path() / ("delta_points_" + std::to_string(::getpid()) + "_" + name);
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

std::string loadError(const fs::path& path) {
  try {
    loadPoints(path);
  } catch (const Error& error) {
    return error.what();
  }
  return "no error";
}

TEST(Points, ReadsSeparatorsCommentsAndFormats) {
  const fs::path path = writeFile("good.xyz",
                                  "# x y z\n"
                                  "0 0 0\n"
                                  "\n"
                                  "1.5\t-2e3  +3\r\n"
                                  "  4,5,6  \n"
                                  "1e-300 8 7");  // no final newline
  const std::vector<Vec3> points = loadPoints(path);
  fs::remove(path);
  ASSERT_EQ(points.size(), 4u);
  EXPECT_EQ(points[1], (Vec3{1.5, -2000, 3}));
  EXPECT_EQ(points[2], (Vec3{4, 5, 6}));
  EXPECT_EQ(points[3].x, 1e-300);
}

TEST(Points, AByteOrderMarkAtTheStartIsNotContent) {
  // "line 1 is not three numbers" named a line that looked right: U+FEFF was invisible in it.
  const fs::path path = writeFile("bom.xyz",
                                  "\xEF\xBB\xBF"
                                  "0.5 1 2\n3 4 5\n");
  const std::vector<Vec3> points = loadPoints(path);
  fs::remove(path);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[0], (Vec3{0.5, 1, 2}));
}

TEST(Points, MalformedLinesAreNamedByNumber) {
  const struct {
    const char* text;
    const char* expected;
  } cases[] = {
      {"0 0 0\n1 2\n", "line 2 is not three numbers"},
      {"0 0 0\n\n1 2 x\n", "line 3 is not three numbers"},
      {"1 2 3 4\n", "line 1 has more than three numbers"},
      {"1 nan 3\n", "line 1"},
      {"1 2 inf\n", "line 1"},
      {"1 2 1e999\n", "line 1"},
      {"1..2 0 0\n", "line 1"},
      {"# only a comment\n\n", "holds no points"},
      {"", "holds no points"},
  };
  for (const auto& c : cases) {
    const fs::path path = writeFile("bad.xyz", c.text);
    const std::string message = loadError(path);
    fs::remove(path);
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.text << " → " << message;
    EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  }
}

TEST(Points, BinaryBytesAreQuotedInHexNotWrittenRaw) {
  // Garbage in a points file was echoed to the terminal; a NUL cut the message short.
  const fs::path path = writeFile("binary.xyz", std::string("0 0 0\n1 \x1B[2J\0\xFF 2\n", 17));
  const std::string message = loadError(path);
  fs::remove(path);
  EXPECT_NE(message.find("line 2 is not three numbers 'x y z': '1 \\x1B[2J\\x00\\xFF 2"),
            std::string::npos)
      << message;
  for (char c : message)
    EXPECT_TRUE(static_cast<unsigned char>(c) >= 0x20) << message;
  // And so is a path (a config names one).
  EXPECT_NE(loadError("/nonexistent/\x1B[2J.xyz").find("'/nonexistent/\\x1B[2J.xyz'"),
            std::string::npos);
}

TEST(Points, CoordinatesBeyondTheQueriesRangeAreNamedByLine) {
  // ±2^200 (kLargestCoordinate) is the last coordinate the queries answer exactly; the next
  // double beyond is refused by its line, not later by a query that knows only its index.
  const fs::path edge = writeFile("edge.xyz", "0 0 0\n-1.6069380442589903e+60 0 1\n");
  const std::vector<Vec3> points = loadPoints(edge);
  fs::remove(edge);
  ASSERT_EQ(points.size(), 2u);
  EXPECT_EQ(points[1].x, -kLargestCoordinate);
  for (const char* beyond : {"0 0 0\n1 -1.6069380442589907e+60 0\n", "0 0 0\n1 2 1e300\n"}) {
    const fs::path path = writeFile("beyond.xyz", beyond);
    const std::string message = loadError(path);
    fs::remove(path);
    EXPECT_NE(message.find("line 2 has a coordinate beyond ±2^200"), std::string::npos) << message;
  }
}

TEST(Points, MissingFileAndDirectoryFail) {
  EXPECT_NE(loadError("/nonexistent/points.xyz").find("no such file"), std::string::npos);
  EXPECT_NE(loadError(fs::temp_directory_path()).find("directory"), std::string::npos);
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

TEST(Points, RefusesFifosDevicesAndEndlessLinesAtOnce) {
  const fs::path fifo =
      fs::temp_directory_path() / ("delta_points_fifo_" + std::to_string(std::random_device{}()));
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto start = std::chrono::steady_clock::now();
  const std::string fifoMessage = loadError(fifo);  // blocked forever before
  fs::remove(fifo);
  EXPECT_NE(fifoMessage.find("FIFO"), std::string::npos) << fifoMessage;
  EXPECT_NE(loadError("/dev/zero").find("not a regular file"), std::string::npos);
  // A 3 GiB sparse file: one line of zeros without an end, refused after its first 4 KiB.
  const fs::path sparse =
      fs::temp_directory_path() / ("delta_points_sparse_" + std::to_string(std::random_device{}()));
  {
    const int fd = ::open(sparse.c_str(), O_CREAT | O_WRONLY, 0600);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::ftruncate(fd, off_t{3} << 30), 0);
    ::close(fd);
  }
  const std::string sparseMessage = loadError(sparse);
  fs::remove(sparse);
  EXPECT_NE(sparseMessage.find("line 1 is longer than 4096 bytes"), std::string::npos)
      << sparseMessage;
  EXPECT_LT(secondsSince(start), 1.0);
}

TEST(Points, LinesAcrossReadChunksAreWhole) {
  // More than one 1 MiB chunk: lines cut by the chunk boundary are joined.
  std::string text;
  std::size_t count = 0;
  while (text.size() < (std::size_t{3} << 20)) {
    text += std::to_string(count) + ".25 -0.1 1e-3\n";
    ++count;
  }
  const fs::path path = writeFile("chunks.xyz", text + "7 8 9");  // no final line end
  const std::vector<Vec3> points = loadPoints(path);
  fs::remove(path);
  ASSERT_EQ(points.size(), count + 1);
  for (std::size_t i = 0; i < count; ++i)
    ASSERT_EQ(points[i], (Vec3{static_cast<double>(i) + 0.25, -0.1, 1e-3})) << i;
  EXPECT_EQ(points.back(), (Vec3{7, 8, 9}));
}

}  // namespace
}  // namespace delta::io
