#include "delta/core/mat3.h"

#include <cmath>

namespace delta {

double orthonormalityError(const Mat3& m) noexcept {
  const Mat3 gram = m.transposed() * m;
  double worst = 0.0;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      worst = std::fmax(worst, std::fabs(gram(r, c) - (r == c ? 1.0 : 0.0)));
  return worst;
}

}  // namespace delta
