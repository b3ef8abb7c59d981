#pragma once

#include <cstdint>
#include <string>
#include <string_view>

/// Checks that run on a file's bytes before assimp reads it.
///
/// Assimp 5.2's readers for these formats accept damaged files and return wrong geometry without
/// a word (each function lists what was seen); they also trust the element counts in a header and
/// allocate for them before reading, so a lying header costs gigabytes or hangs. Each check reads
/// the whole file once, allocates nothing that grows with the file, and throws delta::Error with
/// the reason (line or byte offset, element, value; not the path: the caller adds it) where the
/// file is not what its header says. A file that passes is one assimp's reader reads as written.
namespace delta::io::detail {

/// OFF text rewritten so that assimp's reader reads what the file means:
/// - every comment ('#' to the end of its line) cut, and the blanks before it; line ends stay, so
///   line numbers do. That reader skips comments only in the header: between the elements it
///   takes a comment or blank line for a vertex, or drops it as a face (with the last face).
/// - the keyword `[ST][C][N][4][n]OFF` reduced to `[4][n]OFF`: the colours, normals and texture
///   coordinates after a vertex are of no use to Δ, and that reader fails on three-value (RGB)
///   colours unless a comment follows them.
std::string offForAssimp(std::string_view text);

/// OFF, after offForAssimp, as assimp's reader understands it: the header (optional
/// `[ST][C][N][4][n]OFF` keyword, then the vertex, face and edge counts on one line) and then one
/// vertex or face per line. Rejects what that reader gets silently wrong: a count of 2³² or more
/// (it wraps), fewer lines than the counts, a face with no vertex or more than 9 (dropped), an
/// index that is not a plain number below the vertex count (clamped to the last vertex), a line
/// of 4096 characters or more (its line buffer), lines beyond the announced faces.
void checkOff(std::string_view text);

/// OBJ: a `v` line whose first three values are not numbers (assimp drops the vertex, which
/// shifts every later index) and an `f`, `l` or `p` line with no vertex (dropped).
void checkObj(std::string_view text);

/// PLY, ascii or binary: the body must hold exactly the elements the header announces, with the
/// declared number of values each; assimp reads missing values as 0, repeats the last face when
/// faces are missing and reads past the end of a truncated binary body. Header lines that are
/// not PLY keywords are ignored, as assimp ignores them.
void checkPly(std::string_view bytes);

/// Whether `head`, the first 84 bytes of an STL file of `size` bytes (or all of it, if shorter),
/// is the header of a binary STL of exactly the announced size: then checkStl has nothing to add
/// and need not read the rest.
bool isBinaryStlOfAnnouncedSize(std::string_view head, std::uintmax_t size);

/// STL: a binary file must be exactly 84 + 50·n bytes for the n triangles its header announces;
/// an ascii file must end with `endsolid` (assimp returns the facets read so far from a file cut
/// after a facet).
void checkStl(std::string_view bytes);

}  // namespace delta::io::detail
