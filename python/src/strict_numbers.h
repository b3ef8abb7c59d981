// Scalar number arguments read exactly or refused: pybind11's own casters take a bool as 1, and
// any object with __float__ (numpy.longdouble, fractions.Fraction) as its rounded value. These
// explicit specialisations replace them for double and the integer types the module takes; every
// header of the module includes this one, so that each translation unit sees the same casters
// (a pybind11 header that had used the default ones first would make the specialisation an
// error, not a silent mix).
#pragma once

#include <pybind11/pybind11.h>

#include <limits>
#include <optional>
#include <type_traits>

namespace delta::python {

/// `given` as a double exactly, or nothing where it is not a real number (None, a string, a bool
/// or numpy.bool_, a complex number, a real wider than float64, an object). Taken: float (and
/// numpy.float64), numpy.float16/float32 (widened exactly), int and numpy integers, and a 0-d
/// array of those. Without `convert` only float (pybind11's first pass over the overloads).
/// Throws delta::Error for an integer that float64 does not hold exactly (beyond 2^53 some are
/// not) or that lies beyond float64's range.
std::optional<double> exactReal(pybind11::handle given, bool convert);

/// `given` as an integer within [lowest, highest], or nothing where it is not an integer (a bool,
/// a float, an object; numpy integers and 0-d integer arrays are integers where `convert`) or
/// lies outside that range (pybind11 then tries the next overload, or raises TypeError).
std::optional<long long> exactSigned(pybind11::handle given, bool convert, long long lowest,
                                     long long highest);
std::optional<unsigned long long> exactUnsigned(pybind11::handle given, bool convert,
                                                unsigned long long highest);

/// A truth-value argument: Python's bool or numpy.bool_ only. (pybind11's own caster of bool,
/// which cannot be replaced, takes None as False and 2 or 0.5 as True: the bindings' truth-value
/// parameters are Flags.)
struct Flag {
  bool value = false;
};

}  // namespace delta::python

namespace pybind11::detail {

template <>
class type_caster<delta::python::Flag> {
 public:
  PYBIND11_TYPE_CASTER(delta::python::Flag, const_name("bool"));
  bool load(handle source, bool) {
    if (!source) return false;
    static const handle numpyBool = object(module_::import("numpy").attr("bool_")).release();
    if (!PyBool_Check(source.ptr()) && PyObject_IsInstance(source.ptr(), numpyBool.ptr()) != 1)
      return false;
    value.value = PyObject_IsTrue(source.ptr()) == 1;
    return true;
  }
  static handle cast(delta::python::Flag flag, return_value_policy, handle) {
    return handle(flag.value ? Py_True : Py_False).inc_ref();
  }
};

template <>
class type_caster<double> {
 public:
  PYBIND11_TYPE_CASTER(double, const_name("float"));
  bool load(handle source, bool convert) {
    const std::optional<double> read = delta::python::exactReal(source, convert);
    if (read) value = *read;
    return read.has_value();
  }
  static handle cast(double number, return_value_policy, handle) {
    return PyFloat_FromDouble(number);
  }
};

/// The integer casters of the module's integer types.
template <typename T>
class StrictIntegerCaster {
 public:
  PYBIND11_TYPE_CASTER(T, const_name("int"));
  bool load(handle source, bool convert) {
    if constexpr (std::is_signed_v<T>) {
      const std::optional<long long> read = delta::python::exactSigned(
          source, convert, std::numeric_limits<T>::min(), std::numeric_limits<T>::max());
      if (read) value = static_cast<T>(*read);
      return read.has_value();
    } else {
      const std::optional<unsigned long long> read =
          delta::python::exactUnsigned(source, convert, std::numeric_limits<T>::max());
      if (read) value = static_cast<T>(*read);
      return read.has_value();
    }
  }
  static handle cast(T number, return_value_policy, handle) {
    if constexpr (std::is_signed_v<T>)
      return PyLong_FromLongLong(static_cast<long long>(number));
    else
      return PyLong_FromUnsignedLongLong(static_cast<unsigned long long>(number));
  }
};

template <>
class type_caster<int> : public StrictIntegerCaster<int> {};
template <>
class type_caster<unsigned int> : public StrictIntegerCaster<unsigned int> {};
template <>
class type_caster<long> : public StrictIntegerCaster<long> {};
template <>
class type_caster<unsigned long> : public StrictIntegerCaster<unsigned long> {};
template <>
class type_caster<long long> : public StrictIntegerCaster<long long> {};
template <>
class type_caster<unsigned long long> : public StrictIntegerCaster<unsigned long long> {};

}  // namespace pybind11::detail
