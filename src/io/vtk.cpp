#include "delta/io/vtk.h"

#include <zlib.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <type_traits>
#include <utility>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/io/atomic_file.h"

namespace delta::io {
namespace {

static_assert(std::endian::native == std::endian::little, "the writer emits little-endian data");

/// `text` as an XML attribute value.
std::string escaped(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '"')
      out += "&quot;";
    else
      out += c;
  }
  return out;
}

/// Bytes as the file stores them.
using Bytes = std::span<const unsigned char>;

template <typename T>
Bytes bytesOf(std::span<const T> values) noexcept {
  return {reinterpret_cast<const unsigned char*>(values.data()), values.size_bytes()};
}

/// A buffer that is not zeroed first (the encoders write every byte they keep).
struct Buffer {
  std::unique_ptr<unsigned char[]> data;
  std::size_t size = 0;
};

Buffer uninitialised(std::size_t size) {
  return {std::make_unique_for_overwrite<unsigned char[]>(size), size};
}

/// Ends a zlib stream however the block loop leaves.
struct Deflater {
  z_stream stream{};
  explicit Deflater(int level) {
    if (deflateInit(&stream, level) != Z_OK) throw Error("zlib cannot start compressing");
  }
  ~Deflater() { deflateEnd(&stream); }
  Deflater(const Deflater&) = delete;
  Deflater& operator=(const Deflater&) = delete;
};

/// `bytes` as vtkZLibDataCompressor stores an array with header_type UInt64: the number of
/// blocks, kVtkBlockBytes, the size of a last partial block (0 when every block is whole), the
/// compressed size of each block, then the blocks, each a zlib stream of its own. The blocks are
/// compressed on parallelFor's threads, each into a slot of the largest size zlib may need, then
/// moved together.
Buffer zlibBlocks(Bytes bytes, int level) {
  const std::size_t blocks = (bytes.size() + kVtkBlockBytes - 1) / kVtkBlockBytes;
  const std::size_t slot = compressBound(kVtkBlockBytes);
  const std::size_t headerBytes = (3 + blocks) * sizeof(std::uint64_t);
  Buffer out = uninitialised(headerBytes + blocks * slot);
  std::vector<std::uint64_t> header(3 + blocks);
  header[0] = blocks;
  header[1] = kVtkBlockBytes;
  header[2] = bytes.size() % kVtkBlockBytes;
  constexpr std::size_t kBlocksPerTask = 4;
  parallelFor(0, blocks, kBlocksPerTask, [&](std::size_t begin, std::size_t end) {
    Deflater deflater(level);
    z_stream& stream = deflater.stream;
    for (std::size_t b = begin; b < end; ++b) {
      const std::size_t first = b * kVtkBlockBytes;
      const std::size_t size = std::min(kVtkBlockBytes, bytes.size() - first);
      deflateReset(&stream);
      stream.next_in = const_cast<unsigned char*>(bytes.data() + first);  // zlib reads it only
      stream.avail_in = static_cast<uInt>(size);
      stream.next_out = out.data.get() + headerBytes + b * slot;
      stream.avail_out = static_cast<uInt>(slot);
      if (deflate(&stream, Z_FINISH) != Z_STREAM_END) throw Error("zlib failed to compress");
      header[3 + b] = stream.total_out;
    }
  });
  std::size_t at = headerBytes;
  for (std::size_t b = 0; b < blocks; ++b) {  // the slots' contents, one after the other
    std::memmove(out.data.get() + at, out.data.get() + headerBytes + b * slot, header[3 + b]);
    at += header[3 + b];
  }
  std::memcpy(out.data.get(), header.data(), headerBytes);
  out.size = at;
  return out;
}

/// The appended-data section: each array's bytes encoded (compressed, or raw after a UInt64
/// byte count) in the order added, and the XML that points at them by offset. Arrays given as
/// Bytes are read where they are, and must outlive the object.
class AppendedData {
 public:
  /// zlib's `level` (checkLevel), 0 for raw data.
  explicit AppendedData(int level) noexcept : level_(level) {}

  bool compressed() const noexcept { return level_ > 0; }

