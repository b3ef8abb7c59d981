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
/// Output that ParaView opens: VTK XML PolyData (.vtp) and UnstructuredGrid (.vtu), parallel
/// PolyData (.pvtp) that joins .vtp pieces into one data set, and ParaView collections (.pvd) that
/// play files as a time series. The data are appended binary, little-endian, compressed by default
/// with zlib in blocks as VTK's vtkZLibDataCompressor writes them (VtkWriteOptions), which
/// ParaView and VTK's readers read; measured values are written as the doubles they are (Float64),
/// ids and flags as the integer types their arrays name (VtkType). Each writer replaces an
/// existing file whole or not at all (io/atomic_file.h: a failed write, a full disk, leaves the
/// previous file as it was and no temporary file; a symlink at the path is kept and its target
/// replaced), writes empty data as a valid empty file (a .pvtp needs one piece at least), and
/// writes coordinates and values as they are (NaN included).
///
/// Threading: the writers read their arguments only; they may run on several threads at once,
/// for different paths. A writer compresses the blocks of a large array on the OpenMP threads of
/// delta::parallelFor (serially when called inside a parallel region).

namespace delta::io {

/// How a VtkArray's values are stored in the file (VTK's type names).
///
/// Threading: a value type.
enum class VtkType : std::uint8_t {
  Float64,  ///< measured values (coordinates, velocities, distances): the doubles as computed
  Int64,
  Int32,
  UInt32,  ///< ids and indices (Δ's are std::uint32_t)
  UInt8,   ///< flags (0 or 1) and small counts such as grid levels
};

/// The name VTK's XML formats give `type`: "Float64", "Int64", "Int32", "UInt32" or "UInt8".
const char* vtkTypeName(VtkType type) noexcept;

/// A named array of values attached to points or cells: `components` values per element
/// (1 for a scalar, 3 for a vector), element after element, stored in the file as `type`.
///
/// The values are held as doubles whatever the type (every integer of the types above up to
/// 2^53 is a double exactly). An integer type writes each value as that integer, exactly: a
/// writer throws delta::Error naming the array, the element and the value when one is not an
/// integer within the type's range (2.5 or NaN for any of them, -1 for UInt8, 2^31 for Int32),
/// and never rounds. Float64 writes the doubles bit for bit.
///
/// Threading: a value type; no shared state.
struct VtkArray {
  std::string name;
  int components = 1;
  std::vector<double> values;
  VtkType type = VtkType::Float64;
};

/// How writeVtp and writeVtu encode the appended data.
///
/// Threading: a value type.
struct VtkWriteOptions {
  /// 1 (fastest, the default) to 9 (smallest): zlib's level; each array is compressed in blocks
  /// of kVtkBlockBytes (header_type UInt64: the number of blocks, the block size, the size of a
  /// last partial block or 0, each block's compressed size, then the blocks; format
  /// `compressor="vtkZLibDataCompressor"`). 0: no compression, each array's bytes after their
  /// UInt64 count: the fastest to write (zlib level 1 costs about 5 ns a byte on one core), for
  /// files rewritten every step (`delta ib`) or read by a simple tool. Other levels are refused
  /// with delta::Error.
  int compressionLevel = 1;
};

/// The uncompressed size of a compressed block (VTK's own default): the last one of an array
/// may be shorter.
inline constexpr std::size_t kVtkBlockBytes = std::size_t{1} << 15;

/// Points, optionally joined into polylines and triangles, with data per point and per cell.
///
/// Cells are, in VTK's order: one vertex cell per point when `pointsAsVertices` (so that a bare
/// point set shows in ParaView), then the polylines, then the triangles. A cell array has one
/// element per cell.
///
/// Threading: a value type; no shared state.
struct VtkPolyData {
  std::vector<Vec3> points;
  /// Polylines (VTK's Lines cells): each the indices of its points in order, two at least; a
  /// closed curve repeats its first index at the end.
  std::vector<std::vector<std::uint32_t>> lines;
  std::vector<TriangleIndices> triangles;
  bool pointsAsVertices = false;
  std::vector<VtkArray> pointData;
  std::vector<VtkArray> cellData;

  /// The mesh's vertices and triangles (degenerate ones included), in its order.
  static VtkPolyData fromMesh(const Mesh& mesh);
  /// A point set, each point a vertex cell.
  static VtkPolyData fromPoints(std::vector<Vec3> points);

  /// Vertex cells (when `pointsAsVertices`) plus polylines plus triangles.
  std::size_t cellCount() const noexcept {
    return (pointsAsVertices ? points.size() : 0) + lines.size() + triangles.size();
  }
};

/// Writes `data` as a VTK XML PolyData file (format version 1.0, appended little-endian data
/// encoded as `options` say, Float64 points, each array as its VtkType; connectivity and offsets
/// Int32 where the points and the cells' point references fit, 2^31 − 1 at most, Int64
/// otherwise). Throws delta::Error naming the path when an array's size does not match its
/// points or cells, an integer array holds a value its type cannot store exactly, a polyline
/// has fewer than two points, a polyline or a triangle refers past the points, the compression
/// level is not 0 to 9, or writing fails.
void writeVtp(const VtkPolyData& data, const std::filesystem::path& path,
              const VtkWriteOptions& options = {});

/// Writes a ParaView parallel PolyData file (.pvtp) that shows `pieces` — .vtp files written by
/// writeVtp, each path relative to the .pvtp file or absolute, in the order given — as one data
/// set: what each process of a parallel run writes its own piece of, and one process writes the
/// .pvtp for. `layout` is the data of any one piece: only the names, components and types of its
/// point and cell arrays are read, and every piece must have been written with the same arrays
/// (names, components and types; each piece may be compressed or not). A piece may hold no points;
/// the pieces need not exist yet. Throws delta::Error naming the path when there are no pieces, an
/// array has fewer than one component, or writing fails (leaving the previous file); replaces an
/// existing file.
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
/// version 1.0, appended little-endian data as `options` say, Float64 points, each array as its
/// VtkType, Int32 connectivity and offsets where they fit and Int64 otherwise, UInt8 cell
/// types). Throws delta::Error naming the path when an array's size does not match its points
/// or voxels, an integer array holds a value its type cannot store exactly, a voxel refers past
/// the points (writing nothing), the compression level is not 0 to 9, or writing fails (leaving
/// the previous file).
void writeVtu(const VtkVoxelGrid& grid, const std::filesystem::path& path,
              const VtkWriteOptions& options = {});

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
