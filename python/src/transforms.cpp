#include "transforms.h"

#include <pybind11/numpy.h>

#include "delta/core/error.h"
#include "delta/core/mat3.h"

#include "arrays.h"

namespace delta::python {

RigidTransform fromHomogeneous(py::handle matrix, const std::string& what) {
  const RealArray given = realArray(matrix);
  if (!given.problem.empty()) throw py::type_error(what + " " + given.problem);
  if (given.array.ndim() != 2 || given.array.shape(0) != 4 || given.array.shape(1) != 4)
    throw Error(what + " must have shape (4, 4), not " + shapeOf(given.array));
  requireExactIntegers(given.array, what.c_str());
  const DoubleArray values = DoubleArray::ensure(given.array);
  requireFinite({values.data(), 16}, what.c_str());
  const double* m = values.data();
  if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0)
    throw Error(what + ": the last row must be (0, 0, 0, 1)");
  Mat3 rotation;
  for (int row = 0; row < 3; ++row)
    for (int column = 0; column < 3; ++column)
      rotation(row, column) = m[4 * row + column];
  try {
    return {Quaternion::fromMatrix(rotation), {m[3], m[7], m[11]}};
  } catch (const Error& error) {
    throw Error(what + ": " + error.what());
  }
}

}  // namespace delta::python