  /// Adds an array and returns the XML element that describes it.
  std::string add(Bytes bytes, const char* type, const std::string& name, int components) {
    std::string element = std::string("<DataArray type=\"") + type + "\"";
    if (!name.empty()) element += " Name=\"" + escaped(name) + "\"";
    element += " NumberOfComponents=\"" + std::to_string(components) +
               "\" format=\"appended\" offset=\"" + std::to_string(size_) + "\"/>\n";
    if (compressed()) {
      keep(zlibBlocks(bytes, level_));
    } else {
      const std::uint64_t count = bytes.size();
      Buffer header = uninitialised(sizeof count);
      std::memcpy(header.data.get(), &count, sizeof count);
      keep(std::move(header));
      pieces_.push_back(bytes);
      size_ += bytes.size();
    }
    return element;
  }

  /// Adds an array of values the object keeps.
  template <typename T>
  std::string add(std::vector<T> values, const char* type, const std::string& name,
                  int components) {
    owned_.push_back(std::make_shared<std::vector<T>>(std::move(values)));
    const auto& kept = *std::static_pointer_cast<std::vector<T>>(owned_.back());
    return add(bytesOf(std::span<const T>(kept)), type, name, components);
  }

  /// Writes the encoded arrays one after the other.
  void writeTo(AtomicFile& file) const {
    for (const Bytes piece : pieces_)
      file.write({reinterpret_cast<const char*>(piece.data()), piece.size()});
  }

 private:
  void keep(Buffer buffer) {
    pieces_.push_back({buffer.data.get(), buffer.size});
    size_ += buffer.size;
    buffers_.push_back(std::move(buffer));
  }

  int level_;
  std::vector<Bytes> pieces_;                 ///< what the file holds, in order
  std::vector<Buffer> buffers_;               ///< encoded bytes and headers the pieces point into
  std::vector<std::shared_ptr<void>> owned_;  ///< values converted for the file
  std::uint64_t size_ = 0;
};

void checkLevel(int level) {
  if (level < 0 || level > 9)
    throw Error("compression level " + std::to_string(level) + " is not 0 (none) to 9");
}

void checkArrays(const std::vector<VtkArray>& arrays, std::size_t elements, const char* what) {
  for (const VtkArray& array : arrays)
    if (array.components < 1 || array.values.size() != elements * array.components)
      throw Error(std::string(what) + " array '" + array.name + "' has " +
                  std::to_string(array.values.size()) + " values for " + std::to_string(elements) +
                  " elements of " + std::to_string(array.components) + " components");
}

/// The values of `array` as integers of type T, exactly; throws delta::Error naming the array,
/// the element and the value where one is not an integer T holds.
template <typename T>
std::vector<T> exactIntegers(const VtkArray& array, const char* what) {
  constexpr int kBits = std::numeric_limits<T>::digits;
  const double lowest = std::numeric_limits<T>::is_signed ? -std::ldexp(1.0, kBits) : 0.0;
  const double beyond = std::ldexp(1.0, kBits);  // the first value above T's largest
  std::vector<T> integers(array.values.size());
  for (std::size_t i = 0; i < integers.size(); ++i) {
    const double value = array.values[i];
    if (!(value >= lowest && value < beyond && value == std::trunc(value)))
      throw Error(std::string(what) + " array '" + array.name + "' holds " + toString(value) +
                  " (element " + std::to_string(i / static_cast<std::size_t>(array.components)) +
                  "), which is not an " + vtkTypeName(array.type) + " exactly");
    integers[i] = static_cast<T>(value);
  }
  return integers;
}

std::string arrayElement(const VtkArray& array, const char* what, AppendedData& appended) {
  const char* type = vtkTypeName(array.type);
  switch (array.type) {
    case VtkType::Int64:
      return appended.add(exactIntegers<std::int64_t>(array, what), type, array.name,
                          array.components);
    case VtkType::Int32:
      return appended.add(exactIntegers<std::int32_t>(array, what), type, array.name,
                          array.components);
    case VtkType::UInt32:
      return appended.add(exactIntegers<std::uint32_t>(array, what), type, array.name,
                          array.components);
    case VtkType::UInt8:
      return appended.add(exactIntegers<std::uint8_t>(array, what), type, array.name,
                          array.components);
    case VtkType::Float64:
      break;
  }
  return appended.add(bytesOf(std::span<const double>(array.values)), type, array.name,
                      array.components);
}

/// Whether cells of `points` points and `references` point references in all can be written
/// with Int32 connectivity and offsets.
bool fitsInt32(std::size_t points, std::size_t references) noexcept {
  constexpr auto kLargest = static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max());
  return points <= kLargest && references <= kLargest;
}

