// Checks that the guide's examples cannot rot: every C++ and Python code block of docs/guide.md
// is, byte for byte, an example of docs/guide/ (C++ programs the tests build and run, Python
// scripts they run), and every example appears in the guide. Run as the test
// Guide.CodeBlocksMatchExamples:
//
//   delta_guide_check docs/guide.md docs/guide
//
// In the guide, the last non-blank line before a C++ block (```cpp) or a Python block
// (```python) names its source, an example in the block's language:
//
//   <!-- example: NAME.cpp -->           the block is the whole file (NAME.py in Python)
//   <!-- example: NAME.cpp#REGION -->    the block is the region REGION of the file
//
// In an example, a region is the lines between `// [guide:begin REGION]` and
// `// [guide:end REGION]` (in Python `# [guide:begin REGION]` and `# [guide:end REGION]`), each
// alone on its line, without the marker lines of other regions nested in it, and with the
// indentation common to its non-blank lines removed (so a region in the body of main() shows at
// the left margin). Every file, and every region, must be shown. Other blocks (```cmake, …) are
// not checked; the table `languages()` says which are.
//
// After changing an example, `delta_guide_check --update docs/guide.md docs/guide` copies every
// named file or region into its block of the guide (and still reports what it cannot fix).
#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <utility>
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

/// A language of the guide's examples: the fence tags that open its blocks (lower case), its
/// files' extension and the comment that starts its region markers.
struct Language {
  std::string_view name;
  std::string_view extension;
  std::string_view comment;
  std::set<std::string, std::less<>> fences;
};

/// The languages checked; a block of any other (```cmake, ```sh) is left alone.
const std::vector<Language>& languages() {
  static const std::vector<Language> kLanguages = {
      {"C++", ".cpp", "//", {"cpp", "c++", "cxx", "cc", "h", "hpp"}},
      {"Python", ".py", "#", {"python", "py", "python3"}},
  };
  return kLanguages;
}

/// "C++ or Python", for messages.
std::string languageNames() {
  std::string names;
  for (const Language& language : languages())
    names += (names.empty() ? "" : " or ") + std::string(language.name);
  return names;
}

/// The language whose block a fence line opens (```cpp, ```python, …), or null.
const Language* fenceLanguage(std::string_view line) {
  if (!line.starts_with("```")) return nullptr;
  std::string tag(trimmed(line.substr(3)));
  std::transform(tag.begin(), tag.end(), tag.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const Language& language : languages())
    if (language.fences.contains(tag)) return &language;
  return nullptr;
}

/// The language of an example file, by its extension, or null.
const Language* fileLanguage(const fs::path& path) {
  for (const Language& language : languages())
    if (path.extension() == language.extension) return &language;
  return nullptr;
}

/// One example (a program or a script) and its regions.
struct Example {
  const Language* language = nullptr;
  Lines lines;
  std::map<std::string, Lines> regions;
  bool shown = false;       // whole or in part
  bool shownWhole = false;  // then its regions need not be shown on their own
  std::set<std::string> regionsShown;
};

/// The start of a region marker line, `// [guide:begin ` in C++ and `# [guide:begin ` in Python.
std::string beginMarker(const Language& language) {
  return std::string(language.comment) + " [guide:begin ";
}
std::string endMarker(const Language& language) {
  return std::string(language.comment) + " [guide:end ";
}

