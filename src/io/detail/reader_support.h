#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

/// Messages and numbers shared by the mesh readers (mesh_readers.h).
namespace delta::detail {

/// Throws delta::Error "line <line>: <what>".
[[noreturn]] void failAtLine(std::size_t line, const std::string& what);

/// `token`, a coordinate on line `line`, as a finite double correctly rounded from its decimal
/// text. Throws delta::Error naming the line and the token when it is not a number, beyond the
/// range of double (1e999, 1e-999) or not finite (nan, inf).
double parseCoordinate(std::string_view token, std::size_t line);

/// `what` for an index into `count` vertices: throws delta::Error naming the line unless
/// index < count.
void requireVertexIndex(std::uint64_t index, std::uint64_t count, std::size_t line,
                        const std::string& what);

}  // namespace delta::detail
