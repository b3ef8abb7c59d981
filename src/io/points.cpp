#include "delta/io/points.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <string>
#include <string_view>

#include "delta/core/error.h"

namespace delta::io {
namespace {

bool isSeparator(char c) {
  return c == ' ' || c == '\t' || c == ',' || c == '\r';
}

/// The next number of `line` from `position`, or false if there is none or it is malformed.
bool nextNumber(std::string_view line, std::size_t& position, double& value) {
  while (position < line.size() && isSeparator(line[position]))
    ++position;
  if (position == line.size()) return false;
  const char* begin = line.data() + position;
  const char* end = line.data() + line.size();
  if (*begin == '+') ++begin;  // from_chars does not take a leading '+'
  const auto [stop, status] = std::from_chars(begin, end, value);
  if (status != std::errc() || (stop != end && !isSeparator(*stop))) return false;
  position = static_cast<std::size_t>(stop - line.data());
  return true;
}

bool isBlankOrComment(std::string_view line) {
  for (char c : line) {
    if (c == '#') return true;
    if (!isSeparator(c)) return false;
  }
  return true;
}

Vec3 parseLine(std::string_view line, std::size_t number) {
  Vec3 point;
  std::size_t position = 0;
  for (int axis = 0; axis < 3; ++axis)
    if (!nextNumber(line, position, point[static_cast<std::size_t>(axis)]))
      throw Error("line " + std::to_string(number) + " is not three numbers 'x y z': '" +
                  std::string(line.substr(0, 80)) + "'");
  while (position < line.size() && isSeparator(line[position]))
    ++position;
  if (position != line.size())
    throw Error("line " + std::to_string(number) + " has more than three numbers: '" +
                std::string(line.substr(0, 80)) + "'");
  if (!isFinite(point))
    throw Error("line " + std::to_string(number) + " has a coordinate that is not finite: '" +
                std::string(line.substr(0, 80)) + "'");
  return point;
}

}  // namespace

std::vector<Vec3> loadPoints(const std::filesystem::path& path) {
  try {
    if (std::filesystem::is_directory(path)) throw Error("it is a directory, not a file");
    std::ifstream file(path);
    if (!file) throw Error("cannot open it for reading");
    std::vector<Vec3> points;
    std::string line;
    for (std::size_t number = 1; std::getline(file, line); ++number)
      if (!isBlankOrComment(line)) points.push_back(parseLine(line, number));
    if (file.bad()) throw Error("reading failed");
    if (points.empty()) throw Error("it holds no points");
    return points;
  } catch (const Error& error) {
    throw Error("cannot load points from '" + path.string() + "': " + error.what());
  }
}

}  // namespace delta::io
