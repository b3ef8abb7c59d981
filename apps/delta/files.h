#pragma once

#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <system_error>

#include "delta/core/error.h"

namespace delta::cli {

/// The extension of a file name, lower case, with its dot (".vtp"); empty when there is none.
inline std::string extensionOf(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

/// The file of frame `frame` of a series written into an --out folder: "particles_000012.vtp".
inline std::string frameFileName(const char* series, std::size_t frame, const char* extension) {
  char name[128];
  std::snprintf(name, sizeof name, "%s_%06zu%s", series, frame, extension);
  return name;
}

/// Throws delta::Error where --out `out` is one of the command's input files, through whatever
/// path or link: the readers tell formats by content, so an input may carry an output's
/// extension, and it was replaced by the output without a word. `inputs` may hold built-in
/// sources and paths that do not exist (neither is a file to lose).
inline void requireOutputIsNotAnInput(const std::string& out,
                                      std::initializer_list<std::string> inputs) {
  if (out.empty()) return;
  for (const std::string& input : inputs) {
    std::error_code error;
    if (!input.empty() && std::filesystem::equivalent(out, input, error))
      throw Error("--out '" + out + "' is the input '" + input +
                  "': writing it would replace it; write elsewhere");
  }
}

/// Makes the folder given to --out (and its parents) unless it exists. Throws delta::Error naming
/// it when it is a file or cannot be made.
inline void makeOutputFolder(const std::filesystem::path& directory) {
  std::error_code error;
  if (std::filesystem::exists(directory, error) && !std::filesystem::is_directory(directory, error))
    throw Error("--out '" + directory.string() + "' exists and is not a folder");
  std::filesystem::create_directories(directory, error);
  if (error)
    throw Error("--out '" + directory.string() + "': cannot make the folder: " + error.message());
}

}  // namespace delta::cli
