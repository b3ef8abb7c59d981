#include "arrays.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/memory.h"

namespace delta::python {

namespace {

/// A boolean NumPy would read as 0 or 1: Python's bool, numpy.bool_, a boolean array.
bool isBoolean(py::handle item) {
  if (PyBool_Check(item.ptr())) return true;
  if (PyFloat_CheckExact(item.ptr()) || PyLong_CheckExact(item.ptr())) return false;
  if (py::isinstance<py::array>(item))
    return py::reinterpret_borrow<py::array>(item).dtype().kind() == 'b';
  static const py::handle numpyBool =
      py::object(py::module_::import("numpy").attr("bool_")).release();
  return PyObject_IsInstance(item.ptr(), numpyBool.ptr()) == 1;
}

/// Whether a list or tuple holds a boolean at any depth (NumPy would make 0 or 1 of it, or of
/// [True, 2, 3] an integer array).
bool holdsBoolean(py::handle given, int depth) {
  if (depth > 64 || !(PyList_Check(given.ptr()) || PyTuple_Check(given.ptr()))) return false;
  const py::sequence items = py::reinterpret_borrow<py::sequence>(given);
  for (const py::handle item : items)
    if (isBoolean(item) || holdsBoolean(item, depth + 1)) return true;
  return false;
}

/// The lowest and one past the highest byte an array's elements occupy.
std::pair<const char*, const char*> byteRange(const py::array& array) {
  const char* lowest = static_cast<const char*>(array.data());
  const char* highest = lowest;
  for (py::ssize_t axis = 0; axis < array.ndim(); ++axis) {
    const py::ssize_t reach = (array.shape(axis) - 1) * array.strides(axis);
    (reach < 0 ? lowest : highest) += reach;
  }
  return {lowest, highest + array.itemsize()};
}

/// Where a nest of lists and tuples is ragged: "rows of 3 and 2 items" for the first level whose
/// sequences differ in length, or whose items are sequences and numbers mixed; empty where it is
/// rectangular (as far as NumPy cares: depth 32 at most).
std::string raggedness(py::handle given, int depth = 0) {
  const auto isSequence = [](py::handle item) {
    return PyList_Check(item.ptr()) || PyTuple_Check(item.ptr());
  };
  if (depth > 32 || !isSequence(given)) return "";
  const py::sequence items = py::reinterpret_borrow<py::sequence>(given);
  const std::size_t count = items.size();
  if (count == 0) return "";
  const bool nested = isSequence(items[0]);
  const std::size_t length = nested ? py::len(items[0]) : 0;
  for (std::size_t i = 1; i < count; ++i) {
    const py::handle item = items[i];
    if (isSequence(item) != nested) return "sequences and numbers mixed at one level";
    if (nested && py::len(item) != length)
      return "rows of " + std::to_string(length) + " and " + std::to_string(py::len(item)) +
             " items";
  }
  if (!nested) return "";
  for (std::size_t i = 0; i < count; ++i)
    if (std::string why = raggedness(items[i], depth + 1); !why.empty()) return why;
  return "";
}

}  // namespace

RealArray realArray(py::handle given) {
  const auto refuse = [](std::string why) { return RealArray{py::array(), std::move(why)}; };
  if (!given || given.is_none()) return refuse("must be real numbers, not None");
  if (PyUnicode_Check(given.ptr()) || PyBytes_Check(given.ptr()) || PyByteArray_Check(given.ptr()))
    return refuse("must be real numbers, not a string");
  if (isBoolean(given) || holdsBoolean(given, 0))
    return refuse("must be real numbers, not booleans");
  py::array array = py::array::ensure(given);  // clears NumPy's error when it cannot
  if (!array) {
    if (const std::string ragged = raggedness(given); !ragged.empty())
      return refuse("must be a rectangular array of real numbers, not a ragged " +
                    py::str(py::type::handle_of(given).attr("__name__")).cast<std::string>() +
                    " (" + ragged + ")");
  }
  if (!array)
    return refuse("must be real numbers, not " +
                  py::str(py::type::handle_of(given).attr("__name__")).cast<std::string>() +
                  " (NumPy makes no array of numbers of it)");
  const py::dtype dtype = array.dtype();
  const std::string name = py::str(static_cast<const py::handle&>(dtype)).cast<std::string>();
  switch (dtype.kind()) {
    case 'i':
    case 'u':
      return {std::move(array), ""};
    case 'f':
      if (dtype.itemsize() <= 8) return {std::move(array), ""};
      return refuse("must be real numbers of at most 64 bits, not " + name +
                    " (float64 would round them: convert them yourself)");
    case 'b':
      return refuse("must be real numbers, not booleans");
    case 'c':
      return refuse("must be real numbers, not complex numbers (" + name + ")");
    default:
      return refuse("must be real numbers, not of dtype " + name);
  }
}

std::string shapeOf(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t axis = 0; axis < array.ndim(); ++axis)
    text += (axis ? ", " : "") + std::to_string(array.shape(axis));
  return text + (array.ndim() == 1 ? ",)" : ")");
}

DoubleArray pointArray(const ArrayLike& argument, const char* what, bool exactlyTwoAxes) {
  const RealArray given = realArray(argument.object);
  if (!given.problem.empty()) throw py::type_error(std::string(what) + " " + given.problem);
  const py::array& array = given.array;
  const bool shaped = exactlyTwoAxes ? array.ndim() == 2 && array.shape(1) == 3
                                     : array.ndim() >= 1 && array.shape(array.ndim() - 1) == 3;
  if (!shaped)
    throw Error(std::string(what) + " must have shape " + (exactlyTwoAxes ? "(n, 3)" : "(..., 3)") +
                ", not " + shapeOf(array));
  requireExactIntegers(array, what);
  // The float64 copy NumPy makes of any other array, and the library's own copy: refused with
  // a clear error where they would not fit (a broadcast view of 10^9 points was OOM-killed).
  requireMemory(2.0 * static_cast<double>(array.size()) * sizeof(double), what);
  DoubleArray points = DoubleArray::ensure(array);
  if (!points) throw Error(std::string(what) + ": conversion to float64 failed");
  return points;
}

