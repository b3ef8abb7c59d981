#include "delta/io/mesh_io.h"

#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <new>
#include <string>
#include <string_view>
#include <system_error>
#include <unordered_set>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/mat3.h"
#include "delta/io/atomic_file.h"
#include "delta/io/regular_file.h"
#include "delta/io/vtk.h"
#include "delta/mesh/coordinate_range.h"

#include "detail/isolated_import.h"
#include "detail/mesh_readers.h"
#include "detail/text_scan.h"
#include "detail/vertex_join.h"

namespace delta::io {
namespace {

namespace fs = std::filesystem;

/// The reason carried by the exception in flight; call only inside a catch block.
std::string currentExceptionReason() {
  try {
    throw;
  } catch (const std::bad_alloc&) {
    return "out of memory";
  } catch (const std::exception& error) {
    return error.what();
  } catch (...) {
    return "unknown error";
  }
}

std::string lowerCaseExtension(const fs::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return extension;
}

std::string describe(double x, double y, double z) {
  return toString(Vec3{x, y, z});
}

// ----- Δ's own readers -----

/// What assimp's child process may use (detail::IsolationLimits): 4 GiB of address space
/// beyond the caller's, plus 64 bytes a byte of the file (assimp's scene of a compact binary
/// format takes tens of times its size); a minute of processor time; two minutes in all.
constexpr std::uint64_t kAssimpAddressSpaceBytes = std::uint64_t{4} << 30;
constexpr std::uint64_t kAssimpAddressSpacePerFileByte = 64;
constexpr unsigned kAssimpCpuSeconds = 60;
constexpr unsigned kAssimpWallSeconds = 120;

/// Bytes read first to recognise the format: more than any signature needs (`solid` ... `facet`
/// after a long name, an OFF keyword after a block of comments, the binary STL header).
constexpr std::uintmax_t kHeadBytes = 4096;

detail::TriangleSoup readOwnFormat(detail::MeshFormat format, const RegularFile& file,
                                   std::string_view head) {
  // From the head alone, so that a sparse file of gigabytes named .ply is not read whole to say
  // that it does not start with "ply".
  detail::requireFormatStart(format, head, file.size());
  const std::string bytes = file.readAll();
  switch (format) {
    case detail::MeshFormat::off:
      return detail::readOff(bytes);
    case detail::MeshFormat::ply:
      return detail::readPly(bytes);
    case detail::MeshFormat::obj:
      return detail::readObj(bytes);
    case detail::MeshFormat::stl:
      return detail::readStl(bytes);
    case detail::MeshFormat::other:
      break;
  }
  throw Error("no reader of Δ's own for this format");
}

// ----- assimp's scene -----

/// Primitives of a scene as its importer delivered it.
struct RawPrimitives {
  std::size_t polygons = 0;  ///< faces with 3 or more corners
  std::size_t points = 0;    ///< one-corner faces, and the vertices of meshes without faces
  std::size_t lines = 0;     ///< two-corner faces
};

void checkRawFace(const aiFace& face, const aiMesh& mesh, unsigned meshIndex, unsigned faceIndex) {
  const auto name = [&] {
    return "mesh " + std::to_string(meshIndex) + " face " + std::to_string(faceIndex);
  };
  if (face.mNumIndices == 0 || face.mIndices == nullptr) throw Error(name() + " has no vertices");
  for (unsigned i = 0; i < face.mNumIndices; ++i)
    if (face.mIndices[i] >= mesh.mNumVertices)
      throw Error(name() + " refers to vertex " + std::to_string(face.mIndices[i]) + " of " +
                  std::to_string(mesh.mNumVertices));
}

/// Checks the arrays and indices an importer produced, which assimp leaves unchecked unless
/// asked (and aiProcess_ValidateDataStructure also rejects legitimate files, such as an STL with
/// one empty solid), so that the post-processing steps and the merge read only valid memory.
RawPrimitives checkRawScene(const aiScene& scene) {
  if (scene.mNumMeshes > 0 && scene.mMeshes == nullptr)
    throw Error("the scene's meshes are missing");
  RawPrimitives primitives;
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh* mesh = scene.mMeshes[m];
    if (mesh == nullptr || (mesh->mNumVertices > 0 && mesh->mVertices == nullptr) ||
        (mesh->mNumFaces > 0 && mesh->mFaces == nullptr))
      throw Error("mesh " + std::to_string(m) + " is incomplete");
    if (mesh->mNumFaces == 0) primitives.points += mesh->mNumVertices;  // a point cloud
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      checkRawFace(face, *mesh, m, f);
      if (face.mNumIndices == 1) ++primitives.points;
      if (face.mNumIndices == 2) ++primitives.lines;
      if (face.mNumIndices >= 3) ++primitives.polygons;
    }
  }
  return primitives;
}

