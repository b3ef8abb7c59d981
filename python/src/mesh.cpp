// delta.Error, Quaternion, RigidTransform, Mesh, the primitives, load and save.
#include "delta/mesh/mesh.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/memory.h"
#include "delta/core/rotation.h"
#include "delta/io/mesh_io.h"
#include "delta/mesh/bounding_sphere.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/measures.h"
#include "delta/mesh/primitives.h"
#include "delta/mesh/topology.h"

#include "arrays.h"
#include "bindings.h"
#include "handles.h"
#include "transforms.h"

namespace delta::python {
namespace {

using namespace pybind11::literals;

/// Applies `map` to every point of a (…, 3) array, into a new float64 array of the same shape.
/// delta::Error names the first point that is not finite, or that `map` sends out of the range
/// of doubles (a result is never ±∞ or NaN).
template <typename Map>
py::array mapPoints(const ArrayLike& points, const Map& map) {
  const DoubleArray input = pointArray(points, "points", false);
  DoubleArray output(std::vector<py::ssize_t>(input.shape(), input.shape() + input.ndim()));
  const std::span<const Vec3> from = asVec3(input);
  auto* to = reinterpret_cast<Vec3*>(output.mutable_data());
  for (std::size_t i = 0; i < from.size(); ++i) {
    if (!isFinite(from[i]))
      throw Error("points: point " + std::to_string(i) + " " + toString(from[i]) +
                  " has a non-finite coordinate");
    to[i] = map(from[i]);
    if (!isFinite(to[i]))
      throw Error("points: point " + std::to_string(i) + " " + toString(from[i]) +
                  " moves out of the range of doubles, to " + toString(to[i]));
  }
  return output;
}

/// (2, 3): the lower corner, then the upper.
py::array boxArray(const Aabb& box) {
  return vec3Array(std::vector<Vec3>{box.lower, box.upper});
}

std::string repr(const Quaternion& q) {
  return "Quaternion(w=" + toString(q.w) + ", x=" + toString(q.x) + ", y=" + toString(q.y) +
         ", z=" + toString(q.z) + ")";
}

std::string repr(const Vec3& v) {
  return "(" + toString(v.x) + ", " + toString(v.y) + ", " + toString(v.z) + ")";
}

/// The 4×4 homogeneous matrix [R t; 0 1].
py::array homogeneous(const RigidTransform& motion) {
  py::array_t<double> matrix({py::ssize_t{4}, py::ssize_t{4}});
  auto m = matrix.mutable_unchecked<2>();
  const Mat3 r = motion.rotation.matrix();
  for (py::ssize_t row = 0; row < 4; ++row)
    for (py::ssize_t column = 0; column < 4; ++column)
      m(row, column) = row == 3      ? (column == 3 ? 1.0 : 0.0)
                       : column == 3 ? motion.translation[static_cast<std::size_t>(row)]
                                     : r(static_cast<int>(row), static_cast<int>(column));
  return matrix;
}

/// The vertex indices of an (m, 3) integer array, each checked to fit a uint32 (Mesh checks
/// that it names a vertex). TypeError for what is not integers (booleans, reals, strings),
/// delta::Error for another shape.
std::vector<TriangleIndices> triangleIndices(const ArrayLike& triangles) {
  const RealArray given = realArray(triangles.object);
  if (!given.problem.empty()) {
    std::string why = given.problem;
    const std::string reals = "must be real numbers";
    if (why.starts_with(reals)) why.replace(0, reals.size(), "must be integers");
    throw py::type_error("Mesh: triangles " + why);
  }
  const char kind = given.array.dtype().kind();
  if (kind != 'i' && kind != 'u')
    throw py::type_error("Mesh: triangles must be integers, not of dtype " +
                         py::str(given.array.dtype()).cast<std::string>());
  if (given.array.ndim() != 2 || given.array.shape(1) != 3)
    throw Error("Mesh: triangles must have shape (m, 3), not " + shapeOf(given.array));
  const auto count = static_cast<std::size_t>(given.array.shape(0));
  // NumPy's 64-bit copy and the 32-bit corners.
  requireMemory(static_cast<double>(count) * 3.0 * (8.0 + 4.0), "Mesh: triangles");
  std::vector<TriangleIndices> corners(count);
  const auto copy = [&]<typename Index>(Index) {
    using Indices = py::array_t<Index, py::array::c_style | py::array::forcecast>;
    const Indices indices = Indices::ensure(given.array);
    if (!indices) throw Error("Mesh: triangles: conversion to integers failed");
    const Index* index = indices.data();
    for (std::size_t t = 0; t < count; ++t)
      for (std::size_t k = 0; k < 3; ++k) {
        const Index value = index[3 * t + k];
        bool negative = false;
        if constexpr (std::is_signed_v<Index>) negative = value < 0;
        if (negative ||
            static_cast<std::uint64_t>(value) > std::numeric_limits<std::uint32_t>::max())
          throw Error("mesh: triangle " + std::to_string(t) + " refers to vertex " +
                      std::to_string(value) + ", which is not a vertex index");
        corners[t][k] = static_cast<std::uint32_t>(value);
      }
  };
  if (kind == 'u')
    copy(std::uint64_t{});
  else
    copy(std::int64_t{});
  return corners;
}

PyMesh makeMesh(const ArrayLike& vertices, const ArrayLike& triangles) {
  const DoubleArray coordinates = pointArray(vertices, "Mesh: vertices", true);
  std::vector<TriangleIndices> corners = triangleIndices(triangles);
  const std::span<const Vec3> points = asVec3(coordinates);
  std::vector<Vec3> copied(points.begin(), points.end());
  py::gil_scoped_release release;
  return PyMesh(Mesh(std::move(copied), std::move(corners)));
}

py::dict topologyDict(const Topology& topology) {
  return py::dict("edges"_a = topology.edges, "boundary_edges"_a = topology.boundaryEdges,
                  "non_manifold_edges"_a = topology.nonManifoldEdges,
                  "misoriented_edges"_a = topology.misorientedEdges, "closed"_a = topology.closed,
                  "manifold"_a = topology.manifold,
                  "consistently_oriented"_a = topology.consistentlyOriented);
}

/// The topology of the mesh, computed without the GIL.
Topology topologyOf(const PyMesh& mesh) {
  const std::shared_ptr<const Mesh> snapshot = mesh.snapshot();
  py::gil_scoped_release release;
  return analyzeTopology(*snapshot);
}

/// `motion`, or delta::Error naming `what` where its translation is not finite (two finite
/// motions whose translations add beyond a double): a Python object never holds one.
RigidTransform finiteMotion(const RigidTransform& motion, const char* what) {
  if (!isFinite(motion.translation))
    throw Error(std::string(what) + ": the translation " + toString(motion.translation) +
                " overflows a double");
  return motion;
}

void bindRotations(py::module_& module) {
  py::class_<Quaternion>(module, "Quaternion", R"(A rotation as a unit quaternion w + xi + yj + zk.

Quaternion() is the identity; Quaternion(w, x, y, z) normalises its components (delta.Error
when they are zero or not finite). Rotations compose with `*` (`a * b` applies b first) and are
renormalised after every product.)")
      .def(py::init<>(), "The identity rotation.")
      .def(py::init(&Quaternion::fromComponents), "w"_a, "x"_a, "y"_a, "z"_a,
           "The unit quaternion in the direction of (w, x, y, z) (delta.Error when zero or not "
           "finite).")
      .def_static("from_axis_angle", &Quaternion::fromAxisAngle, "axis"_a, "angle"_a,
                  "The rotation by `angle` radians about `axis` (3 numbers, not zero), "
                  "right-handed.")
      .def_static("from_matrix", &Quaternion::fromMatrix, "matrix"_a,
                  "The rotation of a 3x3 rotation matrix (orthonormal, determinant +1, to 1e-6; "
                  "delta.Error otherwise).")
      .def_readonly("w", &Quaternion::w, "The real part.")
      .def_readonly("x", &Quaternion::x, "The i component.")
      .def_readonly("y", &Quaternion::y, "The j component.")
      .def_readonly("z", &Quaternion::z, "The k component.")
      .def_property_readonly("matrix", &Quaternion::matrix,
                             "The 3x3 rotation matrix (float64 array, rows first).")
      .def(
          "rotate",
          [](const Quaternion& q, const ArrayLike& points) {
            return mapPoints(points, [&](const Vec3& p) { return q.rotate(p); });
          },
          "points"_a, "Rotates points, an array of shape (..., 3); returns a new float64 array.")
      .def("conjugate", &Quaternion::conjugate, "The inverse rotation.")
      .def(
          "to_array",
          [](const Quaternion& q) {
            py::array_t<double> wxyz(4);
            double* data = wxyz.mutable_data();
            data[0] = q.w, data[1] = q.x, data[2] = q.y, data[3] = q.z;
            return wxyz;
          },
          "(w, x, y, z) as a float64 array of shape (4,).")
      .def("__mul__", [](const Quaternion& a, const Quaternion& b) { return a * b; })
      .def("__repr__", [](const Quaternion& q) { return repr(q); })
      .def(py::pickle([](const Quaternion& q) { return py::make_tuple(q.w, q.x, q.y, q.z); },
                      [](const py::tuple& wxyz) {
                        if (wxyz.size() != 4)
                          throw Error("Quaternion: a pickled state is (w, x, y, z), not " +
                                      std::to_string(wxyz.size()) + " values");
                        const Quaternion q{wxyz[0].cast<double>(), wxyz[1].cast<double>(),
                                           wxyz[2].cast<double>(), wxyz[3].cast<double>()};
                        // A pickled unit quaternion comes back bit for bit (normalising it
                        // again would change its last bits); anything else is normalised and
                        // checked as Quaternion(w, x, y, z) is.
                        const double norm2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
                        if (std::abs(norm2 - 1.0) <= 8 * std::numeric_limits<double>::epsilon())
                          return q;
                        return Quaternion::fromComponents(q.w, q.x, q.y, q.z);
                      }));

  py::class_<RigidTransform>(module, "RigidTransform", R"(A rigid motion p -> R p + t.

RigidTransform(rotation=Quaternion(), translation=(0, 0, 0)). Compose with `*` (`a * b` applies b
first); `inverse()` undoes it. A QueryMesh's pose, and what QueryMesh.transform,
Mesh.transform and the immersed-boundary grid's moves take.)")
      .def(py::init([](const Quaternion& rotation, const Vec3& translation) {
             return RigidTransform{rotation, translation};
           }),
           py::arg_v("rotation", Quaternion{}, "Quaternion()"),
           py::arg_v("translation", Vec3{}, "(0, 0, 0)"),
           "p -> R p + t with R the rotation (a Quaternion) and t the translation (3 numbers).")
      .def_static("translation_by", &RigidTransform::translationBy, "offset"_a,
                  "The translation by `offset` (3 numbers).")
      .def_static("rotation_about", &RigidTransform::rotationAbout, "rotation"_a, "pivot"_a,
                  "The rotation about the line through `pivot` (not through the origin).")
      .def_static(
          "from_matrix",
          [](const ArrayLike& matrix) {
            return fromHomogeneous(matrix.object, "RigidTransform.from_matrix: the matrix");
          },
          "matrix"_a, "From a 4x4 homogeneous matrix [R t; 0 1] (R a rotation to 1e-6).")
      .def_readwrite("rotation", &RigidTransform::rotation, "The rotation R, a Quaternion.")
      .def_property(
          "translation", [](const RigidTransform& motion) { return motion.translation; },
          [](RigidTransform& motion, const Vec3& t) { motion.translation = t; },
          "The translation t, float64 array of shape (3,).")
      .def_property_readonly("matrix", &homogeneous,
                             "The 4x4 homogeneous matrix [R t; 0 1] (float64 array).")
      .def(
          "apply",
          [](const RigidTransform& motion, const ArrayLike& points) {
            return mapPoints(points, [&](const Vec3& p) { return motion.apply(p); });
          },
          "points"_a, "Moves points, an array of shape (..., 3); returns a new float64 array.")
      .def(
          "inverse",
          [](const RigidTransform& motion) {
            return finiteMotion(motion.inverse(), "RigidTransform.inverse()");
          },
          "The motion that undoes this one (delta.Error where its translation overflows).")
      .def(
          "__mul__",
          [](const RigidTransform& a, const RigidTransform& b) {
            return finiteMotion(a * b, "RigidTransform * RigidTransform");
          },
          "The composition: b first, then a (delta.Error where its translation overflows).")
      .def("__repr__", [](const RigidTransform& motion) {
        return "RigidTransform(rotation=" + repr(motion.rotation) +
               ", translation=" + repr(motion.translation) + ")";
      });
}

void bindMeshClass(py::module_& module) {
  py::class_<PyMesh>(module, "Mesh", R"(An indexed triangle mesh: vertices and index triples.

Mesh(vertices, triangles): vertices an array of shape (n, 3) of real numbers (float64, converted
if needed), triangles an array of shape (m, 3) of integers (0-based vertex indices; their order
gives the orientation). Validated: at least one triangle, finite coordinates, indices in range;
delta.Error (a ValueError) names the element and value otherwise. The mesh owns a copy.

`vertices` and `triangles` are read-only NumPy views of the mesh's storage (no copy). A
transform writes new storage: a view taken before keeps showing the coordinates it was taken of.
Transforms return the mesh itself, so they chain: mesh.rotate((0, 0, 1), 0.5).translate((1, 0, 0)).

Threading: the GIL serialises methods; queries work on a snapshot without the GIL.)")
      .def(py::init(&makeMesh), "vertices"_a, "triangles"_a,
           "A mesh of these vertices (n, 3) and triangles (m, 3), validated and copied.")
      .def_property_readonly(
          "vertices",
          [](const PyMesh& mesh) {
            const std::shared_ptr<const Mesh> snapshot = mesh.snapshot();
            const auto count = static_cast<py::ssize_t>(snapshot->vertexCount());
            const void* data = snapshot->vertices().data();
            return view(snapshot, data, py::dtype::of<double>(), {count, 3},
                        {py::ssize_t{sizeof(Vec3)}, py::ssize_t{sizeof(double)}});
          },
          "Read-only float64 view of shape (n, 3) onto the mesh's vertices.")
      .def_property_readonly(
          "triangles",
          [](const PyMesh& mesh) {
            static_assert(sizeof(TriangleIndices) == 3 * sizeof(std::uint32_t));
            const std::shared_ptr<const Mesh> snapshot = mesh.snapshot();
            const auto count = static_cast<py::ssize_t>(snapshot->triangleCount());
            const void* data = snapshot->triangles().data();
            return view(snapshot, data, py::dtype::of<std::uint32_t>(), {count, 3},
                        {py::ssize_t{sizeof(TriangleIndices)}, py::ssize_t{sizeof(std::uint32_t)}});
          },
          "Read-only uint32 view of shape (m, 3) onto the mesh's vertex indices.")
      .def_property_readonly(
          "vertex_count", [](const PyMesh& mesh) { return mesh.mesh().vertexCount(); },
          "The number of vertices, n.")
      .def_property_readonly(
          "triangle_count", [](const PyMesh& mesh) { return mesh.mesh().triangleCount(); },
          "The number of triangles, m.")
      .def_property_readonly(
          "bounds", [](const PyMesh& mesh) { return boxArray(mesh.mesh().bounds()); },
          "The axis-aligned bounding box, shape (2, 3): lower corner, upper corner.")
      .def_property_readonly(
          "memory_bytes", [](const PyMesh& mesh) { return mesh.mesh().memoryBytes(); },
          "Bytes the mesh holds on the heap.")
      .def_property_readonly(
          "area", [](const PyMesh& mesh) { return surfaceArea(mesh.mesh()); },
          "The surface area (sum of the triangles' areas).")
      .def_property_readonly(
          "volume",
          [](const PyMesh& mesh) -> py::object {
            const Topology topology = topologyOf(mesh);
            if (!topology.closed || !topology.consistentlyOriented) return py::none();
            return py::float_(signedVolume(mesh.mesh()));
          },
          "The enclosed volume (negative when inside-out), or None when the mesh is not closed "
          "and consistently oriented.")
      .def_property_readonly(
          "closed", [](const PyMesh& mesh) { return topologyOf(mesh).closed; },
          "Every edge has exactly two triangles (as `delta info` reports it).")
      .def_property_readonly(
          "consistently_oriented",
          [](const PyMesh& mesh) { return topologyOf(mesh).consistentlyOriented; },
          "Manifold, and neighbours traverse each shared edge oppositely.")
      .def(
          "topology", [](const PyMesh& mesh) { return topologyDict(topologyOf(mesh)); },
          "Edge analysis as a dict: edges, boundary_edges, non_manifold_edges, "
          "misoriented_edges, closed, manifold, consistently_oriented.")
      .def_property_readonly(
          "degenerate_triangle_count",
          [](const PyMesh& mesh) { return degenerateTriangleCount(mesh.mesh()); },
          "Triangles of zero area relative to their size.")
      .def(
          "edge_lengths",
          [](const PyMesh& mesh) {
            const EdgeLengths lengths = edgeLengths(mesh.mesh());
            return py::dict("min"_a = lengths.min, "mean"_a = lengths.mean, "max"_a = lengths.max);
          },
          "Lengths of the distinct edges, a dict with min, mean and max: the mesh size h.")
      .def(
          "bounding_sphere",
          [](const PyMesh& mesh) {
            const Sphere sphere = boundingSphere(mesh.mesh());
            return py::make_tuple(sphere.center, sphere.radius);
          },
          "A tight bounding sphere: (center, radius).")
      .def(
          "mass_properties",
          [](const PyMesh& mesh, double density) {
            const MassProperties mass = massProperties(mesh.mesh(), density);
            return py::dict("volume"_a = mass.volume, "mass"_a = mass.mass,
                            "centroid"_a = mass.centroid, "inertia"_a = mass.inertia);
          },
          "density"_a = 1.0,
          "Volume, mass, centroid (3,) and inertia tensor (3, 3) about the centroid of the solid "
          "a closed, outward-oriented mesh bounds, as a dict (delta.Error otherwise).")
      .def(
          "translate",
          [](PyMesh& mesh, const Vec3& offset) -> PyMesh& {
            mesh.change([&](Mesh& m) { m.translate(offset); });
            return mesh;
          },
          "offset"_a, "Moves every vertex by `offset`. Returns the mesh.")
      .def(
          "scale",
          [](PyMesh& mesh, double factor, const Vec3& pivot) -> PyMesh& {
            mesh.change([&](Mesh& m) { m.scale(factor, pivot); });
            return mesh;
          },
          "factor"_a, py::arg_v("pivot", Vec3{}, "(0, 0, 0)"),
          "Uniform scale by `factor` > 0 about `pivot`. Returns the mesh.")
      .def(
          "stretch",
          [](PyMesh& mesh, const Vec3& factors, const Vec3& pivot) -> PyMesh& {
            mesh.change([&](Mesh& m) { m.stretch(factors, pivot); });
            return mesh;
          },
          "factors"_a, py::arg_v("pivot", Vec3{}, "(0, 0, 0)"),
          "Per-axis scale by `factors` (each > 0) about `pivot`. Returns the mesh.")
      .def(
          "rotate",
          [](PyMesh& mesh, const Vec3& axis, double angle, const Vec3& pivot) -> PyMesh& {
            mesh.change([&](Mesh& m) { m.rotate(axis, angle, pivot); });
            return mesh;
          },
          "axis"_a, "angle"_a, py::arg_v("pivot", Vec3{}, "(0, 0, 0)"),
          "Rotation by `angle` radians about the line through `pivot` along `axis`. Returns the "
          "mesh.")
      .def(
          "rotate",
          [](PyMesh& mesh, const Quaternion& rotation, const Vec3& pivot) -> PyMesh& {
            mesh.change([&](Mesh& m) { m.rotate(rotation, pivot); });
            return mesh;
          },
          "rotation"_a, py::arg_v("pivot", Vec3{}, "(0, 0, 0)"),
          "Rotation by a Quaternion about `pivot`. Returns the mesh.")
      .def(
          "rotate",
          [](PyMesh& mesh, const Mat3& rotation, const Vec3& pivot) -> PyMesh& {
            mesh.change([&](Mesh& m) { m.rotate(rotation, pivot); });
            return mesh;
          },
          "matrix"_a, py::arg_v("pivot", Vec3{}, "(0, 0, 0)"),
          "Rotation by a 3x3 rotation matrix about `pivot` (delta.Error when it is not one, to "
          "1e-6). Returns the mesh.")
      .def(
          "transform",
          [](PyMesh& mesh, const Motion& motion) -> PyMesh& {
            mesh.change([&](Mesh& m) { m.transform(motion.value); });
            return mesh;
          },
          "motion"_a,
          "Applies p -> R p + t to every vertex (`motion`: a RigidTransform or a 4×4 matrix). "
          "Returns the mesh.")
      .def(
          "copy", [](const PyMesh& mesh) { return PyMesh(mesh.mesh()); }, "An independent copy.")
      .def("__copy__", [](const PyMesh& mesh) { return PyMesh(mesh.mesh()); })
      .def("__deepcopy__", [](const PyMesh& mesh, py::handle) { return PyMesh(mesh.mesh()); })
      .def("__repr__",
           [](const PyMesh& mesh) {
             return "<delta.Mesh: " + std::to_string(mesh.mesh().triangleCount()) + " triangles, " +
                    std::to_string(mesh.mesh().vertexCount()) + " vertices>";
           })
      .def(py::pickle(
          [](const PyMesh& mesh) {
            const py::object self = py::cast(mesh);
            return py::make_tuple(self.attr("vertices"), self.attr("triangles"));
          },
          [](const py::tuple& state) {
            if (state.size() != 2)
              throw Error("Mesh: a pickled state is (vertices, triangles), not " +
                          std::to_string(state.size()) + " values");
            return makeMesh({state[0]}, {state[1]});
          }));
}

void bindPrimitivesAndFiles(py::module_& module) {
  module.def(
      "icosphere",
      [](int subdivisions, double radius, const Vec3& center) {
        py::gil_scoped_release release;
        return PyMesh(primitives::icosphere(subdivisions, radius, center));
      },
      "subdivisions"_a = 2, "radius"_a = 1.0, py::arg_v("center", Vec3{}, "(0, 0, 0)"),
      "A sphere: the icosahedron subdivided `subdivisions` times (0-8; 20*4**n triangles), "
      "closed and outward-oriented.");
  module.def(
      "box",
      [](const Vec3& size, const Vec3& center) { return PyMesh(primitives::box(size, center)); },
      py::arg_v("size", Vec3{1.0, 1.0, 1.0}, "(1, 1, 1)"), py::arg_v("center", Vec3{}, "(0, 0, 0)"),
      "An axis-aligned box with the given edge lengths: 12 triangles, closed.");
  module.def(
      "cylinder",
      [](double radius, double height, int segments, const Vec3& center) {
        return PyMesh(primitives::cylinder(radius, height, segments, center));
      },
      "radius"_a = 1.0, "height"_a = 1.0, "segments"_a = 32,
      py::arg_v("center", Vec3{}, "(0, 0, 0)"),
      "A capped cylinder along z, `segments` (>= 3) around: 4*segments triangles, closed.");
  module.def(
      "quad",
      [](double sizeX, double sizeY, const Vec3& center) {
        return PyMesh(primitives::quad(sizeX, sizeY, center));
      },
      "size_x"_a = 1.0, "size_y"_a = 1.0, py::arg_v("center", Vec3{}, "(0, 0, 0)"),
      "A flat rectangle in the plane z = center[2], normal +z: two triangles, open.");
  module.def(
      "granulate",
      [](std::uint64_t seed, const Vec3& semiAxes, int points) {
        py::gil_scoped_release release;
        return PyMesh(primitives::granulate(seed, semiAxes, points));
      },
      "seed"_a = 1, py::arg_v("semi_axes", Vec3{1.0, 1.0, 1.0}, "(1, 1, 1)"), "points"_a = 42,
      "A random convex granulate (a DEM particle): the convex hull of `points` random points on "
      "the ellipsoid with these semi-axes; the same seed gives the same mesh (42 points: 80 "
      "triangles). builtin:granulate:SEED of the command line.");

  module.def(
      "load",
      [](const std::filesystem::path& path) {
        py::gil_scoped_release release;
        return PyMesh(io::load(path));
      },
      "path"_a,
      R"(Loads every triangle of a file in any format assimp reads (OFF, OBJ, STL, PLY, glTF, ...):
meshes merged, polygons triangulated, identical vertices joined; coordinates are the file's
numbers exactly for OFF, PLY, OBJ and STL (Delta's own readers), rounded to single precision
for the formats only assimp reads (load_with_statistics says which). delta.Error names the
path and the reason for a missing or malformed file.)");
  module.def(
      "load_with_statistics",
      [](const std::filesystem::path& path) {
        io::LoadedMesh loaded = [&] {
          py::gil_scoped_release release;
          return io::loadWithStatistics(path);
        }();
        const io::LoadStatistics& s = loaded.statistics;
        py::dict statistics("meshes"_a = s.meshes, "source_vertices"_a = s.sourceVertices,
                            "points_skipped"_a = s.pointsSkipped,
                            "lines_skipped"_a = s.linesSkipped,
                            "precision"_a = io::toString(s.precision));
        return py::make_tuple(PyMesh(std::move(loaded.mesh)), statistics);
      },
      "path"_a,
      "load(path) and what the import found beside the triangles: (mesh, dict with meshes, "
      "source_vertices, points_skipped, lines_skipped, precision: 'exact' where the vertices are "
      "the file's numbers (OFF, PLY, OBJ, STL), 'single' where assimp rounded them to single "
      "precision (glTF, 3DS, ...)).");
  module.def(
      "save",
      [](const PyMesh& mesh, const std::filesystem::path& path) {
        const std::shared_ptr<const Mesh> snapshot = mesh.snapshot();
        py::gil_scoped_release release;
        io::save(*snapshot, path);
      },
      "mesh"_a, "path"_a,
      "Writes the mesh as .stl, .ply (binary), .obj (text, every coordinate exactly) or .vtp "
      "(VTK, for ParaView; coordinates in double), by the extension. Loading an .stl, .ply or .obj "
      "again gives the same triangles in the same order, coordinates rounded to single precision "
      "(.stl, .ply) or exactly (.obj). The file is replaced whole or not at all.");
}

}  // namespace

void bindMesh(py::module_& module) {
  py::register_exception<Error>(module, "Error", PyExc_ValueError);
  module.attr("Error").attr("__doc__") =
      "Bad input met at a boundary of Delta (a mesh, a file, an argument): the message names "
      "what and where. A ValueError.";
  bindRotations(module);
  bindMeshClass(module);
  bindPrimitivesAndFiles(module);
}

}  // namespace delta::python