/// The offsets of `count` cells of `size` points each, as integers of type T.
template <typename T>
std::vector<T> evenOffsets(std::size_t count, std::size_t size) {
  std::vector<T> offsets(count);
  for (std::size_t i = 0; i < count; ++i)
    offsets[i] = static_cast<T>((i + 1) * size);
  return offsets;
}

/// The connectivity and offsets elements (the content of a Verts, Polys or Cells element) of
/// cells of N points each, checked against the points. Int32 connectivity is the indices as
/// they are: a std::uint32_t below 2^31 has the bytes of the same std::int32_t.
template <std::size_t N>
std::string cellArrays(const std::vector<std::array<std::uint32_t, N>>& elements,
                       std::size_t points, const char* what, AppendedData& appended) {
  for (std::size_t e = 0; e < elements.size(); ++e)
    for (std::uint32_t index : elements[e])
      if (index >= points)
        throw Error(std::string(what) + " " + std::to_string(e) + " refers to point " +
                    std::to_string(index) + " of " + std::to_string(points));
  // Blocks are appended in the order of the elements in the XML: each `+=` below is a
  // statement of its own because the operands of one `+` chain are evaluated in an unspecified
  // order.
  std::string xml;
  if (fitsInt32(points, N * elements.size())) {
    static_assert(sizeof(std::array<std::uint32_t, N>) == N * sizeof(std::uint32_t));
    xml += appended.add(Bytes(reinterpret_cast<const unsigned char*>(elements.data()),
                              elements.size() * N * sizeof(std::uint32_t)),
                        "Int32", "connectivity", 1);
    xml += appended.add(evenOffsets<std::int32_t>(elements.size(), N), "Int32", "offsets", 1);
  } else {
    std::vector<std::int64_t> connectivity;
    connectivity.reserve(N * elements.size());
    for (const auto& element : elements)
      connectivity.insert(connectivity.end(), element.begin(), element.end());
    xml += appended.add(std::move(connectivity), "Int64", "connectivity", 1);
    xml += appended.add(evenOffsets<std::int64_t>(elements.size(), N), "Int64", "offsets", 1);
  }
  return xml;
}

/// The connectivity and offsets elements of one vertex cell per point (`count` of them).
template <typename T>
std::string vertexCellArrays(std::size_t count, const char* type, AppendedData& appended) {
  std::vector<T> connectivity(count);
  for (std::size_t i = 0; i < count; ++i)
    connectivity[i] = static_cast<T>(i);
  std::string xml = appended.add(std::move(connectivity), type, "connectivity", 1);
  xml += appended.add(evenOffsets<T>(count, 1), type, "offsets", 1);
  return xml;
}

std::string vertexCellArrays(std::size_t count, AppendedData& appended) {
  return fitsInt32(count, count) ? vertexCellArrays<std::int32_t>(count, "Int32", appended)
                                 : vertexCellArrays<std::int64_t>(count, "Int64", appended);
}

/// The connectivity and offsets elements of polylines (the content of a Lines element), checked
/// against the points: each of two points at least, none past the last.
template <typename T>
std::string polylineArrays(const std::vector<std::vector<std::uint32_t>>& lines, const char* type,
                           AppendedData& appended) {
  std::vector<T> connectivity, offsets;
  offsets.reserve(lines.size());
  for (const std::vector<std::uint32_t>& line : lines) {
    connectivity.insert(connectivity.end(), line.begin(), line.end());
    offsets.push_back(static_cast<T>(connectivity.size()));
  }
  std::string xml = appended.add(std::move(connectivity), type, "connectivity", 1);
  xml += appended.add(std::move(offsets), type, "offsets", 1);
  return xml;
}

std::string polylineArrays(const std::vector<std::vector<std::uint32_t>>& lines, std::size_t points,
                           AppendedData& appended) {
  std::size_t references = 0;
  for (std::size_t l = 0; l < lines.size(); ++l) {
    if (lines[l].size() < 2)
      throw Error("polyline " + std::to_string(l) + " has " + std::to_string(lines[l].size()) +
                  " point(s), fewer than two");
    for (std::uint32_t index : lines[l])
      if (index >= points)
        throw Error("polyline " + std::to_string(l) + " refers to point " + std::to_string(index) +
                    " of " + std::to_string(points));
    references += lines[l].size();
  }
  return fitsInt32(points, references) ? polylineArrays<std::int32_t>(lines, "Int32", appended)
                                       : polylineArrays<std::int64_t>(lines, "Int64", appended);
}

