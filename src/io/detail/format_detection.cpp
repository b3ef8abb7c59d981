#include <optional>
#include <string_view>

#include "delta/core/error.h"

#include "mesh_readers.h"
#include "text_scan.h"

namespace delta::detail {
namespace {

/// The first line of `head` that is neither blank nor a comment ('#' to the end of the line),
/// without its comment and blanks.
std::string_view firstContentLine(std::string_view head) {
  LineReader lines(head);
  for (std::optional<std::string_view> line = lines.next(); line; line = lines.next()) {
    const std::string_view content = trimBlanks(line->substr(0, line->find('#')));
    if (!content.empty()) return content;
  }
  return {};
}

bool isPly(std::string_view head) {
  LineReader lines(head);
  const std::optional<std::string_view> first = lines.next();
  return first && trimBlanks(*first) == "ply";
}

bool isAsciiStl(std::string_view head) {
  const std::size_t start = head.find_first_not_of(" \t\r\n\f");
  return start != head.npos && head.substr(start).starts_with("solid") &&
         head.find('\0') == head.npos &&
         (head.find("facet") != head.npos || head.find("endsolid") != head.npos);
}

bool isOff(std::string_view head) {
  std::string_view line = firstContentLine(head);
  const std::string_view keyword = takeToken(line);
  if (!keyword.ends_with("OFF")) return false;
  return keyword.substr(0, keyword.size() - 3).find_first_not_of("STCN4n") == keyword.npos;
}

bool isObj(std::string_view head) {
  if (head.find('\0') != head.npos) return false;
  std::string_view line = firstContentLine(head);
  const std::string_view keyword = takeToken(line);
  if (keyword == "v") {
    for (int i = 0; i < 3; ++i)
      if (parseReal(takeToken(line)).status != RealStatus::ok) return false;
    return true;
  }
  for (const std::string_view statement : {"vt", "vn", "f", "o", "g", "mtllib", "usemtl", "s"})
    if (keyword == statement) return !trimBlanks(line).empty();
  return false;
}

}  // namespace

MeshFormat detectMeshFormat(std::string_view head, std::uintmax_t size, std::string_view extension,
                            bool assimpReadsExtension) {
  if (isPly(head)) return MeshFormat::ply;
  if (isBinaryStlOfAnnouncedSize(head, size) || isAsciiStl(head)) return MeshFormat::stl;
  if (isOff(head)) return MeshFormat::off;
  const bool objByExtension = extension == ".obj";
  const bool ownExtension =
      objByExtension || extension == ".off" || extension == ".ply" || extension == ".stl";
  if (isObj(head) && (ownExtension || !assimpReadsExtension)) return MeshFormat::obj;
  if (extension == ".off") return MeshFormat::off;
  if (extension == ".ply") return MeshFormat::ply;
  if (objByExtension) return MeshFormat::obj;
  if (extension == ".stl") return MeshFormat::stl;
  return MeshFormat::other;
}

void requireFormatStart(MeshFormat format, std::string_view head, std::uintmax_t size) {
  switch (format) {
    case MeshFormat::ply:
      if (!isPly(head)) throw Error("the file does not start with 'ply'");
      return;
    case MeshFormat::stl:
      return requireStlStart(head, size);
    case MeshFormat::off:
    case MeshFormat::obj:
      return requireText(head);
    case MeshFormat::other:
      return;
  }
}

}  // namespace delta::detail
