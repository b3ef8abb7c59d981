// PLY after Greg Turk's format description (ascii, binary little and big endian).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "delta/core/error.h"

#include "mesh_readers.h"
#include "reader_support.h"
#include "soup_builder.h"
#include "text_scan.h"

namespace delta::detail {
namespace {

enum class PlyEncoding { ascii, littleEndian, bigEndian };

enum class ScalarKind { signedInteger, unsignedInteger, real };

struct PlyType {
  std::size_t bytes = 0;  ///< 0: not a PLY type
  ScalarKind kind = ScalarKind::real;
};

struct PlyProperty {
  std::string name;
  PlyType value;  ///< the value's type (each item's, for a list)
  PlyType count;  ///< the list length's type; bytes 0 for a scalar property
  bool isList() const noexcept { return count.bytes != 0; }
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  std::size_t headerLine = 0;
};

struct PlyHeader {
  PlyEncoding encoding = PlyEncoding::ascii;
  std::vector<PlyElement> elements;
};

[[noreturn]] void fail(const std::string& what) {
  throw Error(what);
}

PlyType plyType(std::string_view name) {
  using enum ScalarKind;
  if (name == "char" || name == "int8") return {1, signedInteger};
  if (name == "uchar" || name == "uint8") return {1, unsignedInteger};
  if (name == "short" || name == "int16") return {2, signedInteger};
  if (name == "ushort" || name == "uint16") return {2, unsignedInteger};
  if (name == "int" || name == "int32") return {4, signedInteger};
  if (name == "uint" || name == "uint32") return {4, unsignedInteger};
  if (name == "float" || name == "float32") return {4, real};
  if (name == "double" || name == "float64") return {8, real};
  return {};
}

PlyType requireType(std::string_view name, std::size_t line) {
  const PlyType type = plyType(name);
  if (type.bytes == 0) failAtLine(line, "unknown property type '" + excerpt(name) + "'");
  return type;
}

PlyProperty readProperty(std::string_view rest, std::size_t line) {
  PlyProperty property;
  const std::string_view type = takeToken(rest);
  if (type == "list") {
    property.count = requireType(takeToken(rest), line);
    if (property.count.kind == ScalarKind::real)
      failAtLine(line, "a list's length must have an integer type");
    property.value = requireType(takeToken(rest), line);
  } else {
    property.value = requireType(type, line);
  }
  property.name = std::string(takeToken(rest));
  return property;
}

PlyElement readElement(std::string_view rest, std::size_t line) {
  PlyElement element;
  element.name = std::string(takeToken(rest));
  element.headerLine = line;
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

/// Where the mesh's values are: the vertex element's coordinate properties and the face
/// element's index list.
struct MeshLayout {
  const PlyElement* vertex = nullptr;
  std::size_t coordinate[3] = {0, 0, 0};  ///< property index of x, y, z
  const PlyElement* face = nullptr;
  std::size_t indices = 0;  ///< property index of the face's vertex_indices
};

MeshLayout findLayout(const PlyHeader& header) {
  MeshLayout layout;
  for (const PlyElement& element : header.elements) {
    if (element.name == "vertex" && layout.vertex == nullptr) layout.vertex = &element;
    if (element.name == "face" && layout.face == nullptr) {
      if (layout.vertex == nullptr)
        failAtLine(element.headerLine, "the 'face' element comes before the 'vertex' element");
      layout.face = &element;
    }
  }
  if (layout.vertex == nullptr) fail("the header has no 'vertex' element");
  const auto find = [](const PlyElement& element, auto accept) -> std::optional<std::size_t> {
    for (std::size_t p = 0; p < element.properties.size(); ++p)
      if (accept(element.properties[p])) return p;
    return std::nullopt;
  };
  for (std::size_t axis = 0; axis < 3; ++axis) {
    const std::string name(1, "xyz"[axis]);
    const std::optional<std::size_t> at =
        find(*layout.vertex, [&](const PlyProperty& p) { return p.name == name && !p.isList(); });
    if (!at)
      failAtLine(layout.vertex->headerLine,
                 "the 'vertex' element has no scalar property '" + name + "'");
    layout.coordinate[axis] = *at;
  }
  if (layout.face != nullptr) {
    const std::optional<std::size_t> at = find(*layout.face, [](const PlyProperty& p) {
      return p.isList() && (p.name == "vertex_indices" || p.name == "vertex_index");
    });
    if (!at)
      failAtLine(layout.face->headerLine,
                 "the 'face' element has no list property 'vertex_indices' or 'vertex_index'");
    if (layout.face->properties[*at].value.kind == ScalarKind::real)
      failAtLine(layout.face->headerLine, "the face's vertex indices must have an integer type");
    layout.indices = *at;
  }
  return layout;
}

// ----- ascii -----

/// Non-blank lines; one element instance a line.
std::optional<std::string_view> nextContentLine(LineReader& lines) {
  std::optional<std::string_view> line = lines.next();
  while (line && trimBlanks(*line).empty())
    line = lines.next();
  return line;
}

class AsciiBody {
 public:
  /// `lines`: the file's lines, at the `end_header` line.
  AsciiBody(const PlyHeader& header, const MeshLayout& layout, LineReader lines)
      : header_(header), layout_(layout), lines_(lines) {}

  TriangleSoup read() {
    for (const PlyElement& element : header_.elements) {
      if (&element == layout_.vertex)
        soup_.vertices().reserve(static_cast<std::size_t>(
            std::min<std::uint64_t>(element.count, lines_.rest().size() / 2 + 1)));
      for (std::uint64_t index = 0; index < element.count; ++index) {
        const std::optional<std::string_view> line = nextContentLine(lines_);
        if (!line) fail("the file ends before " + elementName(element, index));
        readInstance(*line, element, index);
      }
    }
    if (nextContentLine(lines_))
      failAtLine(lines_.lineNumber(), "more lines than the elements the header announces");
    return soup_.finish(layout_.face == nullptr || layout_.face->count == 0);
  }

 private:
  void readInstance(std::string_view line, const PlyElement& element, std::uint64_t index) {
    const std::size_t number = lines_.lineNumber();
    const bool isVertex = &element == layout_.vertex;
    const bool isFace = &element == layout_.face;
    std::string_view rest = line;
    const auto failValues = [&] {
      failAtLine(number, elementName(element, index) + " has fewer values than its header " +
                             "declares, or one is not a number: '" + excerpt(line) + "'");
    };
    Vec3 position;
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& property = element.properties[p];
      const std::string_view token = takeToken(rest);
      if (!property.isList()) {
        if (isVertex && (p == layout_.coordinate[0] || p == layout_.coordinate[1] ||
                         p == layout_.coordinate[2])) {
          if (token.empty()) failValues();
          const double value = parseCoordinate(token, number);
          for (std::size_t axis = 0; axis < 3; ++axis)
            if (p == layout_.coordinate[axis]) position[axis] = value;
        } else if (!startsLikeNumber(token)) {
          failValues();
        }
        continue;
      }
      if (!startsLikeNumber(token)) failValues();
      const std::optional<std::uint64_t> length = parseUnsigned(token);
      if (!length)
        failAtLine(number, "a list length in " + elementName(element, index) +
                               " is not a count: '" + excerpt(token) + "'");
      if (*length > rest.size() / 2 + 1) failValues();
      const bool isIndices = isFace && p == layout_.indices;
      if (isIndices) corners_.clear();
      for (std::uint64_t item = 0; item < *length; ++item) {
        const std::string_view value = takeToken(rest);
        if (!startsLikeNumber(value)) failValues();
        if (!isIndices) continue;
        const std::optional<std::uint64_t> vertex = parseUnsigned(value);
        if (!vertex)
          failAtLine(number, elementName(element, index) + " has the vertex index '" +
                                 excerpt(value) + "', not a whole number from 0");
        requireVertexIndex(*vertex, soup_.vertices().size(), number, elementName(element, index));
        corners_.push_back(static_cast<std::uint32_t>(*vertex));
      }
      if (isIndices) {
        if (corners_.empty()) failAtLine(number, elementName(element, index) + " has no vertices");
        soup_.addFace(corners_);
      }
    }
    if (!trimBlanks(rest).empty())
      failAtLine(number, elementName(element, index) +
                             " has more values than its header declares: '" + excerpt(line) + "'");
    if (isVertex) soup_.vertices().push_back(position);
  }

  const PlyHeader& header_;
  const MeshLayout& layout_;
  LineReader lines_;
  SoupBuilder soup_;
  std::vector<std::uint32_t> corners_;
};

// ----- binary -----

class BinaryBody {
 public:
  BinaryBody(const PlyHeader& header, const MeshLayout& layout, std::string_view bytes)
      : header_(header), layout_(layout), bytes_(bytes) {}

