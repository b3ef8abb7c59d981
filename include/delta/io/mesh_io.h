#pragma once

#include <cstddef>
#include <filesystem>

#include "delta/mesh/mesh.h"

/// @file
/// Mesh import and export through the Open Asset Import Library (assimp).

/// Files: meshes through assimp, query points from text, VTK output for ParaView.
namespace delta::io {

/// What an import found beside the triangles it kept.
///
/// Threading: a value type; no shared state.
struct LoadStatistics {
  /// Mesh placements merged into one: a mesh that n nodes place counts n times; placements
  /// without triangles do not count.
  std::size_t meshes = 0;
  /// Vertices of the kept triangles as assimp delivered them, before joining (an STL facet
  /// brings its own three).
  std::size_t sourceVertices = 0;
  std::size_t pointsSkipped = 0;  ///< point primitives, and the vertices of meshes without faces
  std::size_t linesSkipped = 0;   ///< line primitives
};

/// A loaded mesh and what its import skipped.
///
/// Threading: a value type; no shared state.
struct LoadedMesh {
  Mesh mesh;
  LoadStatistics statistics;
};

/// Loads every triangle of the file at `path`, in any format assimp reads (OFF, OBJ, STL, PLY,
/// glTF, ...):
/// - all meshes of the scene merged, each placed by the transforms of the nodes above it (a mesh
///   placed by several nodes appears once per placement);
/// - polygons triangulated (assimp's aiProcess_Triangulate; when a mesh holds polygons, the
///   corners of its triangles may come rotated, orientation kept);
/// - vertices at exactly the same position joined, across meshes and whatever their normals or
///   texture coordinates (so topology checks see a closed STL as closed); vertices that no
///   triangle uses dropped; the others in the file's order;
/// - points and lines skipped and counted.
/// Triangle order is the file's order, mesh after mesh in the order of the node tree. Degenerate
/// triangles are kept (a triangle whose corners are joined into one vertex keeps its repeated
/// index), as are overlapping and self-intersecting ones: a file is taken as it is.
///
/// Precision: assimp stores coordinates as its ai_real, a 32-bit float in Debian's build (defs.h
/// makes it double only with ASSIMP_DOUBLE_PRECISION, which Debian's config.h leaves undefined),
/// so coordinates arrive rounded to single precision; node transforms are applied in double
/// precision. A mesh built in memory keeps full double precision.
///
/// Throws delta::Error, naming the path and the reason, for a missing file, a directory, an
/// unreadable or empty file, a format assimp does not read, a malformed file, non-finite
/// coordinates, or a file with no triangles. Never returns a partial mesh. Assimp's readers take
/// some damaged files without complaint and return wrong geometry; Δ checks OFF, OBJ, PLY and
/// STL files itself before (io/detail/format_checks.h): a truncated binary STL or PLY, element
/// counts that do not match the file, out-of-range OFF indices are errors. OFF files are read
/// with their comments removed, which assimp's reader does not skip between elements.
///
/// Threading: may be called from several threads at once (each call has its own importer; Δ
/// installs no assimp logger).
LoadedMesh loadWithStatistics(const std::filesystem::path& path);

/// loadWithStatistics(path).mesh: the same contract, errors and threading.
Mesh load(const std::filesystem::path& path);

/// Writes the mesh to `path` in the format its extension names, case-insensitive: .stl (binary),
/// .ply (binary) or .obj (no material file), through assimp's exporters. Loading the file again
/// gives the same triangles in the same order, with coordinates rounded to single precision
/// (assimp's precision, and the formats'); vertices are joined on loading, so an STL comes back
/// with shared vertices.
///
/// Throws delta::Error, naming the path and the reason, for another extension, a coordinate
/// beyond single precision, or when writing fails. An existing file is replaced. Degenerate
/// triangles are written as they are.
///
/// Threading: may be called from several threads at once, for different paths.
void save(const Mesh& mesh, const std::filesystem::path& path);

}  // namespace delta::io
