#pragma once

namespace delta {

/// The library version, "MAJOR.MINOR.PATCH".
///
/// Threading: returns a static string; safe from any thread.
const char* version() noexcept;

/// The git commit the library was built from (short hash, "-dirty" when the tree had changes),
/// or "unknown" outside a git checkout.
///
/// Threading: returns a static string; safe from any thread.
const char* gitCommit() noexcept;

}  // namespace delta
