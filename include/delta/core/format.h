#pragma once

#include <string>

#include "delta/core/vec3.h"

namespace delta {

/// "(x, y, z)" at full precision (17 significant digits), for error messages: a value quoted in
/// a message pastes back into a test unchanged. NaN and infinities print as "nan", "inf", "-inf".
///
/// Threading: a pure function (the C++ stream it formats with is its own).
std::string toString(const Vec3& v);

/// A double at full precision (17 significant digits); "nan", "inf" or "-inf" where not finite.
///
/// Threading: a pure function.
std::string toString(double value);

}  // namespace delta
