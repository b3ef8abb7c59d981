// Checks that the guide's C++ cannot rot: every C++ code block of docs/guide.md is, byte for
// byte, an example program of docs/guide/ (which the tests build and run), and every example
// appears in the guide. Run as the test Guide.CodeBlocksMatchExamples:
//
//   delta_guide_check docs/guide.md docs/guide
//
// In the guide, the last non-blank line before a C++ block (```cpp) names its source:
//
//   <!-- example: NAME.cpp -->           the block is the whole file
//   <!-- example: NAME.cpp#REGION -->    the block is the region REGION of the file
//
// In an example, a region is the lines between `// [guide:begin REGION]` and
// `// [guide:end REGION]` (each alone on its line), without the marker lines of other regions
// nested in it, and with the indentation common to its non-blank lines removed (so a region in
// the body of main() shows at the left margin). Every file, and every region, must be shown.
//
// After changing an example, `delta_guide_check --update docs/guide.md docs/guide` copies every
// named file or region into its block of the guide (and still reports what it cannot fix).
#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace {

namespace fs = std::filesystem;
using Lines = std::vector<std::string>;

int failures = 0;

void fail(const std::string& where, const std::string& what) {
  std::fprintf(stderr, "%s: %s\n", where.c_str(), what.c_str());
  ++failures;
}

/// The file's lines, without their '\n' (a final newline ends the last line; it adds none).
Lines readLines(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) {
    fail(path.string(), "cannot read it");
    return {};
  }
  const std::string text{std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>()};
  Lines lines;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    if (end == std::string::npos) {
      lines.push_back(text.substr(start));
      break;
    }
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  return lines;
}

std::string_view trimmed(std::string_view text) {
  const std::size_t first = text.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const std::size_t last = text.find_last_not_of(" \t\r");
  return text.substr(first, last - first + 1);
}

bool isBlank(std::string_view line) {
  return trimmed(line).empty();
}

/// The name in a marker line "<prefix>NAME<suffix>", or "" when the line is not one.
std::string markerName(std::string_view line, std::string_view prefix, std::string_view suffix) {
  const std::string_view text = trimmed(line);
  if (text.size() <= prefix.size() + suffix.size() || !text.starts_with(prefix) ||
      !text.ends_with(suffix))
    return {};
  return std::string(
      trimmed(text.substr(prefix.size(), text.size() - prefix.size() - suffix.size())));
}

