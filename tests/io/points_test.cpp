#include "delta/io/points.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "delta/core/error.h"

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

TEST(Points, MissingFileAndDirectoryFail) {
  EXPECT_NE(loadError("/nonexistent/points.xyz").find("cannot open"), std::string::npos);
  EXPECT_NE(loadError(fs::temp_directory_path()).find("directory"), std::string::npos);
}

}  // namespace
}  // namespace delta::io
