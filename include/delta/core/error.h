#pragma once

#include <stdexcept>
#include <string>

namespace delta {

/// The one exception Δ throws: bad input met at a boundary (mesh construction, file import, the
/// command line). The message names what was wrong and where (file, element, value), so that it
/// can be shown to a user as it is.
///
/// Threading: an immutable value; safe to share.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace delta