/// Reads the file, checks what the importer made and triangulates it. The scene belongs to
/// `importer`.
const aiScene& importScene(Assimp::Importer& importer, const fs::path& path) {
  // Animation formats (MD5, BVH) would otherwise invent a mesh for a skeleton.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_NO_SKELETON_MESHES, true);
  const auto failed = [&importer] {
    const std::string reason = importer.GetErrorString();
    return Error(reason.empty() ? "assimp could not read it" : reason);
  };
  const aiScene* raw = importer.ReadFile(path.string(), 0);
  if (raw == nullptr) throw failed();
  const RawPrimitives primitives = checkRawScene(*raw);
  if (primitives.polygons == 0)
    throw Error("the file has no triangles, only " + std::to_string(primitives.points) +
                " points and " + std::to_string(primitives.lines) + " lines");
  // Not aiProcess_SortByPType: it rejects a scene with an empty mesh (an STL with an empty
  // solid), and the merge sorts primitives face by face anyway.
  const aiScene* scene = importer.ApplyPostProcessing(aiProcess_Triangulate);
  if (scene == nullptr) throw failed();
  return *scene;
}

/// p ↦ linear · p + offset: a node's transform accumulated from the root, in double precision.
struct Placement {
  Mat3 linear = Mat3::identity();
  Vec3 offset;

  Vec3 apply(const aiVector3D& p) const { return linear * Vec3{p.x, p.y, p.z} + offset; }

  /// This placement after the child node's transform `local` (row-major, translation in column 4).
  Placement then(const aiMatrix4x4& local, const aiNode& node) const {
    if (local.d1 != 0 || local.d2 != 0 || local.d3 != 0 || local.d4 != 1)
      throw Error("node '" + std::string(node.mName.C_Str()) + "' has a projective transform");
    const Mat3 m = Mat3::fromRows({local.a1, local.a2, local.a3}, {local.b1, local.b2, local.b3},
                                  {local.c1, local.c2, local.c3});
    return {linear * m, linear * Vec3{local.a4, local.b4, local.c4} + offset};
  }
};

constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
constexpr std::uint32_t kUsed = 0;

using detail::TriangleSoup;

/// Appends the vertices of `mesh` that `soupIndex` marks as used, in the mesh's order, placed,
/// and records where each went.
void addUsedVertices(const aiMesh& mesh, unsigned meshIndex, const Placement& placement,
                     std::vector<std::uint32_t>& soupIndex, TriangleSoup& soup) {
  const auto name = [meshIndex](unsigned v) {
    return "mesh " + std::to_string(meshIndex) + " vertex " + std::to_string(v);
  };
  for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
    if (soupIndex[v] == kUnused) continue;
    const aiVector3D& raw = mesh.mVertices[v];
    const Vec3 placed = placement.apply(raw);
    if (!std::isfinite(raw.x) || !std::isfinite(raw.y) || !std::isfinite(raw.z))
      throw Error(name(v) +
                  " has a coordinate that is not finite: " + describe(raw.x, raw.y, raw.z));
    if (!isFinite(placed))
      throw Error(name(v) + " " + describe(raw.x, raw.y, raw.z) +
                  " is moved by its node transform to " + describe(placed.x, placed.y, placed.z) +
                  ", which is not finite");
    if (soup.positions.size() == kUnused) throw Error("more than 2^32 - 1 vertices before joining");
    soupIndex[v] = static_cast<std::uint32_t>(soup.positions.size());
    soup.positions.push_back(placed);
  }
}

