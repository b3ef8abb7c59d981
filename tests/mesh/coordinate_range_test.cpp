// The coordinate range (mesh/coordinate_range.h): its checks and messages, and the mesh measures
// that rescale by powers of two instead (answers for any finite mesh, or an error where the
// answer itself is beyond a double).
#include "delta/mesh/coordinate_range.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/mesh/mass_properties.h"
#include "delta/mesh/measures.h"
#include "delta/mesh/primitives.h"
#include "delta/mesh/triangle_soa.h"

#include "core/expect_error.h"
#include "mesh/tetrahedron.h"

namespace delta {
namespace {

TEST(CoordinateRange, ChecksAndMessages) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(inCoordinateRange({kLargestCoordinate, -kLargestCoordinate, 0}));
  EXPECT_FALSE(inCoordinateRange({std::nextafter(kLargestCoordinate, 1e300), 0, 0}));
  EXPECT_FALSE(inCoordinateRange({0, nan, 0}));  // maxAbs would skip the NaN
  EXPECT_FALSE(inCoordinateRange({0, 0, -INFINITY}));
  EXPECT_EQ(magnitude(Aabb{}), 0.0);
  EXPECT_EQ(magnitude(Aabb{{-3, 1, 2}, {1, 2, 2.5}}), 3.0);
  EXPECT_TRUE(std::isnan(magnitude(Aabb{{nan, 0, 0}, {1, 1, 1}})));
  checkMeshScale(Aabb{{-1, -1, -1}, {1, 1, 1}}, "unit");
  expectErrorSaying(
      [] {
        checkCoordinateRange(Aabb{{0, 0, 0}, {1e61, 1, 1}}, "the box");
      },
      {"the box reaches a coordinate of 9.9999999999999995e+60",
       "±2^200 (1.6069380442589903e+60)"});
  expectErrorSaying(
      [] {
        checkMeshScale(Aabb{{0, 0, 0}, {1e-61, 0, 0}}, "the mesh");
      },
      {"the mesh lies within ", "e-61 of the origin", "2^-200"});
  expectErrorSaying([] { checkMeshScale(Aabb{{0, 0, 0}, {0, 0, 0}}, "a point"); }, {"2^-200"});
  expectErrorSaying(
      [] {
        checkPointRange({1e155, 0, 0}, "point 7");
      },
      {"point 7 (1e+155, 0, 0) has a coordinate beyond ±2^200"});
  // A flattened mesh's box: its triangles, not the padding; NaN where a coordinate is NaN.
  const TriangleSoA soa(kTetra);
  EXPECT_EQ(boundsOf(soa).lower, (Vec3{0, 0, 0}));
  EXPECT_EQ(boundsOf(soa).upper, (Vec3{1, 1, 1}));
  TriangleSoA bad;
  bad.assign(std::vector<Triangle>{{{0, 0, 0}, {1, 0, 0}, {nan, 1, 0}}});
  expectErrorSaying([&] { checkMeshScale(bad, "bad"); }, {"bad reaches a coordinate of nan"});
}

TEST(CoordinateRange, MeasuresRescaleAndAnswerOrRefuse) {
  // Mesh(V·1e300, T).volume was NaN (degree-3 products overflowed, ∞ − ∞).
  expectErrorSaying([&] { signedVolume(scaled(kTetra, 1e300)); }, {"signedVolume", "overflows"});
  expectErrorSaying([&] { massProperties(scaled(kTetra, 1e300)); }, {"massProperties", "volume"});
  expectErrorSaying([&] { surfaceArea(scaled(kTetra, 1e300)); }, {"surfaceArea", "overflows"});
  expectErrorSaying([&] { signedVolume(scaled(kTetra, 1e-300)); }, {"underflows"});
  // Scaled by powers of two the answers scale exactly, far beyond what plain products hold
  // (area at 2⁴⁰⁰: the cross products' squares overflowed to +∞ before).
  const Mesh sphere = primitives::icosphere(2);
  const double area = surfaceArea(sphere), volume = signedVolume(sphere);
  const MassProperties mass = massProperties(sphere, 3.0);
  for (const int exponent : {-320, -150, 60, 200, 300, 400}) {
    const Mesh moved = scaled(sphere, std::ldexp(1.0, exponent));
    EXPECT_EQ(surfaceArea(moved), std::ldexp(area, 2 * exponent)) << exponent;
    if (std::abs(3 * exponent) < 1000) {
      EXPECT_EQ(signedVolume(moved), std::ldexp(volume, 3 * exponent)) << exponent;
    }
    if (std::abs(5 * exponent) <= 1000) {
      const MassProperties m = massProperties(moved, 3.0);
      EXPECT_EQ(m.volume, std::ldexp(mass.volume, 3 * exponent)) << exponent;
      EXPECT_EQ(m.inertia(0, 0), std::ldexp(mass.inertia(0, 0), 5 * exponent)) << exponent;
      EXPECT_EQ(m.centroid, mass.centroid * std::ldexp(1.0, exponent)) << exponent;
    } else if (std::abs(5 * exponent) >= 1100) {
      EXPECT_THROW(massProperties(moved, 3.0), Error) << exponent;  // the inertia
    }
  }
}

TEST(CoordinateRange, EdgeLengthsRescale) {
  // A square of edge 1e200 is 1e400 (+∞): the lengths were +∞.
  const EdgeLengths unit = edgeLengths(kTetra);
  const EdgeLengths far = edgeLengths(scaled(kTetra, 0x1p700));
  EXPECT_EQ(far.max, std::ldexp(unit.max, 700));
  EXPECT_EQ(far.min, std::ldexp(unit.min, 700));
  EXPECT_EQ(edgeLengths(scaled(kTetra, 0x1p-1000)).max, std::ldexp(unit.max, -1000));
  const Mesh widest({{-1.5e308, 0, 0}, {1.5e308, 0, 0}, {0, 1, 0}}, {{0, 1, 2}});
  expectErrorSaying([&] { edgeLengths(widest); }, {"edgeLengths", "overflows"});
}

}  // namespace
}  // namespace delta
