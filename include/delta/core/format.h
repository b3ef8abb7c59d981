#pragma once

#include <string>

#include "delta/core/vec3.h"

namespace delta {

/// "(x, y, z)" at full precision (17 significant digits), for error messages: a value quoted in
/// a message pastes back into a test unchanged.
std::string toString(const Vec3& v);

/// A double at full precision (17 significant digits).
std::string toString(double value);

}  // namespace delta