/// Adds one placement of a mesh: its triangles with the vertices they use (in the mesh's vertex
/// order), and the count of its points and lines. Vertices that no triangle uses are dropped.
void addMeshInstance(const aiMesh& mesh, unsigned meshIndex, const Placement& placement,
                     TriangleSoup& soup) {
  LoadStatistics& statistics = soup.statistics;
  if (mesh.mNumFaces == 0) statistics.pointsSkipped += mesh.mNumVertices;  // a point cloud
  std::vector<std::uint32_t> soupIndex(mesh.mNumVertices, kUnused);
  std::size_t triangles = 0;
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices == 1) ++statistics.pointsSkipped;
    if (face.mNumIndices == 2) ++statistics.linesSkipped;
    if (face.mNumIndices > 3) throw Error("assimp left a polygon untriangulated");
    if (face.mNumIndices != 3) continue;
    for (unsigned corner = 0; corner < 3; ++corner)
      soupIndex[face.mIndices[corner]] = kUsed;  // checkRawScene checked the range
    ++triangles;
  }
  if (triangles == 0) return;
  const std::size_t verticesBefore = soup.positions.size();
  addUsedVertices(mesh, meshIndex, placement, soupIndex, soup);
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices == 3)
      soup.triangles.push_back(
          {soupIndex[face.mIndices[0]], soupIndex[face.mIndices[1]], soupIndex[face.mIndices[2]]});
  }
  ++statistics.meshes;
  statistics.sourceVertices += soup.positions.size() - verticesBefore;
}

void addNodeMeshes(const aiScene& scene, const aiNode& node, const Placement& placement,
                   TriangleSoup& soup) {
  if (node.mNumMeshes > 0 && node.mMeshes == nullptr)
    throw Error("node '" + std::string(node.mName.C_Str()) + "' lost its mesh list");
  for (unsigned i = 0; i < node.mNumMeshes; ++i) {
    const unsigned meshIndex = node.mMeshes[i];
    if (meshIndex >= scene.mNumMeshes)
      throw Error("node '" + std::string(node.mName.C_Str()) + "' refers to mesh " +
                  std::to_string(meshIndex) + " of " + std::to_string(scene.mNumMeshes));
    addMeshInstance(*scene.mMeshes[meshIndex], meshIndex, placement, soup);
  }
}

/// Walks the node tree depth first, children in order, so triangles come mesh after mesh in the
/// file's order; a mesh placed by several nodes is added once per node.
TriangleSoup mergeScene(const aiScene& scene) {
  if (scene.mRootNode == nullptr) throw Error("the scene has no root node");
  TriangleSoup soup;
  soup.statistics.precision = CoordinatePrecision::single;
  std::vector<std::pair<const aiNode*, Placement>> pending{{scene.mRootNode, Placement{}}};
  std::unordered_set<const aiNode*> visited;
  while (!pending.empty()) {
    const auto [node, parent] = pending.back();
    pending.pop_back();
    if (!visited.insert(node).second)
      throw Error("node '" + std::string(node->mName.C_Str()) + "' appears twice in the scene");
    const Placement placement = parent.then(node->mTransformation, *node);
    addNodeMeshes(scene, *node, placement, soup);
    if (node->mNumChildren > 0 && node->mChildren == nullptr)
      throw Error("node '" + std::string(node->mName.C_Str()) + "' lost its children");
    for (unsigned c = node->mNumChildren; c-- > 0;) {  // reversed: the stack pops them in order
      if (node->mChildren[c] == nullptr) throw Error("the scene has a missing node");
      pending.emplace_back(node->mChildren[c], placement);
    }
  }
  return soup;
}

