#include "delta/io/vtk.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>

#include "delta/core/error.h"
#include "delta/core/format.h"
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

/// The appended-data section: blocks of raw bytes, each preceded by its UInt64 byte count, and
/// the XML that points at them by offset.
class AppendedData {
 public:
  /// Adds a block and returns the XML element that describes it.
  template <typename T>
  std::string add(const std::vector<T>& values, const char* type, const std::string& name,
                  int components) {
    std::ostringstream element;
    element << "<DataArray type=\"" << type << "\"";
    if (!name.empty()) element << " Name=\"" << escaped(name) << "\"";
    element << " NumberOfComponents=\"" << components << "\" format=\"appended\" offset=\""
            << bytes_.size() << "\"/>\n";
    const std::uint64_t size = values.size() * sizeof(T);
    append(&size, sizeof size);
    append(values.data(), size);
    return element.str();
  }

  const std::string& bytes() const noexcept { return bytes_; }

 private:
  void append(const void* data, std::size_t size) {
    if (size > 0) bytes_.append(static_cast<const char*>(data), size);
  }
  std::string bytes_;
};

void checkArrays(const std::vector<VtkArray>& arrays, std::size_t elements, const char* what) {
  for (const VtkArray& array : arrays)
    if (array.components < 1 || array.values.size() != elements * array.components)
      throw Error(std::string(what) + " array '" + array.name + "' has " +
                  std::to_string(array.values.size()) + " values for " + std::to_string(elements) +
                  " elements of " + std::to_string(array.components) + " components");
}

/// Connectivity and offsets of cells: the vertex cells, the triangles or the voxels.
struct Cells {
  std::vector<std::int64_t> connectivity;
  std::vector<std::int64_t> offsets;
};

Cells vertexCells(std::size_t points) {
  Cells cells;
  for (std::size_t i = 0; i < points; ++i) {
    cells.connectivity.push_back(static_cast<std::int64_t>(i));
    cells.offsets.push_back(static_cast<std::int64_t>(i + 1));
  }
  return cells;
}

/// Cells of a fixed number of points each (triangles, voxels), checked against the points.
template <std::size_t N>
Cells indexedCells(const std::vector<std::array<std::uint32_t, N>>& elements, std::size_t points,
                   const char* what) {
  Cells cells;
  cells.connectivity.reserve(N * elements.size());
  cells.offsets.reserve(elements.size());
  for (std::size_t e = 0; e < elements.size(); ++e) {
    for (std::uint32_t index : elements[e]) {
      if (index >= points)
        throw Error(std::string(what) + " " + std::to_string(e) + " refers to point " +
                    std::to_string(index) + " of " + std::to_string(points));
      cells.connectivity.push_back(index);
    }
    cells.offsets.push_back(static_cast<std::int64_t>(cells.connectivity.size()));
  }
  return cells;
}

std::string dataSection(const char* tag, const std::vector<VtkArray>& arrays,
                        AppendedData& appended) {
  std::string xml = std::string("<") + tag + ">\n";
  for (const VtkArray& array : arrays)
    xml += appended.add(array.values, "Float64", array.name, array.components);
  return xml + "</" + tag + ">\n";
}

// Blocks are appended in the order of the elements in the XML: each `+=` below is a statement of
// its own because the operands of one `+` chain are evaluated in an unspecified order.

/// The connectivity and offsets arrays of `cells` (the content of a Verts, Polys or Cells element).
std::string cellArrays(const Cells& cells, AppendedData& appended) {
  std::string xml = appended.add(cells.connectivity, "Int64", "connectivity", 1);
  xml += appended.add(cells.offsets, "Int64", "offsets", 1);
  return xml;
}

std::string cellSection(const char* tag, const Cells& cells, AppendedData& appended) {
  std::string xml = std::string("<") + tag + ">\n";
  xml += cellArrays(cells, appended);
  return xml + "</" + tag + ">\n";
}

std::string pointSection(const std::vector<Vec3>& points, AppendedData& appended) {
  std::vector<double> coordinates;
  coordinates.reserve(3 * points.size());
  for (const Vec3& p : points)
    coordinates.insert(coordinates.end(), {p.x, p.y, p.z});
  return "<Points>\n" + appended.add(coordinates, "Float64", "Points", 3) + "</Points>\n";
}

/// The XML up to and including the start of the appended data, for a file of `type`
/// (PolyData, UnstructuredGrid) whose Piece has `pieceAttributes` and holds `pieceContent`.
std::string document(const char* type, const std::string& pieceAttributes,
                     const std::string& pieceContent) {
  return std::string("<?xml version=\"1.0\"?>\n<VTKFile type=\"") + type +
         "\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<" + type +
         ">\n<Piece " + pieceAttributes + ">\n" + pieceContent + "</Piece>\n</" + type +
         ">\n<AppendedData encoding=\"raw\">\n_";
}

std::string polyDataDocument(const VtkPolyData& data, AppendedData& appended) {
  const Cells verts = vertexCells(data.pointsAsVertices ? data.points.size() : 0);
  const Cells polys = indexedCells(data.triangles, data.points.size(), "triangle");
  std::ostringstream attributes;
  attributes << "NumberOfPoints=\"" << data.points.size() << "\" NumberOfVerts=\""
             << verts.offsets.size()
             << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\""
             << polys.offsets.size() << "\"";
  std::string content = dataSection("PointData", data.pointData, appended);
  content += dataSection("CellData", data.cellData, appended);
  content += pointSection(data.points, appended);
  content += cellSection("Verts", verts, appended);
  content += cellSection("Polys", polys, appended);
  return document("PolyData", attributes.str(), content);
}

std::string unstructuredGridDocument(const VtkVoxelGrid& grid, AppendedData& appended) {
  constexpr std::uint8_t kVtkVoxel = 11;
  const Cells voxels = indexedCells(grid.voxels, grid.points.size(), "voxel");
  const std::vector<std::uint8_t> types(grid.voxels.size(), kVtkVoxel);
  const std::string attributes = "NumberOfPoints=\"" + std::to_string(grid.points.size()) +
                                 "\" NumberOfCells=\"" + std::to_string(grid.voxels.size()) + "\"";
  std::string content = dataSection("PointData", grid.pointData, appended);
  content += dataSection("CellData", grid.cellData, appended);
  content += pointSection(grid.points, appended);
  content += "<Cells>\n";
  content += cellArrays(voxels, appended);
  content += appended.add(types, "UInt8", "types", 1);
  return document("UnstructuredGrid", attributes, content + "</Cells>\n");
}

/// Writes the XML head, the appended block and the closing tags, all or nothing (AtomicFile).
void writeDocument(const std::string& head, const AppendedData& appended,
                   const std::filesystem::path& path) {
  AtomicFile file(path);
  file.write(head);
  file.write(appended.bytes());
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
    xml += "<PDataArray type=\"Float64\" Name=\"" + escaped(array.name) +
           "\" NumberOfComponents=\"" + std::to_string(array.components) + "\"/>\n";
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

void writeVtp(const VtkPolyData& data, const std::filesystem::path& path) {
  AppendedData appended;
  const std::string head = documentFor(path, [&] {
    checkArrays(data.pointData, data.points.size(), "point");
    checkArrays(data.cellData, data.cellCount(), "cell");
    return polyDataDocument(data, appended);
  });
  writeDocument(head, appended, path);
}

void writeVtu(const VtkVoxelGrid& grid, const std::filesystem::path& path) {
  AppendedData appended;
  const std::string head = documentFor(path, [&] {
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
