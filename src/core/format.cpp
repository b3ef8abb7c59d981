#include "delta/core/format.h"

#include <sstream>

namespace delta {

std::string toString(const Vec3& v) {
  std::ostringstream text;
  text.precision(17);
  text << "(" << v.x << ", " << v.y << ", " << v.z << ")";
  return text.str();
}

std::string toString(double value) {
  std::ostringstream text;
  text.precision(17);
  text << value;
  return text.str();
}

}  // namespace delta