  TriangleSoup read() {
    for (const PlyElement& element : header_.elements) {
      requireRoomFor(element);
      if (&element == layout_.vertex)
        soup_.vertices().reserve(static_cast<std::size_t>(element.count));
      if (element.properties.empty()) continue;  // instances of no bytes: nothing to read
      for (std::uint64_t index = 0; index < element.count; ++index)
        readInstance(element, index);
    }
    if (left() != 0)
      fail(std::to_string(left()) + " bytes follow the elements the header announces (" +
           std::to_string(offset_) + " bytes of binary data expected)");
    return soup_.finish(layout_.face == nullptr || layout_.face->count == 0);
  }

 private:
  std::size_t left() const noexcept { return bytes_.size() - offset_; }

  /// Every instance takes at least its scalars and list lengths: a count that the bytes left
  /// cannot hold is refused before anything is read or allocated for it.
  void requireRoomFor(const PlyElement& element) const {
    std::size_t leastBytes = 0;
    for (const PlyProperty& property : element.properties)
      leastBytes += property.isList() ? property.count.bytes : property.value.bytes;
    if (leastBytes != 0 && element.count > left() / leastBytes)
      fail("the binary data ends inside " + elementName(element, left() / leastBytes));
  }

  /// The raw bits of a value of `bytes` bytes at the current offset, in host order.
  std::uint64_t takeBits(std::size_t bytes, const PlyElement& element, std::uint64_t index) {
    if (bytes > left()) fail("the binary data ends inside " + elementName(element, index));
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < bytes; ++i) {
      const std::size_t at = header_.encoding == PlyEncoding::bigEndian ? i : bytes - 1 - i;
      value = (value << 8) | static_cast<unsigned char>(bytes_[offset_ + at]);
    }
    offset_ += bytes;
    return value;
  }

