#include "strict_numbers.h"

#include <cmath>
#include <string>

#include "delta/core/error.h"

namespace delta::python {

namespace py = pybind11;

namespace {

/// NumPy's scalar type `name` (numpy is loaded with the module), kept for the process.
py::handle numpyType(const char* name) {
  return py::object(py::module_::import("numpy").attr(name)).release();
}

bool isInstance(py::handle given, py::handle type) {
  return PyObject_IsInstance(given.ptr(), type.ptr()) == 1;
}

/// A 0-d NumPy array's element as a NumPy scalar (`given` itself otherwise).
py::object unwrapped(py::handle given) {
  static const py::handle ndarray = numpyType("ndarray");
  if (isInstance(given, ndarray) &&
      py::reinterpret_borrow<py::object>(given).attr("ndim").cast<py::ssize_t>() == 0)
    return py::reinterpret_borrow<py::object>(given)[py::tuple()];
  return py::reinterpret_borrow<py::object>(given);
}

/// Python's bool or numpy.bool_: NumPy and Python would read them as 0 or 1.
bool isBoolean(py::handle given) {
  static const py::handle numpyBool = numpyType("bool_");
  return PyBool_Check(given.ptr()) || isInstance(given, numpyBool);
}

/// An int or a NumPy integer as a Python int (a new reference), or null.
py::object asInteger(py::handle given) {
  static const py::handle numpyInteger = numpyType("integer");
  if (isBoolean(given)) return {};
  if (!PyLong_Check(given.ptr()) && !isInstance(given, numpyInteger)) return {};
  PyObject* index = PyNumber_Index(given.ptr());
  if (index == nullptr) {
    PyErr_Clear();
    return {};
  }
  return py::reinterpret_steal<py::object>(index);
}

}  // namespace

std::optional<double> exactReal(py::handle given, bool convert) {
  if (!given) return std::nullopt;
  if (PyFloat_Check(given.ptr())) return PyFloat_AsDouble(given.ptr());  // numpy.float64 too
  if (!convert) return std::nullopt;
  const py::object item = unwrapped(given);
  if (PyFloat_Check(item.ptr())) return PyFloat_AsDouble(item.ptr());
  static const py::handle numpyFloating = numpyType("floating");
  if (isInstance(item, numpyFloating)) {
    if (item.attr("dtype").attr("itemsize").cast<py::ssize_t>() > 8) return std::nullopt;
    const double value = PyFloat_AsDouble(item.ptr());  // float16, float32: exact
    if (value == -1.0 && PyErr_Occurred()) {
      PyErr_Clear();
      return std::nullopt;
    }
    return value;
  }
  const py::object integer = asInteger(item);
  if (!integer) return std::nullopt;
  int overflow = 0;
  const long long whole = PyLong_AsLongLongAndOverflow(integer.ptr(), &overflow);
  if (overflow == 0 && whole >= -(1LL << 53) && whole <= (1LL << 53))
    return static_cast<double>(whole);
  // Beyond 2^53 only some integers are float64s (2^60 is): those that come back unchanged.
  const double rounded = PyLong_AsDouble(integer.ptr());
  if (rounded == -1.0 && PyErr_Occurred())
    PyErr_Clear();  // beyond float64's range
  else if (const py::object back = py::reinterpret_steal<py::object>(PyLong_FromDouble(rounded));
           back && PyObject_RichCompareBool(back.ptr(), integer.ptr(), Py_EQ) == 1)
    return rounded;
  PyErr_Clear();
  throw Error("the integer " + py::str(integer).cast<std::string>() +
              " is not a float64 exactly (beyond 2^53): it would be rounded; pass a float");
}

std::optional<long long> exactSigned(py::handle given, bool convert, long long lowest,
                                     long long highest) {
  if (!given) return std::nullopt;
  const py::object integer =
      asInteger(convert ? unwrapped(given) : py::reinterpret_borrow<py::object>(given));
  if (!integer) return std::nullopt;
  int overflow = 0;
  const long long value = PyLong_AsLongLongAndOverflow(integer.ptr(), &overflow);
  if (overflow != 0 || (value == -1 && PyErr_Occurred())) {
    PyErr_Clear();
    return std::nullopt;
  }
  if (value < lowest || value > highest) return std::nullopt;
  return value;
}

std::optional<unsigned long long> exactUnsigned(py::handle given, bool convert,
                                                unsigned long long highest) {
  if (!given) return std::nullopt;
  const py::object integer =
      asInteger(convert ? unwrapped(given) : py::reinterpret_borrow<py::object>(given));
  if (!integer) return std::nullopt;
  const int negative = PyObject_RichCompareBool(integer.ptr(), py::int_(0).ptr(), Py_LT);
  if (negative != 0) {
    if (negative < 0) PyErr_Clear();
    return std::nullopt;
  }
  const unsigned long long value = PyLong_AsUnsignedLongLong(integer.ptr());
  if (value == static_cast<unsigned long long>(-1) && PyErr_Occurred()) {
    PyErr_Clear();
    return std::nullopt;
  }
  if (value > highest) return std::nullopt;
  return value;
}

}  // namespace delta::python