bool isRegionMarker(std::string_view line, const Language& language) {
  return !markerName(line, beginMarker(language), "]").empty() ||
         !markerName(line, endMarker(language), "]").empty();
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

Example readExample(const fs::path& path, const Language& language) {
  Example example;
  example.language = &language;
  example.lines = readLines(path);
  const std::string where = path.filename().string();
  const std::string beginPrefix = beginMarker(language), endPrefix = endMarker(language);
  std::map<std::string, std::size_t> open;  // region name -> line of its begin marker
  for (std::size_t i = 0; i < example.lines.size(); ++i) {
    const std::string& line = example.lines[i];
    const std::string begin = markerName(line, beginPrefix, "]");
    const std::string end = markerName(line, endPrefix, "]");
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
        if (!isRegionMarker(example.lines[k], language)) body.push_back(example.lines[k]);
      example.regions[end] = dedented(body);
      open.erase(found);
    } else if (line.find("[guide:") != std::string::npos) {
      fail(at, "a malformed region marker: write `" + beginPrefix + "NAME]` or `" + endPrefix +
                   "NAME]`");
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

  std::map<std::string, Example> examples;  // by file name: NAME.cpp and NAME.py are two
  std::error_code error;
  for (const fs::directory_entry& entry : fs::directory_iterator(examplesDir, error)) {
    const Language* language = fileLanguage(entry.path());
    if (entry.is_regular_file() && language != nullptr)
      examples[entry.path().filename().string()] = readExample(entry.path(), *language);
  }
  if (error) fail(examplesDir.string(), "cannot list it: " + error.message());
  if (examples.empty()) fail(examplesDir.string(), "holds no example (*.cpp, *.py)");

  const Lines guide = readLines(guidePath);
  Lines updated;  // the guide with every block that names its source copied from it
  std::map<std::string_view, std::size_t> blocks;  // checked blocks by language
  std::size_t changed = 0;
  std::string pendingSource;  // the example named by the last marker, until a block takes it
  std::size_t pendingLine = 0;
  const auto markerUnused = [&] {
    if (!pendingSource.empty())
      fail("guide.md:" + std::to_string(pendingLine),
           "no " + languageNames() + " block follows this marker");
    pendingSource.clear();
  };
  for (std::size_t i = 0; i < guide.size(); ++i) {
    const std::string& line = guide[i];
    updated.push_back(line);
    const std::string at = "guide.md:" + std::to_string(i + 1);
    const std::string named = markerName(line, "<!-- example:", "-->");
    if (!named.empty()) {
      markerUnused();
      pendingSource = named;
      pendingLine = i + 1;
      continue;
    }
    if (isBlank(line)) continue;
    if (!line.starts_with("```")) {
      if (const Language* indented = fenceLanguage(trimmed(line)))
        fail(at, "an indented " + std::string(indented->name) + " block: start it at the margin");
      markerUnused();
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
    const Language* language = fenceLanguage(line);
    if (language == nullptr) markerUnused();  // a block of another language (```cmake)
    const std::string sourceName = std::exchange(pendingSource, {});  // this block takes it
    const Lines* source = nullptr;  // what the block should be, when it names a valid source
    if (language != nullptr) {
      ++blocks[language->name];
      const std::string name(language->name), extension(language->extension);
      const std::size_t hash = sourceName.find('#');
      const std::string file = sourceName.substr(0, hash);
      const auto found = examples.find(file);
      if (sourceName.empty()) {
        fail(at, "a " + name + " block without its source: put `<!-- example: NAME" + extension +
                     " -->` or `<!-- example: NAME" + extension +
                     "#REGION -->` on the line above, naming a file of docs/guide/");
      } else if (found == examples.end()) {
        fail(at, "its source " + file + " is not in docs/guide/");
      } else if (found->second.language != language) {
        fail(at, "a " + name + " block, but its source " + file + " is " +
                     std::string(found->second.language->name));
      } else if (hash == std::string::npos) {
        found->second.shown = found->second.shownWhole = true;
        source = &found->second.lines;
      } else {
        const std::string region = sourceName.substr(hash + 1);
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
    if (source != nullptr && !update) compare(block, i + 2, *source, sourceName);
    changed += source != nullptr && *source != block;
    const Lines& kept = source != nullptr && update ? *source : block;
    updated.insert(updated.end(), kept.begin(), kept.end());
    updated.push_back(guide[end]);
    i = end;
  }
  markerUnused();

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
  std::string counts;
  for (const Language& language : languages())
    counts += (counts.empty() ? "" : ", ") + std::to_string(blocks[language.name]) + " " +
              std::string(language.name);
  std::printf("the code blocks of %s (%s) match its %zu examples\n", guidePath.string().c_str(),
              counts.c_str(), examples.size());
  return 0;
}