  /// A value of `type`, exactly as a double (every PLY type converts to double exactly).
  double takeReal(const PlyType& type, const PlyElement& element, std::uint64_t index) {
    const std::uint64_t bits = takeBits(type.bytes, element, index);
    switch (type.kind) {
      case ScalarKind::real:
        if (type.bytes == 4) return std::bit_cast<float>(static_cast<std::uint32_t>(bits));
        return std::bit_cast<double>(bits);
      case ScalarKind::unsignedInteger:
        return static_cast<double>(bits);
      case ScalarKind::signedInteger:
        return static_cast<double>(toSigned(bits, type.bytes));
    }
    return 0.0;
  }

  static std::int64_t toSigned(std::uint64_t bits, std::size_t bytes) noexcept {
    const std::uint64_t signBit = std::uint64_t{1} << (8 * bytes - 1);
    if ((bits & signBit) == 0) return static_cast<std::int64_t>(bits);
    return static_cast<std::int64_t>(bits) - static_cast<std::int64_t>(signBit << 1);
  }

  /// An integer of `type` (checked by the header to be one).
  std::int64_t takeInteger(const PlyType& type, const PlyElement& element, std::uint64_t index) {
    const std::uint64_t bits = takeBits(type.bytes, element, index);
    return type.kind == ScalarKind::signedInteger ? toSigned(bits, type.bytes)
                                                  : static_cast<std::int64_t>(bits);
  }

  void readInstance(const PlyElement& element, std::uint64_t index) {
    const bool isVertex = &element == layout_.vertex;
    const bool isFace = &element == layout_.face;
    const std::size_t start = offset_;
    Vec3 position;
    for (std::size_t p = 0; p < element.properties.size(); ++p) {
      const PlyProperty& property = element.properties[p];
      if (!property.isList()) {
        if (!isVertex) {
          takeBits(property.value.bytes, element, index);
          continue;
        }
        const double value = takeReal(property.value, element, index);
        for (std::size_t axis = 0; axis < 3; ++axis)
          if (p == layout_.coordinate[axis]) {
            if (!std::isfinite(value))
              fail(elementName(element, index) + " (byte " + std::to_string(start) +
                   " of the binary data) has a coordinate that is not finite: " +
                   std::to_string(value));
            position[axis] = value;
          }
        continue;
      }
      const std::int64_t length = takeInteger(property.count, element, index);
      if (length < 0)
        fail(elementName(element, index) + " has a list of length " + std::to_string(length));
      const std::uint64_t items = static_cast<std::uint64_t>(length);
      if (items > left() / property.value.bytes)
        fail("the binary data ends inside " + elementName(element, index));
      if (!(isFace && p == layout_.indices)) {
        offset_ += static_cast<std::size_t>(items) * property.value.bytes;
        continue;
      }
      if (items == 0) fail(elementName(element, index) + " has no vertices");
      corners_.clear();
      for (std::uint64_t item = 0; item < items; ++item) {
        const std::int64_t vertex = takeInteger(property.value, element, index);
        if (vertex < 0 || static_cast<std::uint64_t>(vertex) >= soup_.vertices().size())
          fail(elementName(element, index) + " refers to vertex " + std::to_string(vertex) +
               ", but there are only " + std::to_string(soup_.vertices().size()) + " vertices");
        corners_.push_back(static_cast<std::uint32_t>(vertex));
      }
      soup_.addFace(corners_);
    }
    if (isVertex) soup_.vertices().push_back(position);
  }

  const PlyHeader& header_;
  const MeshLayout& layout_;
  std::string_view bytes_;
  std::size_t offset_ = 0;
  SoupBuilder soup_;
  std::vector<std::uint32_t> corners_;
};

/// The binary body starts after the line end of `end_header`.
std::string_view binaryBody(std::string_view rest) {
  if (rest.starts_with("\r\n")) return rest.substr(2);
  if (rest.starts_with('\n') || rest.starts_with('\r')) return rest.substr(1);
  return rest;
}

}  // namespace

TriangleSoup readPly(std::string_view bytes) {
  LineReader lines(bytes);
  const PlyHeader header = readHeader(lines);
  const MeshLayout layout = findLayout(header);
  if (header.encoding == PlyEncoding::ascii) {
    requireText(lines.rest());
    return AsciiBody(header, layout, lines).read();
  }
  return BinaryBody(header, layout, binaryBody(lines.rest())).read();
}

}  // namespace delta::detail
