// Rigid motions at the boundary between Python and Δ: every argument that is a transform takes a
// delta.RigidTransform or a 4×4 homogeneous matrix [R t; 0 1], as trimesh and Open3D give them.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "delta/core/rotation.h"

#include "strict_numbers.h"

namespace delta::python {

namespace py = pybind11;

/// The rigid motion of a 4×4 homogeneous matrix (a NumPy array, or nested lists or tuples) of
/// real numbers. TypeError when it is not numbers (arrays.h's rule); delta.Error (a ValueError)
/// naming `what` for another shape, a non-finite entry, a last row other than (0, 0, 0, 1) or an
/// upper-left 3×3 block that is not a rotation (a scale, a shear, a reflection: the error gives
/// |MᵀM − I| and det M).
///
/// Threading: with the GIL held.
RigidTransform fromHomogeneous(py::handle matrix, const std::string& what);

/// A transform argument: a RigidTransform, or a 4×4 matrix read by fromHomogeneous.
struct Motion {
  RigidTransform value;
};

}  // namespace delta::python

namespace pybind11::detail {

/// Loads a delta.RigidTransform as it is, and an ndarray, list or tuple as a 4×4 matrix (a bad
/// matrix raises its error rather than "incompatible arguments"); anything else is not loaded.
template <>
struct type_caster<delta::python::Motion> {
  PYBIND11_TYPE_CASTER(delta::python::Motion,
                       const_name("Union[delta.RigidTransform, numpy.typing.ArrayLike]"));

  bool load(handle source, bool /*convert*/) {
    if (isinstance<delta::RigidTransform>(source)) {
      value.value = source.cast<delta::RigidTransform>();
      return true;
    }
    if (isinstance<array>(source) || isinstance<list>(source) || isinstance<tuple>(source)) {
      value.value = delta::python::fromHomogeneous(source, "the transform");
      return true;
    }
    return false;
  }
};

}  // namespace pybind11::detail
