#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "delta/core/vec3.h"
#include "delta/mesh/mesh.h"

/// @file
/// Output that ParaView opens: VTK XML PolyData (.vtp) and UnstructuredGrid (.vtu), binary, double
/// precision, parallel PolyData (.pvtp) that joins .vtp pieces into one data set, and ParaView
/// collections (.pvd) that play files as a time series. Each writer replaces an existing file
/// whole or not at all (io/atomic_file.h: a failed write, a full disk, leaves the previous file
/// as it was and no temporary file; a symlink at the path is kept and its target replaced),
/// writes empty data as a valid empty file (a .pvtp needs one piece at least), and writes
/// coordinates and values as they are (NaN included).
///
/// Threading: the writers read their arguments only; they may run on several threads at once,
/// for different paths.

namespace delta::io {

/// A named array of values attached to points or cells: `components` values per element
/// (1 for a scalar, 3 for a vector), element after element.
///
/// Threading: a value type; no shared state.
struct VtkArray {
  std::string name;
  int components = 1;
  std::vector<double> values;
};

/// Points, optionally joined into triangles, with data per point and per cell.
///
/// Cells are, in this order: one vertex cell per point when `pointsAsVertices` (so that a bare
/// point set shows in ParaView), then the triangles. A cell array has one element per cell.
///
/// Threading: a value type; no shared state.
struct VtkPolyData {
  std::vector<Vec3> points;
  std::vector<TriangleIndices> triangles;
  bool pointsAsVertices = false;
  std::vector<VtkArray> pointData;
  std::vector<VtkArray> cellData;

  /// The mesh's vertices and triangles (degenerate ones included), in its order.
  static VtkPolyData fromMesh(const Mesh& mesh);
  /// A point set, each point a vertex cell.
  static VtkPolyData fromPoints(std::vector<Vec3> points);

  /// Vertex cells (when `pointsAsVertices`) plus triangles.
  std::size_t cellCount() const noexcept {
    return (pointsAsVertices ? points.size() : 0) + triangles.size();
  }
};

/// Writes `data` as a VTK XML PolyData file (format version 1.0, raw appended little-endian
/// data, Float64 values, Int64 connectivity). Throws delta::Error naming the path when an array's
/// size does not match its points or cells, a triangle refers past the points, or writing fails.
void writeVtp(const VtkPolyData& data, const std::filesystem::path& path);

/// Writes a ParaView parallel PolyData file (.pvtp) that shows `pieces` — .vtp files written by
/// writeVtp, each path relative to the .pvtp file or absolute, in the order given — as one data
/// set: what each process of a parallel run writes its own piece of, and one process writes the
/// .pvtp for. `layout` is the data of any one piece: only the names and components of its point
/// and cell arrays are read, and every piece must have been written with the same arrays (names
/// and components). A piece may hold no points; the pieces need not exist yet. Throws delta::Error
/// naming the path when there are no pieces, an array has fewer than one component, or writing
/// fails (leaving the previous file); replaces an existing file.
void writePvtp(const VtkPolyData& layout, std::span<const std::filesystem::path> pieces,
               const std::filesystem::path& path);

/// Axis-aligned hexahedra (VTK_VOXEL, cell type 11): eight point indices each, corner c at offset
/// (c & 1, (c >> 1) & 1, (c >> 2) & 1) from the lowest corner — VTK's voxel order. The writer does
/// not check that the points form boxes; ParaView draws what the indices say.
///
/// Threading: a value type; no shared state.
struct VtkVoxelGrid {
  std::vector<Vec3> points;
  std::vector<std::array<std::uint32_t, 8>> voxels;
  std::vector<VtkArray> pointData;
  std::vector<VtkArray> cellData;  ///< one element per voxel
};

/// Writes `grid` as a VTK XML UnstructuredGrid file (.vtu), encoded as writeVtp encodes (format
/// version 1.0, raw appended little-endian data, Float64 values, Int64 connectivity and offsets,
/// UInt8 cell types). Throws delta::Error naming the path when an array's size does not match
/// its points or voxels, a voxel refers past the points (writing nothing), or writing fails
/// (leaving the previous file).
void writeVtu(const VtkVoxelGrid& grid, const std::filesystem::path& path);

/// One file of a time series: the time it shows and where it is, relative to the .pvd file
/// (or absolute).
///
/// Threading: a value type; no shared state.
struct VtkSeriesEntry {
  double time = 0.0;
  std::filesystem::path file;
};

/// Writes a ParaView collection (.pvd) that plays `entries` as a time series, in the order
/// given (ParaView sorts them by time). Throws delta::Error naming the path when a time is not
/// finite or writing fails. Write it again after each new file so that a run cut short still
/// leaves a series that opens.
void writePvd(std::span<const VtkSeriesEntry> entries, const std::filesystem::path& path);

}  // namespace delta::io