std::string dataSection(const char* tag, const std::vector<VtkArray>& arrays, const char* what,
                        AppendedData& appended) {
  std::string xml = std::string("<") + tag + ">\n";
  for (const VtkArray& array : arrays)
    xml += arrayElement(array, what, appended);
  return xml + "</" + tag + ">\n";
}

std::string pointSection(const std::vector<Vec3>& points, AppendedData& appended) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double) && std::is_standard_layout_v<Vec3>,
                "the points are written as they lie in memory: x, y, z, x, ...");
  return "<Points>\n" +
         appended.add(bytesOf(std::span<const Vec3>(points)), "Float64", "Points", 3) +
         "</Points>\n";
}

/// The XML up to and including the start of the appended data, for a file of `type`
/// (PolyData, UnstructuredGrid) whose Piece has `pieceAttributes` and holds `pieceContent`.
std::string document(const char* type, const std::string& pieceAttributes,
                     const std::string& pieceContent, bool compressed) {
  return std::string("<?xml version=\"1.0\"?>\n<VTKFile type=\"") + type +
         "\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\"" +
         (compressed ? " compressor=\"vtkZLibDataCompressor\"" : "") + ">\n<" + type +
         ">\n<Piece " + pieceAttributes + ">\n" + pieceContent + "</Piece>\n</" + type +
         ">\n<AppendedData encoding=\"raw\">\n_";
}

std::string polyDataDocument(const VtkPolyData& data, AppendedData& appended) {
  const std::size_t verts = data.pointsAsVertices ? data.points.size() : 0;
  const std::string attributes =
      "NumberOfPoints=\"" + std::to_string(data.points.size()) + "\" NumberOfVerts=\"" +
      std::to_string(verts) + "\" NumberOfLines=\"" + std::to_string(data.lines.size()) +
      "\" NumberOfStrips=\"0\" NumberOfPolys=\"" + std::to_string(data.triangles.size()) + "\"";
  std::string content = dataSection("PointData", data.pointData, "point", appended);
  content += dataSection("CellData", data.cellData, "cell", appended);
  content += pointSection(data.points, appended);
  content += "<Verts>\n";
  content += vertexCellArrays(verts, appended);
  content += "</Verts>\n";
  if (!data.lines.empty()) {  // files without polylines stay as they were
    content += "<Lines>\n";
    content += polylineArrays(data.lines, data.points.size(), appended);
    content += "</Lines>\n";
  }
  content += "<Polys>\n";
  content += cellArrays(data.triangles, data.points.size(), "triangle", appended);
  content += "</Polys>\n";
  return document("PolyData", attributes, content, appended.compressed());
}

std::string unstructuredGridDocument(const VtkVoxelGrid& grid, AppendedData& appended) {
  constexpr std::uint8_t kVtkVoxel = 11;
  const std::string attributes = "NumberOfPoints=\"" + std::to_string(grid.points.size()) +
                                 "\" NumberOfCells=\"" + std::to_string(grid.voxels.size()) + "\"";
  std::string content = dataSection("PointData", grid.pointData, "point", appended);
  content += dataSection("CellData", grid.cellData, "cell", appended);
  content += pointSection(grid.points, appended);
  content += "<Cells>\n";
  content += cellArrays(grid.voxels, grid.points.size(), "voxel", appended);
  content +=
      appended.add(std::vector<std::uint8_t>(grid.voxels.size(), kVtkVoxel), "UInt8", "types", 1);
  return document("UnstructuredGrid", attributes, content + "</Cells>\n", appended.compressed());
}

/// Writes the XML head, the appended block and the closing tags, all or nothing (AtomicFile).
void writeDocument(const std::string& head, const AppendedData& appended,
                   const std::filesystem::path& path) {
  AtomicFile file(path);
  file.write(head);
  appended.writeTo(file);
  file.write("\n</AppendedData>\n</VTKFile>\n");
  file.commit();
}

