#include "reader_support.h"

#include <cmath>

#include "delta/core/error.h"

#include "text_scan.h"

namespace delta::detail {

void failAtLine(std::size_t line, const std::string& what) {
  throw Error("line " + std::to_string(line) + ": " + what);
}

double parseCoordinate(std::string_view token, std::size_t line) {
  const ParsedReal parsed = parseReal(token);
  if (parsed.status == RealStatus::notANumber)
    failAtLine(line, "the coordinate '" + excerpt(token) + "' is not a number");
  if (parsed.status == RealStatus::outOfRange) {
    const std::size_t exponent = token.find_first_of("eE");
    if (exponent != token.npos && token.substr(exponent + 1).starts_with('-'))
      failAtLine(line, "the coordinate '" + excerpt(token) +
                           "' is too small for double: it would be rounded to zero");
    failAtLine(line, "the coordinate '" + excerpt(token) +
                         "' is beyond the range of double: it is not finite there");
  }
  if (!std::isfinite(parsed.value))
    failAtLine(line, "the coordinate '" + excerpt(token) + "' is not finite");
  return parsed.value;
}

void requireVertexIndex(std::uint64_t index, std::uint64_t count, std::size_t line,
                        const std::string& what) {
  if (index >= count)
    failAtLine(line, what + " refers to vertex " + std::to_string(index) + ", but there are only " +
                         std::to_string(count) + " vertices");
}

}  // namespace delta::detail
