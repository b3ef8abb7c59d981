#include "records.h"

#include <cstddef>
#include <cstring>
#include <optional>
#include <string>
#include <type_traits>

#include "delta/core/contact_point.h"
#include "delta/query/point_distance.h"

#include "arrays.h"

namespace delta::python {

namespace {

static_assert(std::is_standard_layout_v<ContactPoint> &&
              std::is_trivially_copyable_v<ContactPoint>);
static_assert(std::is_standard_layout_v<contactdetection::PointDistance> &&
              std::is_trivially_copyable_v<contactdetection::PointDistance>);
static_assert(sizeof(bool) == 1, "NumPy's bool is one byte");

constexpr const char* kContactNames[] = {"x",       "normal",    "direction",  "distance",
                                         "overlap", "converged", "triangle_a", "triangle_b"};
constexpr const char* kContactFormats[] = {"(3,)f8", "(3,)f8", "(3,)f8", "f8",
                                           "?",      "?",      "u4",     "u4"};
constexpr std::size_t kContactOffsets[] = {
    offsetof(ContactPoint, x),         offsetof(ContactPoint, normal),
    offsetof(ContactPoint, direction), offsetof(ContactPoint, distance),
    offsetof(ContactPoint, overlap),   offsetof(ContactPoint, converged),
    offsetof(ContactPoint, first),     offsetof(ContactPoint, second)};

}  // namespace

py::list contactFieldNames() {
  py::list names;
  for (const char* name : kContactNames)
    names.append(name);
  return names;
}

py::list contactFieldFormats() {
  py::list formats;
  for (const char* format : kContactFormats)
    formats.append(format);
  return formats;
}

py::list contactFieldOffsets(std::size_t offset) {
  py::list offsets;
  for (const std::size_t field : kContactOffsets)
    offsets.append(offset + field);
  return offsets;
}

py::dtype contactDtype() {
  return py::dtype(contactFieldNames(), contactFieldFormats(), contactFieldOffsets(0),
                   static_cast<py::ssize_t>(sizeof(ContactPoint)));
}

void clearPadding(std::span<contactdetection::PointDistance> records) noexcept {
  using contactdetection::PointDistance;
  constexpr std::size_t kUsed = offsetof(PointDistance, ambiguous) + sizeof(bool);
  static_assert(kUsed <= sizeof(PointDistance));
  for (PointDistance& record : records)
    std::memset(reinterpret_cast<unsigned char*>(&record) + kUsed, 0,
                sizeof(PointDistance) - kUsed);
}

py::dtype distanceDtype() {
  using contactdetection::PointDistance;
  return recordDtype({{"distance", "f8", offsetof(PointDistance, distance)},
                      {"closest", "(3,)f8", offsetof(PointDistance, closest)},
                      {"triangle", "u4", offsetof(PointDistance, triangle)},
                      {"inside", "?", offsetof(PointDistance, inside)},
                      {"ambiguous", "?", offsetof(PointDistance, ambiguous)}},
                     sizeof(PointDistance));
}

contactdetection::Sign signNamed(const std::string& name) {
  if (const std::optional<contactdetection::Sign> sign = contactdetection::parseSign(name))
    return *sign;
  throw py::value_error("sign must be \"pseudonormal\" or \"winding\", not \"" + name + "\"");
}

}  // namespace delta::python
