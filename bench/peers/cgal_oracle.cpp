// The exact oracle for the agreement checks' disputes: the tests' CGAL oracle
// (tests/kernels/exact_distance.h), independent of Δ's kernels.
#include <cmath>

#include "../../tests/kernels/exact_distance.h"
#include "peers.h"

namespace delta::bench {

double exactDistance(const Vec3& p, const Triangle& triangle) {
  return std::sqrt(test::exactSquaredDistance(p, triangle));
}

double exactDistance(const Triangle& first, const Triangle& second) {
  return std::sqrt(test::exactSquaredDistance(first, second));
}

bool exactIntersect(const Triangle& first, const Triangle& second) {
  return test::exactIntersect(first, second);
}

}  // namespace delta::bench
