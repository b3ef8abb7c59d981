#pragma once

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>

namespace delta::cli {

/// The extension of a file name, lower case, with its dot (".vtp"); empty when there is none.
inline std::string extensionOf(const std::string& path) {
  std::string extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension;
}

}  // namespace delta::cli
