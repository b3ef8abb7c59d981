#pragma once

#include <cstddef>
#include <filesystem>

#include "delta/mesh/mesh.h"

/// @file
/// Mesh import (Δ's own readers for OFF, PLY, OBJ and STL; assimp for the rest) and export
/// through the Open Asset Import Library (assimp).

/// Files: meshes (Δ's readers and assimp), query points from text, VTK output for ParaView.
namespace delta::io {

/// How the loaded coordinates relate to the numbers in the file.
enum class CoordinatePrecision {
  /// Δ's own readers (OFF, PLY, OBJ, STL): every coordinate is the file's number, decimal text
  /// correctly rounded to double, binary values widened exactly. A binary STL stores float32 by
  /// its format: its coordinates are exactly those floats, nothing finer was in the file.
  exact,
  /// assimp's readers (glTF, 3DS, X, ...): coordinates were rounded to single precision on the
  /// way (Debian builds assimp with a 32-bit ai_real), so they may differ from the file's numbers
  /// by a relative 6e-8.
  single,
};

/// "exact" or "single", as `delta info --json` and the Python module name it.
const char* toString(CoordinatePrecision precision) noexcept;

/// What an import found beside the triangles it kept.
///
/// Threading: a value type; no shared state.
struct LoadStatistics {
  /// Mesh placements merged into one: a mesh that n nodes place counts n times; placements
  /// without triangles do not count.
  std::size_t meshes = 0;
  /// Vertices of the kept triangles as the file gives them (assimp's readers: as assimp
  /// delivered them), before joining (an STL facet brings its own three).
  std::size_t sourceVertices = 0;
  /// Point primitives (OBJ's `p`, faces of one corner), and the vertices of a file or mesh that
  /// declares no faces at all: a PLY without a face element or with an empty one (`element face
  /// 0`), an OBJ without `f`, `p` or `l`, a mesh assimp delivers without faces. An OFF file
  /// without faces is refused before counting.
  std::size_t pointsSkipped = 0;
  std::size_t linesSkipped = 0;  ///< line primitives (OBJ's `l`, faces of two corners)
  /// Whether the coordinates are the file's numbers or were rounded to single precision.
  CoordinatePrecision precision = CoordinatePrecision::exact;
};

/// A loaded mesh and what its import skipped.
///
/// Threading: a value type; no shared state.
struct LoadedMesh {
  Mesh mesh;
  LoadStatistics statistics;
};

/// Loads every triangle of the file at `path`: OFF, PLY, OBJ and STL with Δ's own readers, in
/// double precision (src/io/detail/mesh_readers.h), any other format assimp reads (glTF, 3DS, X,
/// ...) through assimp:
/// - the reader is chosen by the file's content (a `ply` line, a binary STL of its announced
///   size, `solid` ... `facet`, an OFF keyword, an OBJ statement), then by the extension (.off,
///   .ply, .obj, .stl, case-insensitive, so that such a file gets its reader's error), else
///   assimp: an OFF file named .dat is read, and checked, as OFF;
/// - all meshes of the scene merged, each placed by the transforms of the nodes above it (a mesh
///   placed by several nodes appears once per placement);
/// - polygons triangulated: by Δ's readers as a fan from the first corner when convex, by ear
///   clipping in the polygon's plane when not (detail::triangulatePolygon), orientation kept; by
///   assimp's aiProcess_Triangulate otherwise (the corners of a triangle may come rotated);
/// - vertices at exactly the same position joined, across meshes and whatever their normals or
///   texture coordinates (so topology checks see a closed STL as closed); vertices that no
///   triangle uses dropped; the others in the file's order;
/// - points and lines skipped and counted.
/// Triangle order is the file's order, mesh after mesh in the order of the node tree. Degenerate
/// triangles are kept (a triangle whose corners are joined into one vertex keeps its repeated
/// index), as are overlapping and self-intersecting ones: a file is taken as it is.
///
/// Precision (statistics.precision): Δ's readers give each coordinate exactly as the file holds
/// it, decimal text correctly rounded to double (std::from_chars), binary values widened
/// exactly; a binary STL stores float32 by its format, read as such. assimp stores coordinates
/// as its ai_real, a 32-bit float in Debian's build, so coordinates of its formats arrive rounded
/// to single precision (CoordinatePrecision::single); node transforms are applied in double
/// precision. A mesh built in memory keeps full double precision.
///
/// Isolation: assimp runs in a child process (fork; at most 4 GiB of address space beyond the
/// caller's plus 64 bytes a byte of the file, 60 s of processor time, 120 s in all), so that a
/// damaged file on which assimp crashes, aborts or hangs is an error, not the end of the caller.
///
/// Throws delta::Error, naming the path and the reason, for a missing file, a directory or any
/// other file that is not a regular file (a FIFO, /dev/zero: refused at once, without reading),
/// an unreadable or empty file, a format that no reader reads, a malformed file (counts that the
/// file's size cannot hold, refused before anything is allocated for them; indices out of range;
/// a truncated or padded binary body; missing or extra elements), a coordinate that is not a
/// finite double (nan, inf, a decimal like 1e999: the line and value named), a file with no
/// triangles, or when assimp crashes, exceeds its limits or fails. Never returns a partial mesh.
/// A file of a format Δ reads whose first bytes show it cannot be one (a 3 GB sparse .ply that
/// does not start with `ply`) is refused after reading its first 4 KiB.
///
/// Threading: may be called from several threads at once (each call has its own reader, or its
/// own importer in its own child process; Δ installs no assimp logger).
LoadedMesh loadWithStatistics(const std::filesystem::path& path);

/// loadWithStatistics(path).mesh: the same contract, errors and threading.
Mesh load(const std::filesystem::path& path);

/// Writes the mesh to `path` in the format its extension names, case-insensitive: .stl (binary)
/// or .ply (binary) through assimp's exporters, .obj (text, no material file: each coordinate in
/// the shortest decimal that reads back to the same double), or .vtp (VTK XML PolyData for
/// ParaView, io/vtk.h: coordinates in double, bit for bit). Loading an .stl, .ply or .obj file
/// again gives the same triangles in the same order, with coordinates rounded to single
/// precision (.stl, .ply: the formats' floats) or exactly (.obj); vertices are joined on loading,
/// so an STL comes back with shared vertices. Δ does not read .vtp.
///
/// Throws delta::Error, naming the path and the reason, for another extension, a coordinate
/// beyond single precision or a mesh whose largest coordinate is below its normal range (about
/// 1.2e-38, where the file would round the vertices to zero; .stl, .ply), or when writing
/// fails (a full disk, /dev/full). The
/// file is written whole or not at all (io/atomic_file.h): an existing file is replaced only by a
/// complete one, and left as it was when writing fails; a symlink at `path` is kept and its target
/// replaced. Degenerate triangles are written as they are.
///
/// Threading: may be called from several threads at once, for different paths.
void save(const Mesh& mesh, const std::filesystem::path& path);

}  // namespace delta::io
