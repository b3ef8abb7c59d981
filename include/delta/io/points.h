#pragma once

#include <filesystem>
#include <vector>

#include "delta/core/vec3.h"

namespace delta::io {

/// Reads query points from a text file, one point `x y z` a line (separated by spaces, tabs or
/// commas; blank lines and lines starting with `#` are skipped; a trailing `\r` is ignored).
///
/// Throws delta::Error naming the path and the 1-based line number for a line that is not three
/// numbers, a coordinate that is not finite (nan, inf, or out of double range), a missing or
/// unreadable file, or a file with no points. Never returns a partial set.
///
/// Threading: may be called from several threads at once.
std::vector<Vec3> loadPoints(const std::filesystem::path& path);

}  // namespace delta::io
