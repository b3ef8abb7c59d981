// QueryMesh and the queries: contacts, point_contacts, distance, filter, minimum_distance,
// overlap. Every query prepares and computes without the GIL.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "delta/core/contact_point.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/kernels/triangle_batch.h"
#include "delta/query/contacts.h"
#include "delta/query/filter.h"
#include "delta/query/minimum_distance.h"
#include "delta/query/overlap.h"
#include "delta/query/part_nesting.h"
#include "delta/query/point_distance.h"
#include "delta/query/query_mesh.h"
#include "delta/query/self_intersections.h"

#include "arrays.h"
#include "bindings.h"
#include "handles.h"
#include "interrupt.h"
#include "records.h"
#include "transforms.h"

namespace delta::python {
namespace {

using namespace pybind11::literals;
namespace cd = contactdetection;

kernels::Solver solverNamed(const std::string& method) {
  const std::optional<kernels::Solver> solver = kernels::parseSolver(method);
  if (!solver) throw Error("method '" + method + "': use hybrid, penalty or bruteforce");
  return *solver;
}

py::array contactArray(std::vector<ContactPoint>&& contacts) {
  const auto count = static_cast<py::ssize_t>(contacts.size());
  return adopt(std::move(contacts), contactDtype(), {count});
}

/// A structured array with (at least) the fields of contact_dtype, in any layout, as Δ's contact
/// points (field by field: a sliced, reordered or user-built array works). Every field must hold
/// what contact_dtype holds: real numbers (finite) for x, normal, direction and distance (not
/// negative), integers in the uint32 range for the triangle ids, booleans for overlap; TypeError
/// for another kind, delta::Error naming the record and field for a value out of range.
std::vector<ContactPoint> contactsFrom(const ArrayLike& given) {
  const py::array records = py::array::ensure(given.object);
  if (!records || !records.dtype().has_fields() || records.ndim() != 1)
    throw py::type_error(
        "contacts must be a one-dimensional structured array of delta.contact_dtype");
  const std::size_t count = static_cast<std::size_t>(records.shape(0));
  const py::object fields = records.dtype().attr("fields");
  // The field, checked to be of `kinds`, as a C-contiguous array of T with `width` values a
  // record.
  const auto column = [&]<typename T>(const char* name, std::size_t width, const char* kinds, T) {
    if (!fields.contains(name))
      throw Error(std::string("contacts have no field '") + name + "' (delta.contact_dtype)");
    const py::array field = records[name];
    const py::dtype dtype = field.dtype();
    if (std::string(kinds).find(dtype.kind()) == std::string::npos ||
        (dtype.kind() == 'f' && dtype.itemsize() > 8))
      throw py::type_error(std::string("contacts: the field '") + name + "' must hold " +
                           (kinds[0] == 'b'   ? "booleans"
                            : kinds[0] == 'i' ? "integers"
                                              : "real numbers") +
                           ", not " +
                           py::str(static_cast<const py::handle&>(dtype)).cast<std::string>() +
                           " (delta.contact_dtype)");
    using Column = py::array_t<T, py::array::c_style | py::array::forcecast>;
    if constexpr (std::is_same_v<T, double>) requireExactIntegers(field, name);
    if constexpr (std::is_same_v<T, std::int64_t>) {
      if (dtype.kind() == 'u' && dtype.itemsize() == 8) {
        // Beyond int64: out of the uint32 range anyway.
        using Unsigned = py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>;
        const Unsigned values = Unsigned::ensure(field);
        for (py::ssize_t i = 0; i < values.size(); ++i)
          if (values.data()[i] > std::numeric_limits<std::uint32_t>::max())
            throw Error("contacts: record " + std::to_string(i) + " has '" + name + "' " +
                        std::to_string(values.data()[i]) + ", not a triangle id (uint32)");
      }
    }
    const Column values = Column::ensure(field);
    if (!values || static_cast<std::size_t>(values.size()) != width * count)
      throw Error(std::string("contacts: the field '") + name + "' must hold " +
                  std::to_string(width) + " number(s) a record (delta.contact_dtype)");
    return values;
  };
  const auto x = column("x", 3, "iuf", 0.0), normal = column("normal", 3, "iuf", 0.0),
             direction = column("direction", 3, "iuf", 0.0),
             distance = column("distance", 1, "iuf", 0.0);
  const auto first = column("triangle_a", 1, "iu", std::int64_t{}),
             second = column("triangle_b", 1, "iu", std::int64_t{});
  const auto overlap = column("overlap", 1, "b", false);
  // Records made before the penalty solver reported convergence have no such field.
  std::optional<py::array_t<bool, py::array::c_style | py::array::forcecast>> converged;
  if (fields.contains("converged")) converged = column("converged", 1, "b", false);
  std::vector<ContactPoint> contacts(count);
  const std::span<const Vec3> xs = asVec3(x), normals = asVec3(normal),
                              directions = asVec3(direction);
  const auto refuse = [](std::size_t i, const char* field, const std::string& value,
                         const char* wanted) {
    throw Error("contacts: record " + std::to_string(i) + " has '" + field + "' " + value +
                ", not " + wanted);
  };
  for (std::size_t i = 0; i < count; ++i) {
    if (!isFinite(xs[i])) refuse(i, "x", toString(xs[i]), "finite numbers");
    if (!isFinite(normals[i])) refuse(i, "normal", toString(normals[i]), "finite numbers");
    if (!isFinite(directions[i])) refuse(i, "direction", toString(directions[i]), "finite numbers");
    const double d = distance.data()[i];
    if (!(std::isfinite(d) && d >= 0.0))
      refuse(i, "distance", toString(d), "a finite distance >= 0");
    const std::int64_t a = first.data()[i], b = second.data()[i];
    constexpr std::int64_t kMaxId = std::numeric_limits<std::uint32_t>::max();
    if (a < 0 || a > kMaxId) refuse(i, "triangle_a", std::to_string(a), "a triangle id (uint32)");
    if (b < 0 || b > kMaxId) refuse(i, "triangle_b", std::to_string(b), "a triangle id (uint32)");
    ContactPoint& contact = contacts[i];
    contact.x = xs[i];
    contact.normal = normals[i];
    contact.direction = directions[i];
    contact.distance = d;
    contact.overlap = overlap.data()[i];
    if (converged) contact.converged = converged->data()[i];
    contact.first = static_cast<std::uint32_t>(a);
    contact.second = static_cast<std::uint32_t>(b);
  }
  return contacts;
}

/// `out`, checked: it can take the answers of a points query whose result has this shape, and
/// shares no memory with the points.
py::array checkedOutput(const py::array& out, const std::vector<py::ssize_t>& shape,
                        const DoubleArray& points) {
  if (!out.dtype().equal(distanceDtype()))
    throw py::type_error("out must have dtype delta.distance_dtype, not " +
                         py::str(static_cast<const py::handle&>(out.dtype())).cast<std::string>());
  bool same = out.ndim() == static_cast<py::ssize_t>(shape.size());
  for (std::size_t axis = 0; same && axis < shape.size(); ++axis)
    same = out.shape(static_cast<py::ssize_t>(axis)) == shape[axis];
  if (!same)
    throw Error("out must have the shape of points without their last axis, not " + shapeOf(out));
  if (!(out.flags() & py::array::c_style)) throw Error("out must be C-contiguous");
  if (!out.writeable()) throw Error("out must be writeable");
  if (overlaps(out, points))
    throw Error(
        "out shares memory with points: the answers would overwrite the points being "
        "asked about; pass a separate array");
  return out;
}

py::array distance(const Geometry& mesh, const ArrayLike& points, std::optional<double> epsilon,
                   Flag signedDistance, std::optional<py::object> out,
                   const std::optional<std::string>& sign) {
  const std::optional<cd::Sign> how = sign ? std::optional(signNamed(*sign)) : std::nullopt;
  const DoubleArray coordinates = pointArray(points, "points", false);
  const std::vector<py::ssize_t> shape(coordinates.shape(),
                                       coordinates.shape() + coordinates.ndim() - 1);
  std::optional<py::array> given;
  if (out) {
    if (!py::isinstance<py::array>(*out))
      throw py::type_error("out must be a NumPy array of delta.distance_dtype, not " +
                           py::str(py::type::handle_of(*out).attr("__name__")).cast<std::string>());
    given = checkedOutput(py::reinterpret_borrow<py::array>(*out), shape, coordinates);
  }
  const std::span<const Vec3> query = asVec3(coordinates);
  cd::PointQuery request;
  if (epsilon) request.epsilon = *epsilon;
  request.signedDistance = signedDistance.value || how.has_value();
  if (how) request.sign = *how;
  // Into a new array, or for `out` into a scratch one copied at the end: a query stopped by an
  // error or Ctrl-C leaves `out` as it was, never half-written.
  std::vector<cd::PointDistance> scratch;
  py::array answers = given ? *given : py::array(distanceDtype(), shape);
  {
    const SignalScope interruptible;
    py::gil_scoped_release release;
    if (given) {
      scratch.resize(query.size());
      cd::distances(mesh.prepare(), query, request, scratch);
      clearPadding(scratch);
    } else {
      const std::span<cd::PointDistance> records(
          static_cast<cd::PointDistance*>(answers.mutable_data()), query.size());
      cd::distances(mesh.prepare(), query, request, records);
      clearPadding(records);
    }
  }
  if (given && !scratch.empty())
    std::memcpy(answers.mutable_data(), scratch.data(), scratch.size() * sizeof(cd::PointDistance));
  return answers;
}

void bindQueryMesh(py::module_& module) {
  py::class_<QueryMesh>(module, "QueryMesh", R"(A mesh prepared for queries (O(n log n), once).

QueryMesh(mesh) flattens the triangles, builds a bounding-volume tree and, for a closed mesh, the
pseudonormals that sign distances. It is a snapshot: transforming the Mesh afterwards does not
move it. `transform(motion)` and `set_pose(pose)` move it rigidly in O(1) (nothing is rebuilt);
copies (`copy()`) share the prepared data and each has its own pose. Every query takes a
QueryMesh or a Mesh (prepared for that call); prepare once when querying repeatedly.

Threading: queries run without the GIL on a copy of the pose taken when they start; any number of
Python threads may query one QueryMesh at once.)")
      .def(py::init([](const PyMesh& mesh) {
             const std::shared_ptr<const Mesh> snapshot = mesh.snapshot();
             py::gil_scoped_release release;
             return QueryMesh(*snapshot);
           }),
           "mesh"_a, "Prepares `mesh` (a Mesh) for queries, without the GIL.")
      .def(
          "transform",
          [](QueryMesh& mesh, const Motion& motion) -> QueryMesh& {
            return mesh.transform(motion.value);
          },
          "motion"_a, py::return_value_policy::reference_internal,
          "Moves the mesh rigidly by `motion` (a RigidTransform or a 4×4 matrix): its pose becomes "
          "motion * pose. O(1). Returns the QueryMesh.")
      .def(
          "set_pose",
          [](QueryMesh& mesh, const Motion& pose) -> QueryMesh& {
            return mesh.setPose(pose.value);
          },
          "pose"_a, py::return_value_policy::reference_internal,
          "Puts the mesh at `pose` (a RigidTransform or a 4×4 matrix, from the frame it was "
          "prepared in). O(1). Returns the QueryMesh.")
      .def_property_readonly(
          "pose", [](const QueryMesh& mesh) { return mesh.pose(); },
          "Where the mesh is: a RigidTransform (a copy) from the frame it was prepared in.")
      .def_property_readonly("moved", &QueryMesh::moved,
                             "A pose has been set, by transform or set_pose (even the identity).")
      .def(py::pickle(
          // The mesh it was prepared from and its pose, bit for bit: unpickled, it is prepared
          // again (O(n log n)) and answers as the original does (for multiprocessing).
          [](const QueryMesh& mesh) {
            const Quaternion& q = mesh.pose().rotation;
            return py::make_tuple(py::cast(PyMesh(mesh.mesh())), mesh.moved(),
                                  py::make_tuple(q.w, q.x, q.y, q.z), mesh.pose().translation);
          },
          [](const py::tuple& state) {
            if (state.size() != 4)
              throw Error(
                  "QueryMesh: a pickled state is (mesh, moved, rotation, translation), "
                  "not " +
                  std::to_string(state.size()) + " values");
            const std::shared_ptr<const Mesh> snapshot = state[0].cast<const PyMesh&>().snapshot();
            const auto wxyz = state[2].cast<std::array<double, 4>>();
            const RigidTransform pose{{wxyz[0], wxyz[1], wxyz[2], wxyz[3]}, state[3].cast<Vec3>()};
            std::optional<QueryMesh> mesh;
            {
              py::gil_scoped_release release;
              mesh.emplace(*snapshot);
            }
            if (state[1].cast<bool>()) mesh->setPose(pose);
            return std::move(*mesh);
          }))
      .def_property_readonly("triangle_count", &QueryMesh::size, "The number of triangles.")
      .def_property_readonly("closed", &QueryMesh::closed,
                             "Closed and consistently oriented. Pseudonormal signs also need "
                             "bounds_solid (no self-intersections, its parts nested); "
                             "sign=\"winding\" takes any mesh.")
      .def_property_readonly(
          "bounds",
          [](const QueryMesh& mesh) {
            return vec3Array(std::vector<Vec3>{mesh.bounds().lower, mesh.bounds().upper});
          },
          "The box of the vertices in the prepared frame, shape (2, 3).")
      .def_property_readonly(
          "self_intersections",
          [](const QueryMesh& mesh) {
            py::gil_scoped_release release;
            return selfIntersections(mesh).count;
          },
          "The number of pairs of non-adjacent triangles that intersect (found on first use, "
          "O(n log n), and kept; as `delta info`). Pseudonormal signs refuse a mesh with any.")
      .def_property_readonly(
          "part_nesting",
          [](const QueryMesh& mesh) {
            PartNesting nesting;
            {
              py::gil_scoped_release release;
              nesting = partNesting(mesh);
            }
            py::dict result;
            result["parts"] = nesting.parts;
            result["misoriented"] = nesting.misoriented;
            result["pinched"] = nesting.pinched;
            result["flat"] = nesting.flat;
            result["undecided"] = nesting.undecided;
            result["misoriented_triangles"] = nesting.misorientedTriangles;
            return result;
          },
          "How the parts of a closed mesh (its triangles joined across edges) nest, as a dict: "
          "'parts'; 'misoriented', those oriented against the parts around them (an inside-out "
          "part outside the others, a shell inside a shell of the same orientation: winding "
          "number -1 or 2 there); 'pinched', vertices where the surface meets itself (parts "
          "touching at a vertex or sharing faces); 'flat', parts enclosing no volume (a triangle "
          "stored twice, back to back); 'undecided', parts no exact ray placed; "
          "'misoriented_triangles', a triangle id of each of the first 16 misoriented parts. "
          "Found on first use and kept; all 0 for an open mesh. Pseudonormal signs, overlap() and "
          "particle shapes refuse a mesh whose parts do not nest; sign=\"winding\" answers it.")
      .def_property_readonly(
          "bounds_solid",
          [](const QueryMesh& mesh) {
            py::gil_scoped_release release;
            return boundsSolid(mesh);
          },
          "Closed and consistently oriented, crossing itself nowhere, and its parts nested "
          "(part_nesting): the winding number off the surface is 0 or 1 and pseudonormal signs "
          "are exact.")
      .def_property_readonly("memory_bytes", &QueryMesh::memoryBytes,
                             "Bytes held on the heap (triangles, tree, pseudonormals).")
      .def(
          "copy", [](const QueryMesh& mesh) { return QueryMesh(mesh); },
          "A copy sharing the prepared data, with its own pose.")
      .def("__copy__", [](const QueryMesh& mesh) { return QueryMesh(mesh); })
      .def("__repr__", [](const QueryMesh& mesh) {
        return "<delta.QueryMesh: " + std::to_string(mesh.size()) + " triangles, " +
               (mesh.closed() ? "closed" : "open") + (mesh.moved() ? ", moved" : "") + ">";
      });
}

void bindQueries(py::module_& module) {
  module.def(
      "contacts",
      [](const Geometry& a, const Geometry& b, double epsilon, const std::string& method) {
        const kernels::Solver solver = solverNamed(method);
        std::vector<ContactPoint> found;
        {
          py::gil_scoped_release release;
          found = cd::contacts(a.prepare(), b.prepare(), epsilon, solver);
        }
        return contactArray(std::move(found));
      },
      "a"_a, "b"_a, "eps"_a, "method"_a = "hybrid",
      R"(Every pair of triangles, one of `a` and one of `b` (Mesh or QueryMesh), closer than 2*eps.

Returns a structured array of delta.contact_dtype, one record a pair, sorted by (triangle_a,
triangle_b): `x` (3,) midway between the closest points P on a and Q on b, `normal` (3,) = P - x
(length distance / 2), `direction` (3,) the unit vector from b toward a (defined also for
touching and intersecting triangles), `distance` |P - Q|, `overlap` (the triangles intersect, or
x lies inside both closed meshes), `converged` (always True for the exact methods; for "penalty"
whether its Newton iteration certified the pair: read it before trusting the distance),
`triangle_a`, `triangle_b` (uint32, the meshes' triangle order). `method`: "hybrid" (exact,
fastest), "bruteforce" (exact) or "penalty" (approximate).
The same records as `delta contact A B --eps E --out FILE.csv`. delta.Error when eps is not
finite and positive.)");
  module.def(
      "point_contacts",
      [](const Geometry& mesh, const ArrayLike& points, double epsilon) {
        const DoubleArray coordinates = pointArray(points, "points", true);
        std::vector<ContactPoint> found;
        {
          const SignalScope interruptible;
          py::gil_scoped_release release;
          found = cd::contacts(mesh.prepare(), asVec3(coordinates), epsilon);
        }
        return contactArray(std::move(found));
      },
      "mesh"_a, "points"_a, "eps"_a,
      "Every point of `points` (n, 3) closer than eps to the mesh, in point order, as records of "
      "delta.contact_dtype: the point is the first geometry (triangle_a = its index, P = the "
      "point), the mesh the second (Q = the closest point, triangle_b its triangle); `overlap` = "
      "inside a closed mesh. Ctrl-C stops it (KeyboardInterrupt).");
  module.def("distance", &distance, "mesh"_a, "points"_a, "eps"_a = py::none(), "signed"_a = false,
             py::kw_only(), "out"_a = py::none(), "sign"_a = py::none(),
             R"(The distance from every point to the mesh (a Mesh or a QueryMesh).

`points`: an array of shape (..., 3), used without a copy when it is C-contiguous float64
(converted otherwise). Returns a structured array of delta.distance_dtype with the points' shape
less the last axis, written in place by the query: `distance` (unsigned; +inf beyond eps),
`closest` (3,) the closest point of the mesh, `triangle` (uint32, the smallest id of a tie;
delta.NO_TRIANGLE beyond eps), `inside` (with signed=True), `ambiguous` (with sign="winding": the
winding number is within 0.05 of 1/2, as across a hole). `sign` (implies signed=True):
"pseudonormal" (the default; the mesh must bound a solid, QueryMesh.bounds_solid: closed, not
crossing itself, its parts nested; delta.Error otherwise) or "winding" (inside where the generalized winding number exceeds 1/2: any mesh, open
or self-intersecting; computed fast by Barill et al.'s hierarchy, exact in sign); another string
raises ValueError. The signed distance is np.where(r["inside"], -r["distance"], r["distance"]);
delta.signed_distance(r) computes it. `eps`: answer only points closer than eps (faster: the
search stops near the root for the others). `out`: a C-contiguous, writeable array of
delta.distance_dtype and that shape, sharing no memory with the points (delta.Error otherwise),
to put the answers in instead of a new array (returned); they are computed into a scratch buffer
and copied into `out` at the end, so that an error or Ctrl-C leaves `out` as it was. On the main
thread, Ctrl-C stops the query within some tens of milliseconds (KeyboardInterrupt). Exactly
`delta distance MESH --points FILE`.)");
  module.def(
      "filter",
      [](const ArrayLike& contacts, double h) {
        std::vector<ContactPoint> points = contactsFrom(contacts);
        {
          py::gil_scoped_release release;
          points = cd::filter(points, h);
        }
        return contactArray(std::move(points));
      },
      "contacts"_a, "h"_a,
      "The seed's redundancy elimination: walking the contacts by ascending normal length, keep "
      "one unless a kept one lies closer than h. Returns the kept records in input order "
      "(delta.contact_dtype). delta.Error when h is not finite and positive.");

  py::class_<cd::MinimumDistance>(module, "MinimumDistance",
                                  "The closest pair of triangles of two meshes.")
      .def_readonly("distance", &cd::MinimumDistance::distance, "The minimum distance |p - q|.")
      .def_readonly("triangle_a", &cd::MinimumDistance::first, "Triangle id in the first mesh.")
      .def_readonly("triangle_b", &cd::MinimumDistance::second, "Triangle id in the second mesh.")
      .def_property_readonly(
          "p", [](const cd::MinimumDistance& m) { return m.p; }, "Closest point on triangle_a.")
      .def_property_readonly(
          "q", [](const cd::MinimumDistance& m) { return m.q; }, "Closest point on triangle_b.")
      .def_readonly("intersect", &cd::MinimumDistance::intersect,
                    "The meshes touch or intersect there (distance 0).")
      .def("__repr__", [](const cd::MinimumDistance& m) {
        return "MinimumDistance(distance=" + py::repr(py::float_(m.distance)).cast<std::string>() +
               ", triangle_a=" + std::to_string(m.first) +
               ", triangle_b=" + std::to_string(m.second) +
               ", intersect=" + (m.intersect ? "True" : "False") + ")";
      });
  module.def(
      "minimum_distance",
      [](const Geometry& a, const Geometry& b, const std::string& method) {
        const kernels::Solver solver = solverNamed(method);
        py::gil_scoped_release release;
        return cd::minimumDistance(a.prepare(), b.prepare(), solver);
      },
      "a"_a, "b"_a, "method"_a = "hybrid",
      "The minimum distance between two meshes (Mesh or QueryMesh, where they are now) and the "
      "closest triangle pair, exact with the hybrid or brute-force method; ties go to the "
      "smallest (triangle_a, triangle_b). As `delta contact A B` without --eps.");
}

/// The common read-only attributes of an OverlapRegion and an Overlap (its total): `region`
/// gives the integrals of an object of the class.
template <typename Class, typename Region>
void addRegionAttributes(Class& bound, Region region, const char* which) {
  using Bound = typename Class::type;
  const std::string of = std::string(" (") + which + ")";
  bound
      .def_property_readonly(
          "volume", [region](const Bound& o) { return region(o).volume; },
          ("The volume of A ∩ B" + of + ".").c_str())
      .def_property_readonly(
          "centroid", [region](const Bound& o) { return region(o).centroid; },
          ("The centroid of the shared solid, shape (3,) (world frame; zero where there is none)" +
           of + ".")
              .c_str())
      .def_property_readonly(
          "area_vector", [region](const Bound& o) { return region(o).areaVector; },
          ("∫ n dA over the part of a's surface inside b, n a's outward normal, shape (3,): the "
           "direction the overlap pushes b out of a" +
           of + ".")
              .c_str())
      .def_property_readonly(
          "area_vector_b", [region](const Bound& o) { return region(o).areaVectorB; },
          ("The same over the part of b's surface inside a: -area_vector up to rounding (the "
           "boundary of A ∩ B is closed), for checking" +
           of + ".")
              .c_str())
      .def_property_readonly(
          "moment", [region](const Bound& o) { return region(o).moment; },
          ("∫ (x - centroid) × n dA over the part of a's surface inside b, shape (3,); about "
           "another point p it is moment + np.cross(centroid - p, area_vector)" +
           of + ".")
              .c_str())
      .def_property_readonly(
          "curve_length", [region](const Bound& o) { return region(o).curveLength; },
          ("The length of the intersection curves bounding the shared solid" + of + ".").c_str());
}

/// The numbers of a vector of triangle ids as a uint32 array (a copy).
py::array idArray(const std::vector<std::uint32_t>& ids) {
  py::array_t<std::uint32_t> array(static_cast<py::ssize_t>(ids.size()));
  if (!ids.empty())
    std::memcpy(array.mutable_data(), ids.data(), ids.size() * sizeof(std::uint32_t));
  return array;
}

std::string vectorRepr(const Vec3& v) {
  return "(" + py::repr(py::float_(v.x)).cast<std::string>() + ", " +
         py::repr(py::float_(v.y)).cast<std::string>() + ", " +
         py::repr(py::float_(v.z)).cast<std::string>() + ")";
}

void bindOverlap(py::module_& module) {
  auto region = py::class_<cd::OverlapRegion>(
      module, "OverlapRegion",
      "One connected piece of the solid two closed meshes share (A ∩ B): its volume, centroid "
      "and surface integrals, as delta.overlap finds them.");
  addRegionAttributes(
      region, [](const cd::OverlapRegion& r) -> const cd::OverlapRegion& { return r; },
      "this region");
  region
      .def_readonly("triangles", &cd::OverlapRegion::triangles,
                    "The number of triangles of both meshes wholly or partly on this region's "
                    "boundary.")
      .def("__repr__", [](const cd::OverlapRegion& r) {
        return "OverlapRegion(volume=" + py::repr(py::float_(r.volume)).cast<std::string>() +
               ", centroid=" + vectorRepr(r.centroid) +
               ", triangles=" + std::to_string(r.triangles) + ")";
      });

  py::class_<cd::IntersectionCurve>(
      module, "IntersectionCurve",
      "A curve where the surfaces of two meshes cross: a chain of segments, each where a "
      "triangle of the first mesh crosses one of the second. Seen from outside the first mesh, "
      "the part of its surface inside the second lies to the left of the curve.")
      .def_property_readonly(
          "points", [](const cd::IntersectionCurve& c) { return vec3Array(c.points); },
          "The points, shape (n, 3) float64 (world frame, a copy); a closed curve's last point "
          "repeats its first.")
      .def_property_readonly(
          "triangles_a", [](const cd::IntersectionCurve& c) { return idArray(c.trianglesA); },
          "Per segment (points[i] to points[i + 1]), the first mesh's triangle: uint32, shape "
          "(n - 1,).")
      .def_property_readonly(
          "triangles_b", [](const cd::IntersectionCurve& c) { return idArray(c.trianglesB); },
          "Per segment, the second mesh's triangle: uint32, shape (n - 1,).")
      .def_readonly("region", &cd::IntersectionCurve::region,
                    "The index into Overlap.regions of the region the curve bounds.")
      .def_readonly("closed", &cd::IntersectionCurve::closed,
                    "The curve ends where it starts (always, for closed meshes).")
      .def_readonly("length", &cd::IntersectionCurve::length, "The length of the curve.")
      .def(
          "__len__", [](const cd::IntersectionCurve& c) { return c.trianglesA.size(); },
          "The number of segments.")
      .def("__repr__", [](const cd::IntersectionCurve& c) {
        return "IntersectionCurve(segments=" + std::to_string(c.trianglesA.size()) +
               ", length=" + py::repr(py::float_(c.length)).cast<std::string>() +
               ", region=" + std::to_string(c.region) +
               ", closed=" + (c.closed ? "True" : "False") + ")";
      });

  auto found = py::class_<cd::Overlap>(
      module, "Overlap",
      "What delta.overlap finds: the integrals over all of A ∩ B (volume, centroid, "
      "area_vector, area_vector_b, moment, curve_length), the same per connected region "
      "(regions, largest volume first), the intersection curves, and counts. True when the "
      "meshes share a volume.");
  addRegionAttributes(
      found, [](const cd::Overlap& o) -> const cd::OverlapRegion& { return o.total; },
      "all regions; the centroid is their volume-weighted mean, the moment about it");
  found
      .def_property_readonly(
          "total", [](const cd::Overlap& o) { return o.total; },
          "The integrals over all regions, as an OverlapRegion.")
      .def_property_readonly(
          "regions", [](const cd::Overlap& o) { return o.regions; },
          "The connected pieces of A ∩ B, largest volume first: a list of OverlapRegion.")
      .def_property_readonly(
          "curves", [](const cd::Overlap& o) { return o.curves; },
          "The intersection curves: a list of IntersectionCurve (empty with curves=False).")
      .def_readonly("segments", &cd::Overlap::segments,
                    "The number of intersection segments (pairs of crossing triangles) found.")
      .def_readonly("touching", &cd::Overlap::touching,
                    "Pieces of contact that enclose no volume (surfaces that only touch, faces "
                    "lying on one another): counted here, left out of the regions.")
      .def_readonly("coplanar", &cd::Overlap::coplanar,
                    "Pairs of triangles, one of each mesh, lying in one plane with meeting "
                    "boxes: there the surface integrals are one-sided derivatives of the volume, "
                    "and are answered as the mean of both sides.")
      .def_readonly("one_sided", &cd::Overlap::oneSided,
                    "True where coplanar faces met but the surface integrals are one side's "
                    "alone (symmetric=False).")
      .def("__bool__", &cd::Overlap::any, "The meshes share a volume (regions is not empty).")
      .def("__repr__", [](const cd::Overlap& o) {
        return "Overlap(volume=" + py::repr(py::float_(o.total.volume)).cast<std::string>() +
               ", regions=" + std::to_string(o.regions.size()) +
               ", curves=" + std::to_string(o.curves.size()) +
               ", segments=" + std::to_string(o.segments) +
               ", touching=" + std::to_string(o.touching) + ")";
      });

  module.def(
      "overlap",
      [](const Geometry& a, const Geometry& b, Flag curves, Flag symmetric) {
        cd::OverlapOptions options;
        options.curves = curves.value;
        options.symmetric = symmetric.value;
        py::gil_scoped_release release;
        return cd::overlap(a.prepare(), b.prepare(), options);
      },
      "a"_a, "b"_a, "curves"_a = true, "symmetric"_a = true,
      R"(The solid two closed meshes share, A ∩ B, each where it is now.

`a`, `b`: each a Mesh, or a QueryMesh at its pose. Returns a delta.Overlap: `volume`,
`centroid`, `area_vector` (∫ n dA over the part of a's surface inside b, n a's outward normal:
the direction the overlap pushes b out of a), `area_vector_b` (the same over b's surface inside
a: -area_vector up to rounding), `moment` (∫ (x - centroid) × n dA over a's part) and
`curve_length`, over all of A ∩ B; `regions`, the same per connected piece (delta.OverlapRegion,
largest volume first, with the count of `triangles` on its boundary); `curves`, the intersection
curves (delta.IntersectionCurve: `points` (n, 3), `triangles_a` and `triangles_b` per segment,
`region`, `closed`, `length`; none with curves=False, which the integrals do not need);
`segments` (crossing triangle pairs) and `touching` (contacts that enclose no volume, left out
of the regions); `coplanar` (pairs of triangles in one plane) and `one_sided`. Where faces of a
and b lie in one plane the volume is not differentiable, and the area vectors and moments are
the mean of both one-sided derivatives (a second query, the meshes swapped); symmetric=False
gives one side's alone. Vectors are float64 arrays of shape (3,), in the world frame. The topology is
exact (exact predicates; a symbolic perturbation settles touching and coplanar faces). For a
volume-based contact law with energy w(V): the force on b is w'(V) * area_vector, the torque on
b about its centre c is w'(V) * (moment + np.cross(centroid - c, area_vector)). delta.Error (a
ValueError) when a mesh is open, not consistently oriented, or crosses itself; TypeError when a
or b is not a Mesh or a QueryMesh. As `delta overlap A B`.)");
}

}  // namespace

void bindQuery(py::module_& module) {
  module.attr("contact_dtype") = contactDtype();
  module.attr("distance_dtype") = distanceDtype();
  module.attr("NO_TRIANGLE") = cd::kNoTriangle;
  bindQueryMesh(module);
  bindQueries(module);
  bindOverlap(module);
}

}  // namespace delta::python
