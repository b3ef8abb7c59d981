#pragma once

#include <cstddef>
#include <filesystem>

#include "delta/mesh/mesh.h"

/// Mesh import and export through the Open Asset Import Library (assimp).
namespace delta::io {

/// What an import found beside the triangles it kept.
struct LoadStatistics {
  std::size_t meshes = 0;          ///< meshes in the scene, merged into one
  std::size_t sourceVertices = 0;  ///< vertices as assimp delivered them, before joining
  std::size_t pointsSkipped = 0;   ///< point primitives in the file (not triangles; dropped)
  std::size_t linesSkipped = 0;    ///< line primitives in the file (dropped)
};

struct LoadedMesh {
  Mesh mesh;
  LoadStatistics statistics;
};

/// Loads every triangle of the file at `path`, in any format assimp reads: all meshes of the
/// scene merged, each with its node transform applied; polygons triangulated; vertices at the
/// same position joined (so topology checks see a closed mesh as closed); points and lines
/// skipped and counted. Triangle order is the file's order, mesh after mesh.
///
/// Precision: Debian's assimp stores coordinates as 32-bit floats (its ai_real), so coordinates
/// arrive rounded to single precision; a mesh built in memory keeps full double precision.
///
/// Throws delta::Error, naming the path and the reason, for a missing file, a directory, an
/// unreadable, empty, truncated or malformed file, non-finite coordinates, or a file with no
/// triangles. Never returns a partial mesh.
///
/// Threading: may be called from several threads at once (each call has its own importer).
LoadedMesh loadWithStatistics(const std::filesystem::path& path);

/// loadWithStatistics(path).mesh.
Mesh load(const std::filesystem::path& path);

/// Writes the mesh to `path` in the format its extension names: .stl (binary), .ply (binary) or
/// .obj (case-insensitive), through assimp's exporters. Throws delta::Error for another extension
/// or when writing fails. Loading the file again gives the same triangles in the same order, with
/// coordinates rounded to single precision (assimp's, and binary STL's, precision).
void save(const Mesh& mesh, const std::filesystem::path& path);

}  // namespace delta::io
