// NumPy record types laid over Δ's result structs, so that Δ's answers are NumPy arrays without
// conversion: a vector of contact points becomes a structured array by handing over its buffer.
#pragma once

#include <pybind11/numpy.h>

#include <cstddef>
#include <span>
#include <string>

#include "delta/query/point_distance.h"

#include "strict_numbers.h"

namespace delta::python {

namespace py = pybind11;

/// delta.contact_dtype, over delta::ContactPoint: x, normal, direction ((3,) float64 each),
/// distance (float64), overlap (bool), triangle_a, triangle_b (uint32).
py::dtype contactDtype();

/// delta.distance_dtype, over contactdetection::PointDistance: distance (float64), closest
/// ((3,) float64), triangle (uint32), inside (bool), ambiguous (bool).
py::dtype distanceDtype();
/// Zeros the padding bytes after `ambiguous` in each record, which the queries' struct copies
/// leave as they find them: so that the arrays' bytes (tobytes, hashes) are a function of the
/// answers alone.
void clearPadding(std::span<contactdetection::PointDistance> records) noexcept;

/// The sign mode named `name` ("pseudonormal" or "winding"); ValueError for any other.
contactdetection::Sign signNamed(const std::string& name);

/// The fields of contact_dtype at `offset` in a larger record (DEM contacts hold a contact point).
py::list contactFieldNames();
py::list contactFieldFormats();
py::list contactFieldOffsets(std::size_t offset);

}  // namespace delta::python
