// NumPy arrays at the boundary between Python and Δ: conversions of input arrays that copy only
// when the layout asks for it, arrays that view memory Δ owns, structured record types laid out
// over Δ's own structs, and the casters that turn 3-vectors and 3×3 matrices into arrays.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cstddef>
#include <initializer_list>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/mat3.h"
#include "delta/core/vec3.h"

namespace delta::python {

namespace py = pybind11;

/// An argument NumPy converts to an array (an ndarray, a list, anything with __array__), taken as
/// it is and converted by the function (pointArray), which names the argument in its errors.
struct ArrayLike {
  py::object object;
};

/// A C-contiguous float64 array: what Δ's kernels read without a copy.
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

/// `given` as a C-contiguous float64 array whose last axis has length 3 (points, vertices),
/// converted only when it is not one already (another dtype, another order, a list). Throws
/// delta::Error naming `what` for non-numbers, complex numbers or another shape; `exactlyTwoAxes`
/// asks for shape (n, 3).
DoubleArray pointArray(const ArrayLike& given, const char* what, bool exactlyTwoAxes);

/// The coordinates of a (…, 3) array made by pointArray, as Vec3s (no copy).
std::span<const Vec3> asVec3(const DoubleArray& points);

/// A field of a record (structured) dtype: its name, NumPy format and byte offset.
struct Field {
  const char* name;
  const char* format;
  std::size_t offset;
};

/// The structured dtype with these fields over records of `itemsize` bytes: the layout of a C++
/// struct, so that an array of such structs is a NumPy array without conversion.
py::dtype recordDtype(std::initializer_list<Field> fields, std::size_t itemsize);

/// Makes `array` read-only (numpy's writeable flag): a view of storage Δ owns.
void makeReadOnly(py::array& array);

/// A NumPy array that owns `values` (moved into a capsule, not copied) and views them with the
/// given dtype, shape and strides.
template <typename T>
py::array adopt(std::vector<T>&& values, const py::dtype& dtype, std::vector<py::ssize_t> shape,
                std::vector<py::ssize_t> strides = {}) {
  auto* owned = new std::vector<T>(std::move(values));
  py::capsule base(owned, [](void* pointer) { delete static_cast<std::vector<T>*>(pointer); });
  return py::array(dtype, std::move(shape), std::move(strides), owned->data(), base);
}

/// A read-only NumPy array over `data`, which `owner` keeps alive (a shared_ptr copied into the
/// array's base capsule).
template <typename Owner>
py::array view(std::shared_ptr<Owner> owner, const void* data, const py::dtype& dtype,
               std::vector<py::ssize_t> shape, std::vector<py::ssize_t> strides) {
  auto* kept = new std::shared_ptr<Owner>(std::move(owner));
  py::capsule base(kept,
                   [](void* pointer) { delete static_cast<std::shared_ptr<Owner>*>(pointer); });
  py::array array(dtype, std::move(shape), std::move(strides), data, base);
  makeReadOnly(array);
  return array;
}

/// (n, 3) float64 array of the points (a copy).
py::array vec3Array(std::span<const Vec3> points);

}  // namespace delta::python

namespace pybind11::detail {

/// delta::Vec3 ⇄ anything NumPy reads as three numbers (a tuple, a list, an array of shape (3,));
/// returned as a float64 array of shape (3,).
template <>
struct type_caster<delta::Vec3> {
 public:
  PYBIND11_TYPE_CASTER(delta::Vec3, const_name("numpy.ndarray[numpy.float64[3]]"));
  bool load(handle source, bool convert);
  static handle cast(const delta::Vec3& vector, return_value_policy policy, handle parent);
};

/// Any object, as an ArrayLike: the function converts and checks it.
template <>
struct type_caster<delta::python::ArrayLike> {
 public:
  PYBIND11_TYPE_CASTER(delta::python::ArrayLike, const_name("numpy.typing.ArrayLike"));
  bool load(handle source, bool) {
    if (!source) return false;
    value.object = reinterpret_borrow<object>(source);
    return true;
  }
};

/// delta::Mat3 ⇄ anything NumPy reads as a 3×3 array of numbers, rows first.
template <>
struct type_caster<delta::Mat3> {
 public:
  PYBIND11_TYPE_CASTER(delta::Mat3, const_name("numpy.ndarray[numpy.float64[3, 3]]"));
  bool load(handle source, bool convert);
  static handle cast(const delta::Mat3& matrix, return_value_policy policy, handle parent);
};

}  // namespace pybind11::detail
