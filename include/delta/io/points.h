#pragma once

#include <filesystem>
#include <vector>

#include "delta/core/vec3.h"

namespace delta::io {

/// Reads query points from a text file, one point `x y z` a line (separated by spaces, tabs or
/// commas; blank lines and lines starting with `#` are skipped; a trailing `\r` is ignored).
///
/// Throws delta::Error naming the path and the 1-based line number for a line that is not three
/// numbers, a coordinate that is not finite (nan, inf, or out of double range) or beyond the
/// range the queries answer exactly (±kLargestCoordinate, mesh/coordinate_range.h), a line longer
/// than 4096 bytes, a missing or unreadable file, a path that is not a regular file (a FIFO, a
/// device such as /dev/zero, a directory: refused at once, without waiting or reading), or a file
/// with no points. The file is read in chunks of 1 MiB: memory grows with the points, not the file.
/// Never returns a partial set.
///
/// Threading: may be called from several threads at once.
std::vector<Vec3> loadPoints(const std::filesystem::path& path);

}  // namespace delta::io
