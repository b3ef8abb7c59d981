#include "arrays.h"

#include <string>

#include "delta/core/error.h"

namespace delta::python {

namespace {

/// Numbers NumPy converts to float64 without losing meaning: integers and reals (not booleans,
/// complex numbers, strings or objects).
bool realNumbers(const py::array& array) {
  const char kind = array.dtype().kind();
  return kind == 'i' || kind == 'u' || kind == 'f';
}

std::string shapeOf(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t axis = 0; axis < array.ndim(); ++axis)
    text += (axis ? ", " : "") + std::to_string(array.shape(axis));
  return text + (array.ndim() == 1 ? ",)" : ")");
}

}  // namespace

DoubleArray pointArray(const ArrayLike& argument, const char* what, bool exactlyTwoAxes) {
  const py::array given = py::array::ensure(argument.object);
  if (!given || !realNumbers(given))
    throw Error(std::string(what) + " must be an array of real numbers" +
                (given ? ", not of dtype " + py::str(given.dtype()).cast<std::string>() : ""));
  const bool shaped = exactlyTwoAxes ? given.ndim() == 2 && given.shape(1) == 3
                                     : given.ndim() >= 1 && given.shape(given.ndim() - 1) == 3;
  if (!shaped)
    throw Error(std::string(what) + " must have shape " + (exactlyTwoAxes ? "(n, 3)" : "(..., 3)") +
                ", not " + shapeOf(given));
  DoubleArray points = DoubleArray::ensure(given);
  if (!points) throw Error(std::string(what) + ": conversion to float64 failed");
  return points;
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

/// `source` as a float64 array of the given shape, or a null array (no exception) when it is not
/// one: strings, objects NumPy cannot convert, another shape.
array_t<double, array::c_style | array::forcecast> fixedArray(
    handle source, std::initializer_list<ssize_t> shape) {
  using Result = array_t<double, array::c_style | array::forcecast>;
  if (!source || source.is_none() || isinstance<str>(source) || isinstance<bytes>(source))
    return Result();
  const array given = array::ensure(source);
  if (!given) return Result();
  const char kind = given.dtype().kind();
  if (kind != 'i' && kind != 'u' && kind != 'f') return Result();
  if (given.ndim() != static_cast<ssize_t>(shape.size())) return Result();
  ssize_t axis = 0;
  for (const ssize_t extent : shape)
    if (given.shape(axis++) != extent) return Result();
  return Result::ensure(given);
}

}  // namespace

bool type_caster<delta::Vec3>::load(handle source, bool) {
  const auto array = fixedArray(source, {3});
  if (!array) return false;
  const double* data = array.data();
  value = {data[0], data[1], data[2]};
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
  const auto array = fixedArray(source, {3, 3});
  if (!array) return false;
  for (std::size_t i = 0; i < 9; ++i)
    value.entries[i] = array.data()[i];
  return true;
}

handle type_caster<delta::Mat3>::cast(const delta::Mat3& matrix, return_value_policy, handle) {
  array_t<double> array({ssize_t{3}, ssize_t{3}});
  for (std::size_t i = 0; i < 9; ++i)
    array.mutable_data()[i] = matrix.entries[i];
  return array.release();
}

}  // namespace pybind11::detail
