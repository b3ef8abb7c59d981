#pragma once

#include <string>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/vec3.h"

namespace delta::cli {

/// Query points named on the command line: a text file, one point `x y z` a line (io/points.h),
/// or `builtin:uniform:N[:SEED]`, N points uniform in `box` grown by 10% per side (the peers'
/// benchmark workload), the same for the same seed on every machine.
/// Throws delta::Error for a bad file (naming the line), a bad N or seed, or no points.
std::vector<Vec3> loadPointSource(const std::string& source, const Aabb& box);

}  // namespace delta::cli
