#include "handles.h"

#include <string>

namespace delta::python {

Geometry::Geometry(py::handle object, const char* what) {
  if (py::isinstance<QueryMesh>(object))
    queryMesh_ = object.cast<const QueryMesh&>();
  else if (py::isinstance<PyMesh>(object))
    mesh_ = object.cast<const PyMesh&>().snapshot();
  else
    throw py::type_error(std::string(what) + " must be a delta.Mesh or a delta.QueryMesh, not " +
                         py::str(py::type::handle_of(object).attr("__name__")).cast<std::string>());
}

QueryMesh Geometry::prepare() const {
  return queryMesh_ ? *queryMesh_ : QueryMesh(*mesh_);
}

void BusyFlag::check(const char* what) const {
  if (busy_)
    throw std::runtime_error(std::string(what) +
                             " is in use by another thread (a step, run or move without the "
                             "GIL); wait for it to finish");
}

}  // namespace delta::python

namespace pybind11::detail {

bool type_caster<delta::python::Geometry>::load(handle source, bool) {
  using delta::python::PyMesh;
  if (!source || !(isinstance<delta::QueryMesh>(source) || isinstance<PyMesh>(source)))
    return false;
  value = delta::python::Geometry(source, "geometry");
  return true;
}

}  // namespace pybind11::detail