/// Whether a fence line opens a C++ block: ```cpp, ```c++, ```cxx, ```cc, ```h or ```hpp.
bool isCppFence(std::string_view line) {
  if (!line.starts_with("```")) return false;
  std::string language(trimmed(line.substr(3)));
  std::transform(language.begin(), language.end(), language.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  static const std::set<std::string> kCpp = {"cpp", "c++", "cxx", "cc", "h", "hpp"};
  return kCpp.contains(language);
}

/// One example program and its regions.
struct Example {
  Lines lines;
  std::map<std::string, Lines> regions;
  bool shown = false;       // whole or in part
  bool shownWhole = false;  // then its regions need not be shown on their own
  std::set<std::string> regionsShown;
};

constexpr std::string_view kBegin = "// [guide:begin ";
constexpr std::string_view kEnd = "// [guide:end ";

bool isRegionMarker(std::string_view line) {
  return !markerName(line, kBegin, "]").empty() || !markerName(line, kEnd, "]").empty();
}

Lines dedented(const Lines& lines) {
  std::size_t indent = std::string::npos;
  for (const std::string& line : lines)
    if (!isBlank(line)) indent = std::min(indent, line.find_first_not_of(' '));
  Lines out;
  for (const std::string& line : lines)
    out.push_back(isBlank(line) && line.size() < indent
                      ? std::string()
                      : line.substr(std::min(indent, line.size())));
  return out;
}

Example readExample(const fs::path& path) {
  Example example;
  example.lines = readLines(path);
  const std::string where = path.filename().string();
  std::map<std::string, std::size_t> open;  // region name -> line of its begin marker
  for (std::size_t i = 0; i < example.lines.size(); ++i) {
    const std::string& line = example.lines[i];
    const std::string begin = markerName(line, kBegin, "]");
    const std::string end = markerName(line, kEnd, "]");
    const std::string at = where + ":" + std::to_string(i + 1);
    if (!begin.empty()) {
      if (open.contains(begin) || example.regions.contains(begin))
        fail(at, "region '" + begin + "' begins twice");
      open[begin] = i;
    } else if (!end.empty()) {
      const auto found = open.find(end);
      if (found == open.end()) {
        fail(at, "region '" + end + "' ends but did not begin");
        continue;
      }
      Lines body;
      for (std::size_t k = found->second + 1; k < i; ++k)
        if (!isRegionMarker(example.lines[k])) body.push_back(example.lines[k]);
      example.regions[end] = dedented(body);
      open.erase(found);
    } else if (line.find("[guide:") != std::string::npos) {
      fail(at, "a malformed region marker: write `// [guide:begin NAME]` or `// [guide:end NAME]`");
    }
  }
  for (const auto& [name, line] : open)
    fail(where + ":" + std::to_string(line + 1), "region '" + name + "' never ends");
  return example;
}

/// Reports the first difference between a block and its source; true when they are the same.
bool compare(const Lines& block, std::size_t blockLine, const Lines& expected,
             const std::string& source) {
  const std::size_t common = std::min(block.size(), expected.size());
  for (std::size_t i = 0; i < common; ++i) {
    if (block[i] == expected[i]) continue;
    fail("guide.md:" + std::to_string(blockLine + i),
         "differs from " + source + " (its line " + std::to_string(i + 1) + "):\n  guide:   '" +
             block[i] + "'\n  example: '" + expected[i] + "'");
    return false;
  }
  if (block.size() == expected.size()) return true;
  fail("guide.md:" + std::to_string(blockLine + common),
       "the block has " + std::to_string(block.size()) + " lines and " + source + " has " +
           std::to_string(expected.size()));
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  const bool update = argc == 4 && std::string_view(argv[1]) == "--update";
  if (argc != 3 && !update) {
    std::fprintf(stderr, "usage: %s [--update] GUIDE.md EXAMPLES_DIR\n", argv[0]);
    return 2;
  }
  const fs::path guidePath = argv[argc - 2], examplesDir = argv[argc - 1];

  std::map<std::string, Example> examples;
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(examplesDir, error))
    if (entry.is_regular_file() && entry.path().extension() == ".cpp")
      examples[entry.path().filename().string()] = readExample(entry.path());
  if (error) fail(examplesDir.string(), "cannot list it: " + error.message());
  if (examples.empty()) fail(examplesDir.string(), "holds no example (*.cpp)");

  const Lines guide = readLines(guidePath);
  Lines updated;  // the guide with every block that names its source copied from it
  std::size_t blocks = 0, changed = 0;
  std::string pendingSource;  // the example named by the last marker, until a block takes it
  std::size_t pendingLine = 0;
  for (std::size_t i = 0; i < guide.size(); ++i) {
    const std::string& line = guide[i];
    updated.push_back(line);
    const std::string at = "guide.md:" + std::to_string(i + 1);
    const std::string named = markerName(line, "<!-- example:", "-->");
    if (!named.empty()) {
      if (!pendingSource.empty())
        fail("guide.md:" + std::to_string(pendingLine), "no C++ block follows this marker");
      pendingSource = named;
      pendingLine = i + 1;
      continue;
    }
    if (isBlank(line)) continue;
    if (!line.starts_with("```")) {
      if (isCppFence(trimmed(line))) fail(at, "an indented C++ block: start it at the margin");
      if (!pendingSource.empty())
        fail("guide.md:" + std::to_string(pendingLine), "no C++ block follows this marker");
      pendingSource.clear();
      continue;
    }

    // A fenced block: find its end.
    std::size_t end = i + 1;
    while (end < guide.size() && trimmed(guide[end]) != "```")
      ++end;
    if (end == guide.size()) {
      fail(at, "this code block never ends");
      break;
    }
    const Lines block(guide.begin() + static_cast<std::ptrdiff_t>(i + 1),
                      guide.begin() + static_cast<std::ptrdiff_t>(end));
    const Lines* source = nullptr;  // what the block should be, when it names a valid source
    if (isCppFence(line)) {
      ++blocks;
      if (pendingSource.empty()) {
        fail(at,
             "a C++ block without its source: put `<!-- example: NAME.cpp -->` or "
             "`<!-- example: NAME.cpp#REGION -->` on the line above, naming a file of "
             "docs/guide/");
      } else {
        const std::size_t hash = pendingSource.find('#');
        const std::string file = pendingSource.substr(0, hash);
        const auto found = examples.find(file);
        if (found == examples.end()) {
          fail(at, "its source " + file + " is not in docs/guide/");
        } else if (hash == std::string::npos) {
          found->second.shown = found->second.shownWhole = true;
          source = &found->second.lines;
        } else {
          const std::string region = pendingSource.substr(hash + 1);
          const auto regionFound = found->second.regions.find(region);
          if (regionFound == found->second.regions.end()) {
            fail(at, file + " has no region '" + region + "'");
          } else {
            found->second.shown = true;
            found->second.regionsShown.insert(region);
            source = &regionFound->second;
          }
        }
      }
    } else if (!pendingSource.empty()) {
      fail("guide.md:" + std::to_string(pendingLine), "no C++ block follows this marker");
    }
    if (source != nullptr && !update) compare(block, i + 2, *source, pendingSource);
    changed += source != nullptr && *source != block;
    const Lines& kept = source != nullptr && update ? *source : block;
    updated.insert(updated.end(), kept.begin(), kept.end());
    updated.push_back(guide[end]);
    pendingSource.clear();
    i = end;
  }
  if (!pendingSource.empty())
    fail("guide.md:" + std::to_string(pendingLine), "no C++ block follows this marker");

  for (const auto& [file, example] : examples) {
    if (!example.shown) fail(file, "is not shown in the guide");
    for (const auto& [region, lines] : example.regions)
      if (example.shown && !example.shownWhole && !example.regionsShown.contains(region))
        fail(file, "its region '" + region + "' is not shown in the guide");
  }
  if (update && changed > 0) {
    std::ofstream file(guidePath, std::ios::binary | std::ios::trunc);
    for (const std::string& line : updated)
      file << line << '\n';
    if (!file.flush()) fail(guidePath.string(), "cannot write it");
    std::printf("%zu blocks of %s updated\n", changed, guidePath.string().c_str());
  }
  if (failures > 0) {
    std::fprintf(stderr, "%d problem(s): the guide and docs/guide/ disagree\n", failures);
    return 1;
  }
  std::printf("%zu C++ blocks of %s match %zu examples\n", blocks, guidePath.string().c_str(),
              examples.size());
  return 0;
}
