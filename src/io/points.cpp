#include "delta/io/points.h"

#include <cctype>
#include <charconv>
#include <cmath>
#include <string>
#include <string_view>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/io/regular_file.h"
#include "delta/mesh/coordinate_range.h"

#include "detail/text_scan.h"

namespace delta::io {
namespace {

/// A line of three numbers needs no more than 3 × 24 characters; comments may be longer, but a
/// line past this size is no points file's.
constexpr std::size_t kMaxLineBytes = 4096;
constexpr std::uintmax_t kChunkBytes = std::uintmax_t{1} << 20;

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
                  printable(line) + "'");
  while (position < line.size() && isSeparator(line[position]))
    ++position;
  if (position != line.size())
    throw Error("line " + std::to_string(number) + " has more than three numbers: '" +
                printable(line) + "'");
  if (!isFinite(point))
    throw Error("line " + std::to_string(number) + " has a coordinate that is not finite: '" +
                printable(line) + "'");
  // Refused here, by its line, rather than by the query that would refuse it by its index in
  // whatever batch it came in.
  if (!inCoordinateRange(point))
    throw Error("line " + std::to_string(number) + " has a coordinate beyond " +
                coordinateRangeText() + ", the range in which Δ's distances are exact: '" +
                printable(line) + "'");
  return point;
}

}  // namespace

std::vector<Vec3> loadPoints(const std::filesystem::path& path) {
  try {
    const RegularFile file(path);
    std::vector<Vec3> points;
    std::string line;  // a line cut across two chunks
    std::size_t number = 1;
    const auto takeLine = [&](std::string_view text) {
      if (text.size() > kMaxLineBytes)
        throw Error("line " + std::to_string(number) + " is longer than " +
                    std::to_string(kMaxLineBytes) + " bytes: not a line of three numbers");
      if (!isBlankOrComment(text)) points.push_back(parseLine(text, number));
      ++number;
    };
    // Read in chunks, so that memory is bounded by the points, not by the file (a line without
    // an end is refused once it passes kMaxLineBytes, not read whole).
    for (std::uintmax_t offset = 0; offset < file.size(); offset += kChunkBytes) {
      const std::string chunk = file.read(offset, kChunkBytes);
      if (chunk.empty()) break;  // the file shrank
      std::string_view rest = offset == 0 ? detail::withoutByteOrderMark(chunk) : chunk;
      for (std::size_t end = rest.find('\n'); end != rest.npos; end = rest.find('\n')) {
        if (line.empty()) {
          takeLine(rest.substr(0, end));
        } else {
          line.append(rest.substr(0, end));
          takeLine(line);
          line.clear();
        }
        rest.remove_prefix(end + 1);
      }
      line.append(rest);
      if (line.size() > kMaxLineBytes) takeLine(line);  // throws
    }
    if (!line.empty()) takeLine(line);
    if (points.empty()) throw Error("it holds no points");
    return points;
  } catch (const Error& error) {
    throw Error("cannot load points from '" + printable(path.string(), 4096) +
                "': " + error.what());
  }
}

}  // namespace delta::io