LoadedMesh joinVertices(TriangleSoup soup) {
  if (soup.triangles.empty())
    throw Error("the file has no triangles, only " + std::to_string(soup.statistics.pointsSkipped) +
                " points and " + std::to_string(soup.statistics.linesSkipped) + " lines");
  detail::JoinedVertices joined = detail::joinIdenticalVertices(soup.positions);
  for (TriangleIndices& triangle : soup.triangles)
    for (std::uint32_t& index : triangle)
      index = joined.newIndex[index];
  return {Mesh(std::move(joined.vertices), std::move(soup.triangles)), soup.statistics};
}

// ----- Export -----

/// The assimp exporter for the extension of `path`.
const char* exportFormat(const fs::path& path) {
  const std::string extension = lowerCaseExtension(path);
  if (extension == ".stl") return "stlb";
  if (extension == ".ply") return "plyb";
  throw Error("unknown extension '" + path.extension().string() +
              "': Δ writes .stl (binary), .ply (binary), .obj and .vtp");
}

aiVector3D toSinglePrecision(const Vec3& p, std::size_t index) {
  constexpr double kLargest = std::numeric_limits<float>::max();
  if (std::abs(p.x) > kLargest || std::abs(p.y) > kLargest || std::abs(p.z) > kLargest)
    throw Error("vertex " + std::to_string(index) + " " + describe(p.x, p.y, p.z) +
                " is beyond single precision, which the file stores");
  return {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)};
}

/// One mesh under the root node, with one default material (exporters expect one). Everything is
/// allocated with new / new[] and linked at once, so aiScene's destructor frees it, as it frees
/// an imported scene, even if an allocation fails half way.
void fillScene(aiScene& scene, const Mesh& mesh) {
  if (mesh.triangleCount() > std::numeric_limits<unsigned>::max())
    throw Error("more triangles than assimp's 32-bit counts hold");
  scene.mRootNode = new aiNode("delta");
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mRootNode->mNumMeshes = 1;
  scene.mMaterials = new aiMaterial* [1] {};
  scene.mNumMaterials = 1;
  scene.mMaterials[0] = new aiMaterial();
  scene.mMeshes = new aiMesh* [1] {};
  scene.mNumMeshes = 1;
  scene.mMeshes[0] = new aiMesh();
  aiMesh& out = *scene.mMeshes[0];
  out.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  // Below single precision's normal range the file keeps fewer digits than float's own rounding
  // gives the mesh (a mesh of size 1e-100 would be written as one point at the origin).
  const double largest = magnitude(mesh.bounds());
  if (largest > 0.0 && largest < std::numeric_limits<float>::min())
    throw Error("the mesh's largest coordinate, " + delta::toString(largest) +
                ", is below single precision's normal range (" +
                delta::toString(double{std::numeric_limits<float>::min()}) +
                "), which the file stores: its vertices would round to zero; scale the mesh by a "
                "power of two first");
  out.mVertices = new aiVector3D[mesh.vertexCount()];
  out.mNumVertices = static_cast<unsigned>(mesh.vertexCount());
  for (std::size_t v = 0; v < mesh.vertexCount(); ++v)
    out.mVertices[v] = toSinglePrecision(mesh.vertices()[v], v);
  out.mFaces = new aiFace[mesh.triangleCount()];
  out.mNumFaces = static_cast<unsigned>(mesh.triangleCount());
  for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
    const TriangleIndices& triangle = mesh.triangles()[t];
    out.mFaces[t].mIndices = new unsigned[3]{triangle[0], triangle[1], triangle[2]};
    out.mFaces[t].mNumIndices = 3;
  }
}

}  // namespace

const char* toString(CoordinatePrecision precision) noexcept {
  return precision == CoordinatePrecision::exact ? "exact" : "single";
}

