#pragma once

#include <cstddef>
#include <string>
#include <string_view>

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

/// `text` as it may be quoted in a message printed on a terminal: at most `limit` characters,
/// then "..."; every byte that is not printable text (a control character, NUL included, DEL,
/// the C1 controls, a byte of no valid UTF-8 sequence) written as "\xNN". Valid UTF-8 beyond
/// ASCII is kept. For quoting what a file holds: binary garbage never reaches the terminal raw,
/// and a NUL byte does not cut the message short where it is read as a C string.
///
/// Threading: a pure function.
std::string printable(std::string_view text, std::size_t limit = 80);

}  // namespace delta