void requireExactIntegers(const py::array& array, const char* what) {
  const char kind = array.dtype().kind();
  if ((kind != 'i' && kind != 'u') || array.dtype().itemsize() < 8) return;
  const auto refuse = [&](py::ssize_t index, const std::string& value) {
    throw Error(std::string(what) + ": element " + std::to_string(index) + " (" + value +
                ") is an integer float64 does not hold exactly (beyond 2^53); convert it to "
                "float yourself if rounding is meant");
  };
  if (kind == 'i') {
    using Integers = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;
    const Integers values = Integers::ensure(array);
    for (py::ssize_t i = 0; i < values.size(); ++i) {
      const std::int64_t value = values.data()[i];
      const double rounded = static_cast<double>(value);
      if (rounded >= 0x1p63 || static_cast<std::int64_t>(rounded) != value)
        refuse(i, std::to_string(value));
    }
  } else {
    using Integers = py::array_t<std::uint64_t, py::array::c_style | py::array::forcecast>;
    const Integers values = Integers::ensure(array);
    for (py::ssize_t i = 0; i < values.size(); ++i) {
      const std::uint64_t value = values.data()[i];
      const double rounded = static_cast<double>(value);
      if (rounded >= 0x1p64 || static_cast<std::uint64_t>(rounded) != value)
        refuse(i, std::to_string(value));
    }
  }
}

void requireFinite(std::span<const double> values, const char* what) {
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!std::isfinite(values[i]))
      throw Error(std::string(what) + ": value " + std::to_string(i) + " is " +
                  toString(values[i]) + ", not a finite number");
}

bool overlaps(const py::array& first, const py::array& second) {
  if (first.size() == 0 || second.size() == 0) return false;
  const auto [firstLow, firstHigh] = byteRange(first);
  const auto [secondLow, secondHigh] = byteRange(second);
  return firstLow < secondHigh && secondLow < firstHigh;
}

std::span<const Vec3> asVec3(const DoubleArray& points) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double) && alignof(Vec3) == alignof(double),
                "Vec3 must be three packed doubles to view an (n, 3) array");
  return {reinterpret_cast<const Vec3*>(points.data()),
          static_cast<std::size_t>(points.size()) / 3};
}

py::dtype recordDtype(std::initializer_list<Field> fields, std::size_t itemsize) {
  py::list names, formats, offsets;
  for (const Field& field : fields) {
    names.append(field.name);
    formats.append(field.format);
    offsets.append(field.offset);
  }
  return py::dtype(names, formats, offsets, static_cast<py::ssize_t>(itemsize));
}

void makeReadOnly(py::array& array) {
  array.attr("setflags")(py::arg("write") = false);
}

py::array vec3Array(std::span<const Vec3> points) {
  py::array_t<double> array({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto out = array.mutable_unchecked<2>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const auto row = static_cast<py::ssize_t>(i);
    out(row, 0) = points[i].x;
    out(row, 1) = points[i].y;
    out(row, 2) = points[i].z;
  }
  return array;
}

}  // namespace delta::python

namespace pybind11::detail {

namespace {

/// Reads `source` into `values` (rows first) when it is real numbers of this shape
/// (delta::python::realArray's rule); false when it is not. Throws delta::Error naming `what`
/// when it is, but an integer would round or a value is not finite.
bool loadFixed(handle source, std::initializer_list<ssize_t> shape, double* values,
               const char* what) {
  const delta::python::RealArray given = delta::python::realArray(source);
  if (!given.problem.empty()) return false;
  const array& numbers = given.array;
  if (numbers.ndim() != static_cast<ssize_t>(shape.size())) return false;
  ssize_t axis = 0;
  for (const ssize_t extent : shape)
    if (numbers.shape(axis++) != extent) return false;
  delta::python::requireExactIntegers(numbers, what);
  const delta::python::DoubleArray converted = delta::python::DoubleArray::ensure(numbers);
  if (!converted) throw delta::Error(std::string(what) + ": conversion to float64 failed");
  const std::size_t count = static_cast<std::size_t>(converted.size());
  std::copy(converted.data(), converted.data() + count, values);
  delta::python::requireFinite({values, count}, what);
  return true;
}

}  // namespace

bool type_caster<delta::Vec3>::load(handle source, bool) {
  double values[3];
  if (!loadFixed(source, {3}, values, "a 3-vector argument")) return false;
  value = {values[0], values[1], values[2]};
  return true;
}

handle type_caster<delta::Vec3>::cast(const delta::Vec3& vector, return_value_policy, handle) {
  array_t<double> array(3);
  double* data = array.mutable_data();
  data[0] = vector.x;
  data[1] = vector.y;
  data[2] = vector.z;
  return array.release();
}

bool type_caster<delta::Mat3>::load(handle source, bool) {
  double values[9];
  if (!loadFixed(source, {3, 3}, values, "a 3x3 matrix argument")) return false;
  std::copy(values, values + 9, value.entries.begin());
  return true;
}

handle type_caster<delta::Mat3>::cast(const delta::Mat3& matrix, return_value_policy, handle) {
  array_t<double> array({ssize_t{3}, ssize_t{3}});
  for (std::size_t i = 0; i < 9; ++i)
    array.mutable_data()[i] = matrix.entries[i];
  return array.release();
}

}  // namespace pybind11::detail
