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

#include "strict_numbers.h"

namespace delta::python {

namespace py = pybind11;

/// An argument NumPy converts to an array (an ndarray, a list, anything with __array__), taken as
/// it is and converted by the function (pointArray), which names the argument in its errors.
struct ArrayLike {
  py::object object;
};

/// A C-contiguous, aligned float64 array in native byte order: what Δ's kernels read without a
/// copy.
using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast |
                                            py::detail::npy_api::NPY_ARRAY_ALIGNED_>;

/// How an argument is read as real numbers, the one rule of every array argument:
/// - taken: a tuple, a list (nested for more axes) or anything NumPy converts to an array whose
///   dtype is an integer or a real type of at most 64 bits (float16/32/64, int8 … uint64);
/// - TypeError (the argument is not numbers): None, a string or bytes, booleans (a bool array,
///   or a bool anywhere in a list), complex numbers, objects, records, dates, ragged lists, and
///   reals wider than float64 (longdouble: they would be rounded; convert them first);
/// - delta.Error, a ValueError (numbers, but not these): another shape, an integer that float64
///   does not hold exactly (beyond 2^53), and where finite numbers are asked, NaN or ±∞;
/// - except that a 3-vector or 3×3 matrix of another shape (the casters below) is not loaded, so
///   that pybind11 can try a function's other overloads: TypeError when none takes it.
///
/// Threading: this file's functions are called with the GIL held.
///
/// `given` as a NumPy array of real numbers (not converted yet), or the reason it is not one
/// (for a TypeError: "must be ... not ..."), in `problem`.
struct RealArray {
  py::array array;
  std::string problem;
};
RealArray realArray(py::handle given);

/// The dimensions of an array as text: "(2, 3)", "(3,)", "()".
std::string shapeOf(const py::array& array);

/// `given` as a C-contiguous float64 array whose last axis has length 3 (points, vertices),
/// converted only when it is not one already (another dtype, another order, misaligned, a list).
/// `exactlyTwoAxes` asks for shape (n, 3). Throws TypeError naming `what` for what is not real
/// numbers, delta::Error for another shape or an integer float64 would round (the rule above);
/// non-finite coordinates are left to the function (queries and Mesh name the point).
DoubleArray pointArray(const ArrayLike& given, const char* what, bool exactlyTwoAxes);

/// Throws delta::Error naming `what` for the first integer of `array` (int64 or uint64) that
/// float64 does not hold exactly (beyond 2^53): converting it would round. Other dtypes pass.
void requireExactIntegers(const py::array& array, const char* what);

/// Throws delta::Error naming `what` and the index of the first non-finite value of `values`.
void requireFinite(std::span<const double> values, const char* what);

/// The coordinates of a (…, 3) array made by pointArray, as Vec3s (no copy).
std::span<const Vec3> asVec3(const DoubleArray& points);

/// Whether the memory of two arrays overlaps (by the byte ranges their strides span).
bool overlaps(const py::array& first, const py::array& second);

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

/// delta::Vec3 ⇄ three finite real numbers (a tuple, a list, an array of shape (3,), read by
/// delta::python::realArray's rule); returned as a float64 array of shape (3,).
///
/// What is not three real numbers (None, a string, a scalar, booleans, complex numbers, another
/// shape) is not loaded: pybind11 then tries the function's other overloads and raises TypeError
/// ("incompatible function arguments", listing the signatures) when none takes it. Three numbers
/// that are not all finite, or an integer float64 would round, raise delta.Error (ValueError).
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

/// delta::Mat3 ⇄ a 3×3 array of finite real numbers, rows first; loaded as Vec3 is (another
/// shape: TypeError through overload resolution; a non-finite entry: delta.Error).
template <>
struct type_caster<delta::Mat3> {
 public:
  PYBIND11_TYPE_CASTER(delta::Mat3, const_name("numpy.ndarray[numpy.float64[3, 3]]"));
  bool load(handle source, bool convert);
  static handle cast(const delta::Mat3& matrix, return_value_policy policy, handle parent);
};

}  // namespace pybind11::detail
