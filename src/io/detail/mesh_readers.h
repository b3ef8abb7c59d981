#pragma once

#include <cstdint>
#include <string_view>
#include <vector>

#include "delta/core/vec3.h"
#include "delta/io/mesh_io.h"
#include "delta/mesh/mesh.h"

/// Δ's own readers for OFF, PLY, OBJ and STL, in double precision.
///
/// Each reader is a pure function of the file's bytes (no file system, no global state), so that
/// a fuzz target can call it directly. It reads every coordinate exactly: decimal text is
/// converted with std::from_chars (correctly rounded to the nearest double), binary values
/// (integers, float32, float64) are widened exactly. It validates everything it reads and throws
/// delta::Error with the place (line number, or element and byte offset), the element and the
/// value, without the path (the caller adds it): counts are checked against the bytes that follow
/// them before anything is allocated for them, indices against the vertices, coordinates for
/// being finite. A file that passes is read as written: never a default value for a missing one,
/// never a clamped index.
///
/// Threading: every function may be called from several threads at once.
namespace delta::detail {

/// Triangles of a file with the vertices they use, before vertices at identical positions are
/// joined (detail::joinIdenticalVertices).
struct TriangleSoup {
  /// The vertices that triangles use, in the file's order; vertices no triangle uses are dropped.
  std::vector<Vec3> positions;
  std::vector<TriangleIndices> triangles;  ///< indices into `positions`, in the file's order
  io::LoadStatistics statistics;  ///< sourceVertices is positions.size(); precision is exact
};

/// OFF: an optional `[ST][C][N][4][n]OFF` keyword, the vertex, face and edge counts, then one
/// vertex and one face a line. Comments ('#' to the end of the line) and blank lines may stand
/// anywhere. A vertex line holds its coordinates first (3; the dimension after nOFF, missing
/// coordinates 0; 4OFF adds w, by which x, y and z are divided unless it is 1), then whatever
/// the keyword announces (colours, normals, texture coordinates), which is ignored. A face line
/// holds its corner count, the 0-based indices, then an optional colour, ignored. Faces of one
/// corner count as points, of two as lines, larger ones are triangulated
/// (detail::triangulatePolygon). Counts must fit in 32 bits.
TriangleSoup readOff(std::string_view text);

/// PLY, `ascii`, `binary_little_endian` or `binary_big_endian`: the `vertex` element's `x`, `y`
/// and `z` properties (of any PLY numeric type) and the `face` element's list property
/// `vertex_indices` (or `vertex_index`) of any integer count and index types; other elements
/// and properties are checked for their structure and skipped. The `vertex` element must come
/// before the `face` element. Ascii values are decimal text, read as double whatever type the
/// header declares (the text is the number), one element instance a line; a binary body must
/// hold exactly the announced elements. Faces of one corner count as points, of two as lines,
/// larger ones are triangulated. A file without a `face` element is a point cloud: its vertices
/// count as points.
TriangleSoup readPly(std::string_view bytes);

/// OBJ: `v x y z` (further values, w or a colour, ignored), `f`, `l` and `p` with 1-based or
/// negative (relative) indices in the forms `v`, `v/vt`, `v/vt/vn` and `v//vn`; `o` and `g` start
/// a new mesh (counted in statistics.meshes when it holds a triangle); other statements
/// (`vt`, `vn`, `usemtl`, `mtllib`, `s`, ...) are ignored; a backslash at the end of a line
/// continues the statement. `p` with n indices counts n points, `l` with n indices n − 1 lines;
/// an `f` of one corner counts as a point, of two as a line, larger ones are triangulated. An
/// index must name a vertex defined before it.
TriangleSoup readObj(std::string_view text);

/// STL, binary or ascii. A file of exactly 84 + 50·n bytes for the n triangles its header
/// announces is binary (even if it starts with "solid"): each facet's three float32 corners are
/// widened exactly (the format holds nothing finer) and bring their own three vertices. Any
/// other file must be ascii STL: one or more `solid` ... `endsolid` blocks (each a mesh) of
/// `facet [normal a b c] outer loop vertex x y z ... endloop endfacet`; keywords in any case,
/// normals ignored, a facet of more than three vertices triangulated.
TriangleSoup readStl(std::string_view bytes);

/// Whether the first 84 bytes of a file of `size` bytes (`head`, or the whole file if shorter)
/// are the header of a binary STL of exactly the size it announces.
bool isBinaryStlOfAnnouncedSize(std::string_view head, std::uintmax_t size) noexcept;

/// Throws the error readStl would give a file of `size` bytes that starts with `head` (its
/// first 84 bytes or more) when these show that it is neither a binary STL of the size its
/// header announces nor an ascii one (starting with `solid`, no NUL byte in `head`).
void requireStlStart(std::string_view head, std::uintmax_t size);

/// The formats Δ reads itself; `other` goes to assimp.
enum class MeshFormat { off, ply, obj, stl, other };

/// Refuses, from its first bytes `head` alone, a file of `size` bytes that cannot be of `format`
/// (chosen by its extension: detectMeshFormat did not recognise the content), with the error its
/// reader would give: a PLY that does not start with `ply`, an STL neither binary of the
/// announced size nor ascii, OFF or OBJ text with a NUL byte.
void requireFormatStart(MeshFormat format, std::string_view head, std::uintmax_t size);

/// The format of a file, by its content: `head` is its first bytes (at least the first 4 KiB, or
/// all of it), `size` its size. A PLY starts with the line `ply`; a binary STL has the size its
/// header announces; an ascii STL starts with `solid` and has `facet` or `endsolid` in `head`;
/// an OFF starts (after comments) with an OFF keyword; an OBJ starts (after comments and blank
/// lines) with an OBJ statement (`v` and three numbers, `vt`, `vn`, `f`, `o`, `g`, `mtllib`,
/// `usemtl`, `s`), unless assimp reads files of `extension` by another reader. Content that
/// none of these recognise falls back on `extension` (lower case, with its dot: ".off", ".ply",
/// ".obj", ".stl"), so that such a file gets the reader's error; anything else is `other`.
MeshFormat detectMeshFormat(std::string_view head, std::uintmax_t size, std::string_view extension,
                            bool assimpReadsExtension);

}  // namespace delta::detail