/// The PDataArray elements of a .pvtp's PPointData or PCellData: each array's name and
/// components, as writeVtp declares them.
std::string parallelDataSection(const char* tag, const std::vector<VtkArray>& arrays) {
  std::string xml = std::string("<") + tag + ">\n";
  for (const VtkArray& array : arrays) {
    if (array.components < 1)
      throw Error("array '" + array.name + "' has " + std::to_string(array.components) +
                  " components");
    xml += std::string("<PDataArray type=\"") + vtkTypeName(array.type) + "\" Name=\"" +
           escaped(array.name) + "\" NumberOfComponents=\"" + std::to_string(array.components) +
           "\"/>\n";
  }
  return xml + "</" + tag + ">\n";
}

/// What `make` returns (the checked data as a document), with its errors naming `path`; the
/// writing that follows names the path itself (AtomicFile).
template <typename Make>
std::string documentFor(const std::filesystem::path& path, const Make& make) {
  try {
    return make();
  } catch (const Error& error) {
    throw Error("cannot write '" + path.string() + "': " + error.what());
  }
}

}  // namespace

const char* vtkTypeName(VtkType type) noexcept {
  switch (type) {
    case VtkType::Int64:
      return "Int64";
    case VtkType::Int32:
      return "Int32";
    case VtkType::UInt32:
      return "UInt32";
    case VtkType::UInt8:
      return "UInt8";
    case VtkType::Float64:
      break;
  }
  return "Float64";
}

VtkPolyData VtkPolyData::fromMesh(const Mesh& mesh) {
  VtkPolyData data;
  data.points.assign(mesh.vertices().begin(), mesh.vertices().end());
  data.triangles.assign(mesh.triangles().begin(), mesh.triangles().end());
  return data;
}

VtkPolyData VtkPolyData::fromPoints(std::vector<Vec3> points) {
  VtkPolyData data;
  data.points = std::move(points);
  data.pointsAsVertices = true;
  return data;
}

void writeVtp(const VtkPolyData& data, const std::filesystem::path& path,
              const VtkWriteOptions& options) {
  AppendedData appended(options.compressionLevel);
  const std::string head = documentFor(path, [&] {
    checkLevel(options.compressionLevel);
    checkArrays(data.pointData, data.points.size(), "point");
    checkArrays(data.cellData, data.cellCount(), "cell");
    return polyDataDocument(data, appended);
  });
  writeDocument(head, appended, path);
}

void writeVtu(const VtkVoxelGrid& grid, const std::filesystem::path& path,
              const VtkWriteOptions& options) {
  AppendedData appended(options.compressionLevel);
  const std::string head = documentFor(path, [&] {
    checkLevel(options.compressionLevel);
    checkArrays(grid.pointData, grid.points.size(), "point");
    checkArrays(grid.cellData, grid.voxels.size(), "cell");
    return unstructuredGridDocument(grid, appended);
  });
  writeDocument(head, appended, path);
}

void writePvd(std::span<const VtkSeriesEntry> entries, const std::filesystem::path& path) {
  const std::string xml = documentFor(path, [&] {
    std::string text =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" "
        "byte_order=\"LittleEndian\">\n<Collection>\n";
    for (const VtkSeriesEntry& entry : entries) {
      if (!std::isfinite(entry.time))
        throw Error("time " + toString(entry.time) + " of '" + entry.file.string() +
                    "' is not finite");
      char time[32];
      std::snprintf(time, sizeof time, "%.17g", entry.time);
      text += std::string("<DataSet timestep=\"") + time + "\" group=\"\" part=\"0\" file=\"" +
              escaped(entry.file.generic_string()) + "\"/>\n";
    }
    return text + "</Collection>\n</VTKFile>\n";
  });
  writeFileAtomically(path, xml);
}

void writePvtp(const VtkPolyData& layout, std::span<const std::filesystem::path> pieces,
               const std::filesystem::path& path) {
  const std::string xml = documentFor(path, [&] {
    if (pieces.empty()) throw Error("no pieces to show");
    std::string text =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"PPolyData\" version=\"1.0\" "
        "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<PPolyData GhostLevel=\"0\">\n";
    text += parallelDataSection("PPointData", layout.pointData);
    text += parallelDataSection("PCellData", layout.cellData);
    text +=
        "<PPoints>\n<PDataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"/>\n"
        "</PPoints>\n";
    for (const std::filesystem::path& piece : pieces)
      text += "<Piece Source=\"" + escaped(piece.generic_string()) + "\"/>\n";
    return text + "</PPolyData>\n</VTKFile>\n";
  });
  writeFileAtomically(path, xml);
}

}  // namespace delta::io
