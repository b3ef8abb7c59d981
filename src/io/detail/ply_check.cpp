#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "delta/core/error.h"
#include "delta/io/detail/format_checks.h"
#include "delta/io/detail/text_scan.h"

namespace delta::io::detail {
namespace {

enum class PlyEncoding { ascii, littleEndian, bigEndian };

struct PlyProperty {
  std::size_t valueBytes = 0;  ///< bytes of one value (of each list item, for a list)
  std::size_t countBytes = 0;  ///< bytes of a list's length; 0 for a scalar property
  bool countSigned = false;
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::ascii;
  std::vector<PlyElement> elements;
};

[[noreturn]] void fail(const std::string& what) {
  throw Error(what);
}
[[noreturn]] void failAtLine(std::size_t line, const std::string& what) {
  fail("line " + std::to_string(line) + ": " + what);
}

struct PlyType {
  std::size_t bytes = 0;  ///< 0: not a PLY type
  bool isSigned = false;
  bool isInteger = false;
};

PlyType plyType(std::string_view name) {
  if (name == "char" || name == "int8") return {1, true, true};
  if (name == "uchar" || name == "uint8") return {1, false, true};
  if (name == "short" || name == "int16") return {2, true, true};
  if (name == "ushort" || name == "uint16") return {2, false, true};
  if (name == "int" || name == "int32") return {4, true, true};
  if (name == "uint" || name == "uint32") return {4, false, true};
  if (name == "float" || name == "float32") return {4, true, false};
  if (name == "double" || name == "float64") return {8, true, false};
  return {};
}

PlyType requireType(std::string_view name, std::size_t line) {
  const PlyType type = plyType(name);
  if (type.bytes == 0) failAtLine(line, "unknown property type '" + excerpt(name) + "'");
  return type;
}

PlyProperty readProperty(std::string_view rest, std::size_t line) {
  const std::string_view type = takeToken(rest);
  if (type != "list") return {requireType(type, line).bytes, 0, false};
  const PlyType count = requireType(takeToken(rest), line);
  if (!count.isInteger) failAtLine(line, "a list's length must have an integer type");
  return {requireType(takeToken(rest), line).bytes, count.bytes, count.isSigned};
}

PlyElement readElement(std::string_view rest, std::size_t line) {
  PlyElement element;
  element.name = std::string(takeToken(rest));
  const std::string_view countToken = takeToken(rest);
  const std::optional<std::uint64_t> count = parseUnsigned(countToken);
  if (!count) failAtLine(line, "element '" + element.name + "' has no count");
  if (*count > std::numeric_limits<std::uint32_t>::max())
    failAtLine(line, "element '" + element.name + "' count " + std::string(countToken) +
                         " does not fit in 32 bits");
  element.count = *count;
  return element;
}

PlyEncoding readFormat(std::string_view rest, std::size_t line) {
  const std::string_view format = takeToken(rest);
  if (format == "ascii") return PlyEncoding::ascii;
  if (format == "binary_little_endian") return PlyEncoding::littleEndian;
  if (format == "binary_big_endian") return PlyEncoding::bigEndian;
  failAtLine(line, "unknown PLY format '" + excerpt(format) + "'");
}

/// Reads the header up to `end_header`; `lines` is left at that line.
PlyHeader readHeader(LineReader& lines) {
  const std::optional<std::string_view> magic = lines.next();
  if (!magic || trimBlanks(*magic) != "ply") fail("the file does not start with 'ply'");
  PlyHeader header;
  bool hasFormat = false;
  for (std::optional<std::string_view> line = lines.next(); line; line = lines.next()) {
    std::string_view rest = *line;
    const std::string_view keyword = takeToken(rest);
    const std::size_t number = lines.lineNumber();
    if (keyword == "end_header") {
      if (!hasFormat) failAtLine(number, "the header has no 'format' line");
      return header;
    }
    if (keyword == "format") {
      header.encoding = readFormat(rest, number);
      hasFormat = true;
    } else if (keyword == "element") {
      header.elements.push_back(readElement(rest, number));
    } else if (keyword == "property") {
      if (header.elements.empty()) failAtLine(number, "a property before any element");
      header.elements.back().properties.push_back(readProperty(rest, number));
    }  // other lines ("comment", "obj_info", a bare remark) carry no structure
  }
  fail("the header has no 'end_header' line");
}

std::string elementName(const PlyElement& element, std::uint64_t index) {
  return "element '" + element.name + "' " + std::to_string(index) + " (of " +
         std::to_string(element.count) + ")";
}

void checkAsciiInstance(std::string_view line, const PlyElement& element, std::uint64_t index,
                        std::size_t lineNumber) {
  std::string_view rest = line;
  const auto requireNumber = [&](std::string_view token) {
    if (!startsLikeNumber(token))
      failAtLine(lineNumber, elementName(element, index) + " has fewer values than its header " +
                                 "declares, or one is not a number: '" + excerpt(line) + "'");
  };
  for (const PlyProperty& property : element.properties) {
    const std::string_view token = takeToken(rest);
    requireNumber(token);
    if (property.countBytes == 0) continue;
    const std::optional<std::uint64_t> length = parseUnsigned(token);
    if (!length)
      failAtLine(lineNumber, "a list length in " + elementName(element, index) +
                                 " is not a count: '" + excerpt(token) + "'");
    for (std::uint64_t item = 0; item < *length; ++item)
      requireNumber(takeToken(rest));
  }
  if (!trimBlanks(rest).empty())
    failAtLine(lineNumber, elementName(element, index) +
                               " has more values than its header declares: '" + excerpt(line) +
                               "'");
}

/// Non-blank lines; assimp reads one element a line.
std::optional<std::string_view> nextContentLine(LineReader& lines) {
  std::optional<std::string_view> line = lines.next();
  while (line && trimBlanks(*line).empty())
    line = lines.next();
  return line;
}

void checkAsciiBody(const PlyHeader& header, LineReader& lines) {
  for (const PlyElement& element : header.elements)
    for (std::uint64_t index = 0; index < element.count; ++index) {
      const std::optional<std::string_view> line = nextContentLine(lines);
      if (!line) fail("the file ends before " + elementName(element, index));
      checkAsciiInstance(*line, element, index, lines.lineNumber());
    }
  if (nextContentLine(lines))
    failAtLine(lines.lineNumber(), "more lines than the elements the header announces");
}

/// Walks the binary body, element by element, without reading the values themselves.
class BinaryBody {
 public:
  BinaryBody(std::string_view bytes, PlyEncoding encoding) : bytes_(bytes), encoding_(encoding) {}