LoadedMesh loadWithStatistics(const fs::path& path) {
  try {
    const RegularFile file(path);
    if (file.size() == 0) throw Error("file is empty");
    const std::string head = file.read(0, kHeadBytes);
    const std::string extension = lowerCaseExtension(path);
    const bool ownExtension =
        extension == ".off" || extension == ".ply" || extension == ".obj" || extension == ".stl";
    // An importer only where it is asked (one per call: importers are not shareable between
    // threads): making one makes all of assimp's readers.
    const bool assimpReadsExtension =
        ownExtension || Assimp::Importer().IsExtensionSupported(extension);
    const detail::MeshFormat format =
        detail::detectMeshFormat(head, file.size(), extension, assimpReadsExtension);
    if (format != detail::MeshFormat::other) return joinVertices(readOwnFormat(format, file, head));
    // No mesh format starts with 4 KiB of zeros; assimp would read such a file whole (a sparse
    // file of gigabytes) before saying that it knows no format for it.
    if (head.find_first_not_of('\0') == std::string::npos)
      throw Error("its first " + std::to_string(head.size()) +
                  " bytes are all zero: this is no mesh file");
    // assimp's readers crash, abort or loop on some damaged files (mutated .x, .md5mesh, .mdl,
    // .ase, .3mf, .cob files): they run in a child process, so that this process survives.
    const detail::IsolationLimits limits{
        kAssimpAddressSpaceBytes + kAssimpAddressSpacePerFileByte * file.size(), kAssimpCpuSeconds,
        kAssimpWallSeconds};
    return joinVertices(detail::runIsolated(
        [&path] {
          Assimp::Importer isolated;
          return mergeScene(importScene(isolated, path));
        },
        limits));
  } catch (...) {
    throw Error("cannot load '" + printable(path.string(), 4096) +
                "': " + currentExceptionReason());
  }
}

Mesh load(const fs::path& path) {
  LoadedMesh loaded = loadWithStatistics(path);
  return std::move(loaded.mesh);
}

/// An OBJ file of the mesh, each coordinate in the shortest decimal that reads back to the same
/// double (std::to_chars): loading it again gives the mesh's coordinates exactly. (assimp's OBJ
/// exporter wrote nine significant digits: 0.8183823522853823 came back as 0.818382323.)
std::string objText(const Mesh& mesh) {
  std::string text = "# delta: vertices, then triangles (1-based)\n";
  char digits[32];
  const auto append = [&text, &digits](double value) {
    const std::to_chars_result result = std::to_chars(digits, digits + sizeof digits, value);
    text.append(digits, result.ptr);
  };
  for (const Vec3& v : mesh.vertices()) {
    text += "v ";
    append(v.x);
    text += ' ';
    append(v.y);
    text += ' ';
    append(v.z);
    text += '\n';
  }
  for (const TriangleIndices& t : mesh.triangles()) {
    text += 'f';
    for (const std::uint32_t corner : t) {
      text += ' ';
      text += std::to_string(std::uint64_t{corner} + 1);
    }
    text += '\n';
  }
  return text;
}

void save(const Mesh& mesh, const fs::path& path) {
  if (lowerCaseExtension(path) == ".obj") {
    writeFileAtomically(path, objText(mesh));
    return;
  }
  if (lowerCaseExtension(path) == ".vtp") {  // VTK, for ParaView: every coordinate in double
    try {
      writeVtp(VtkPolyData::fromMesh(mesh), path);
    } catch (const Error& error) {
      throw Error("cannot save '" + path.string() + "': " + error.what());
    }
    return;
  }
  // Exported to memory and written by Δ, whole or not at all (AtomicFile, whose errors name the
  // path): assimp's own file writing does not report a failed write such as a full disk.
  Assimp::Exporter exporter;
  const aiExportDataBlob* blob = nullptr;
  try {
    const char* format = exportFormat(path);
    aiScene scene;
    fillScene(scene, mesh);
    blob = exporter.ExportToBlob(&scene, format);
    if (!blob) throw Error(exporter.GetErrorString());
    if (blob->next) throw Error("the exporter made more than one file");
  } catch (...) {
    throw Error("cannot save '" + path.string() + "': " + currentExceptionReason());
  }
  writeFileAtomically(path, std::string_view(static_cast<const char*>(blob->data), blob->size));
}

}  // namespace delta::io
