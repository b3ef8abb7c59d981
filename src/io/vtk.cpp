#include "delta/io/vtk.h"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "delta/core/error.h"
#include "delta/core/format.h"

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

/// Connectivity and offsets of the vertex cells or the triangles.
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

Cells triangleCells(const std::vector<TriangleIndices>& triangles, std::size_t points) {
  Cells cells;
  for (const TriangleIndices& triangle : triangles) {
    for (std::uint32_t index : triangle) {
      if (index >= points)
        throw Error("triangle refers to point " + std::to_string(index) + " of " +
                    std::to_string(points));
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

std::string cellSection(const char* tag, const Cells& cells, AppendedData& appended) {
  return std::string("<") + tag + ">\n" +
         appended.add(cells.connectivity, "Int64", "connectivity", 1) +
         appended.add(cells.offsets, "Int64", "offsets", 1) + "</" + tag + ">\n";
}

std::string document(const VtkPolyData& data, AppendedData& appended) {
  const Cells verts = vertexCells(data.pointsAsVertices ? data.points.size() : 0);
  const Cells polys = triangleCells(data.triangles, data.points.size());
  std::vector<double> coordinates;
  coordinates.reserve(3 * data.points.size());
  for (const Vec3& p : data.points)
    coordinates.insert(coordinates.end(), {p.x, p.y, p.z});

  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
         "header_type=\"UInt64\">\n<PolyData>\n"
      << "<Piece NumberOfPoints=\"" << data.points.size() << "\" NumberOfVerts=\""
      << verts.offsets.size() << "\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\""
      << polys.offsets.size() << "\">\n"
      << dataSection("PointData", data.pointData, appended)
      << dataSection("CellData", data.cellData, appended) << "<Points>\n"
      << appended.add(coordinates, "Float64", "Points", 3) << "</Points>\n"
      << cellSection("Verts", verts, appended) << cellSection("Polys", polys, appended)
      << "</Piece>\n</PolyData>\n<AppendedData encoding=\"raw\">\n_";
  return xml.str();
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
  try {
    checkArrays(data.pointData, data.points.size(), "point");
    checkArrays(data.cellData, data.cellCount(), "cell");
    AppendedData appended;
    const std::string head = document(data, appended);
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    if (!file) throw Error("cannot open it for writing");
    file << head;
    file.write(appended.bytes().data(), static_cast<std::streamsize>(appended.bytes().size()));
    file << "\n</AppendedData>\n</VTKFile>\n";
    if (!file.flush()) {
      file.close();
      std::error_code ignored;
      std::filesystem::remove(path, ignored);  // no partial file
      throw Error("writing failed");
    }
  } catch (const Error& error) {
    throw Error("cannot write '" + path.string() + "': " + error.what());
  }
}

void writePvd(std::span<const VtkSeriesEntry> entries, const std::filesystem::path& path) {
  try {
    std::string xml =
        "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"1.0\" "
        "byte_order=\"LittleEndian\">\n<Collection>\n";
    for (const VtkSeriesEntry& entry : entries) {
      if (!std::isfinite(entry.time))
        throw Error("time " + toString(entry.time) + " of '" + entry.file.string() +
                    "' is not finite");
      char time[32];
      std::snprintf(time, sizeof time, "%.17g", entry.time);
      xml += std::string("<DataSet timestep=\"") + time + "\" group=\"\" part=\"0\" file=\"" +
             escaped(entry.file.generic_string()) + "\"/>\n";
    }
    xml += "</Collection>\n</VTKFile>\n";
    std::ofstream file(path, std::ios::binary | std::ios::trunc);
    if (!file) throw Error("cannot open it for writing");
    file << xml;
    if (!file.flush()) throw Error("writing failed");
  } catch (const Error& error) {
    throw Error("cannot write '" + path.string() + "': " + error.what());
  }
}

}  // namespace delta::io