  void skipElements(const PlyElement& element) {
    std::size_t fixedBytes = 0;
    bool hasList = false;
    for (const PlyProperty& property : element.properties) {
      fixedBytes += property.countBytes == 0 ? property.valueBytes : 0;
      hasList = hasList || property.countBytes != 0;
    }
    if (!hasList) {  // all instances alike: one bound, no loop
      if (fixedBytes != 0 && element.count > left() / fixedBytes)
        fail("the binary data ends inside " + elementName(element, left() / fixedBytes));
      offset_ += static_cast<std::size_t>(element.count) * fixedBytes;
      return;
    }
    for (std::uint64_t index = 0; index < element.count; ++index)
      for (const PlyProperty& property : element.properties)
        skipProperty(property, element, index);
  }

  std::size_t left() const noexcept { return bytes_.size() - offset_; }
  std::size_t offset() const noexcept { return offset_; }

 private:
  void skipProperty(const PlyProperty& property, const PlyElement& element, std::uint64_t index) {
    if (property.countBytes == 0) return skip(property.valueBytes, element, index);
    skip(property.countBytes, element, index);
    const std::int64_t length = readLength(property, offset_ - property.countBytes);
    if (length < 0)
      fail(elementName(element, index) + " has a list of length " + std::to_string(length));
    const std::uint64_t items = static_cast<std::uint64_t>(length);
    if (items > left() / property.valueBytes)
      fail("the binary data ends inside " + elementName(element, index));
    offset_ += static_cast<std::size_t>(items) * property.valueBytes;
  }

  void skip(std::size_t count, const PlyElement& element, std::uint64_t index) {
    if (count > left()) fail("the binary data ends inside " + elementName(element, index));
    offset_ += count;
  }

  std::int64_t readLength(const PlyProperty& property, std::size_t at) const {
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < property.countBytes; ++i) {
      const std::size_t byte =
          encoding_ == PlyEncoding::bigEndian ? i : property.countBytes - 1 - i;
      value = (value << 8) | static_cast<unsigned char>(bytes_[at + byte]);
    }
    const std::uint64_t signBit = std::uint64_t{1} << (8 * property.countBytes - 1);
    if (property.countSigned && (value & signBit) != 0)
      return static_cast<std::int64_t>(value) - static_cast<std::int64_t>(signBit << 1);
    return static_cast<std::int64_t>(value);
  }

  std::string_view bytes_;
  PlyEncoding encoding_;
  std::size_t offset_ = 0;
};

/// The binary body starts after the line end of `end_header`.
std::string_view binaryBody(std::string_view rest) {
  if (rest.starts_with("\r\n")) return rest.substr(2);
  if (rest.starts_with('\n') || rest.starts_with('\r')) return rest.substr(1);
  return rest;
}

void checkBinaryBody(const PlyHeader& header, std::string_view body) {
  BinaryBody walker(body, header.encoding);
  for (const PlyElement& element : header.elements)
    walker.skipElements(element);
  if (walker.left() != 0)
    fail(std::to_string(walker.left()) + " bytes follow the elements the header announces (" +
         std::to_string(walker.offset()) + " bytes of binary data expected)");
}

}  // namespace

void checkPly(std::string_view bytes) {
  LineReader lines(bytes);
  const PlyHeader header = readHeader(lines);
  if (header.encoding == PlyEncoding::ascii) {
    requireText(lines.rest());
    checkAsciiBody(header, lines);
  } else {
    checkBinaryBody(header, binaryBody(lines.rest()));
  }
}

}  // namespace delta::io::detail
