// What the Python objects hold: Δ's objects behind shared pointers, so that NumPy views of their
// storage and queries running without the GIL keep what they read alive and unchanged.
#pragma once

#include <pybind11/pybind11.h>

#include <memory>
#include <optional>
#include <utility>

#include "delta/mesh/mesh.h"
#include "delta/query/query_mesh.h"

#include "strict_numbers.h"

namespace delta::python {

namespace py = pybind11;

/// The object behind a Python `delta.Mesh`: copy on write.
///
/// Views of the vertices and triangles (NumPy arrays) and queries running without the GIL each
/// hold a snapshot (a shared pointer). A transform changes the mesh in place when nothing else
/// holds it and otherwise transforms a copy and holds that from then on, so a snapshot never
/// changes under its holder: a view keeps showing the coordinates it was taken of. (Mesh's
/// transforms replace the vertex array anyway; in place or not, a view never dangles.)
///
/// Threading: used with the GIL held; snapshots may be read without it.
class PyMesh {
 public:
  explicit PyMesh(Mesh mesh) : mesh_(std::make_shared<Mesh>(std::move(mesh))) {}

  const Mesh& mesh() const noexcept { return *mesh_; }
  /// The mesh as it is now, kept alive and unchanged for as long as the pointer lives.
  std::shared_ptr<const Mesh> snapshot() const noexcept { return mesh_; }

  /// Applies `change` (a Mesh transform) to this mesh, copying it first if a snapshot is held.
  /// A change that throws leaves the mesh as it was (Mesh's transforms do).
  template <typename Change>
  void change(Change&& transform) {
    if (mesh_.use_count() > 1) {
      auto copy = std::make_shared<Mesh>(*mesh_);
      transform(*copy);
      mesh_ = std::move(copy);
    } else {
      transform(*mesh_);
    }
  }

 private:
  std::shared_ptr<Mesh> mesh_;
};

/// A geometry argument that may be a `delta.Mesh` or a `delta.QueryMesh`, taken with the GIL
/// held and prepared without it: a QueryMesh is copied (its prepared data is shared, its pose is
/// this call's own, so moving the Python object meanwhile changes nothing here); a Mesh is
/// snapshotted and prepared by prepare().
class Geometry {
 public:
  Geometry() = default;
  /// Throws TypeError naming `what` for anything else.
  Geometry(py::handle object, const char* what);

  /// The prepared mesh; builds the QueryMesh of a Mesh (O(n log n): call it without the GIL).
  QueryMesh prepare() const;

 private:
  std::shared_ptr<const Mesh> mesh_;
  std::optional<QueryMesh> queryMesh_;
};

/// Marks an object that a call works on without the GIL (a DEM World stepping, a grid moving),
/// so that other Python threads get a RuntimeError instead of a data race while it does.
///
/// Threading: used with the GIL held.
class BusyFlag {
 public:
  /// Throws RuntimeError naming `what` while the object is in use.
  void check(const char* what) const;
  bool busy() const noexcept { return busy_; }

  /// Holds the flag for its lifetime (checked first).
  class Hold {
   public:
    Hold(BusyFlag& flag, const char* what) : flag_(flag) {
      flag_.check(what);
      flag_.busy_ = true;
    }
    ~Hold() { flag_.busy_ = false; }
    Hold(const Hold&) = delete;
    Hold& operator=(const Hold&) = delete;

   private:
    BusyFlag& flag_;
  };

 private:
  bool busy_ = false;
};

}  // namespace delta::python

namespace pybind11::detail {

/// A `delta.Mesh` or `delta.QueryMesh` argument, as a Geometry.
template <>
struct type_caster<delta::python::Geometry> {
 public:
  PYBIND11_TYPE_CASTER(delta::python::Geometry, const_name("Union[delta.Mesh, delta.QueryMesh]"));
  bool load(handle source, bool);
};

}  // namespace pybind11::detail
