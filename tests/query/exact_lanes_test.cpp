// The exact point–triangle kernel in lanes (query/detail/exact_lanes.h: AVX-512's eight, AVX2's
// four, NEON's two; each ISA's point table), against the scalar kernel, bit for bit, on random and
// adversarial triangles and points: slivers, needles, zero-area and repeated-vertex triangles,
// points on vertices, edges and faces and just off them, just beyond a needle's tip, far points,
// coordinates far from the origin and tiny triangles.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "delta/kernels/isa.h"
#include "delta/kernels/point_triangle.h"
#include "delta/mesh/mesh.h"
#include "delta/query/query_mesh.h"

#include "kernels/triangle_pairs.h"
#include "query/detail/point_kernels.h"

namespace delta::detail {
namespace {

/// Triangles of every awkward shape, at `scale` around `centre`.
std::vector<Triangle> awkwardTriangles(std::mt19937_64& random, const Vec3& centre, double scale) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto any = [&] { return centre + Vec3{unit(random), unit(random), unit(random)} * scale; };
  std::vector<Triangle> triangles;
  for (int i = 0; i < 40; ++i) {
    const Vec3 a = any(), b = any(), c = any();
    triangles.push_back({a, b, c});                                                 // random
    triangles.push_back({a, b, a + (b - a) * 0.3 + Vec3{1e-9, -2e-9, 0} * scale});  // sliver
    triangles.push_back({a, b, a + (b - a) * 0.7});                                 // collinear
    triangles.push_back({a, a + (b - a) * 1e-7, c});                                // needle
    triangles.push_back({a, a, c});                                                 // repeated
    triangles.push_back({a, a, a});                                                 // a point
    triangles.push_back({a, b, a + (c - a) * 1e-12});                               // thin
    // A needle whose third corner lies off its middle: points beyond its tips project within
    // rounding of both edges' lines there (the face test's bound).
    triangles.push_back({a, b, (a + b) * 0.5 + cross(b - a, c - a) * (1e-12 / scale)});
    triangles.push_back({a, {a.x, a.y, c.z}, {b.x, a.y, c.z}});  // axis-aligned
  }
  return triangles;
}

/// Points near and far from `triangles`, on and just off their features.
std::vector<Vec3> probes(std::mt19937_64& random, const std::vector<Triangle>& triangles,
                         const Vec3& centre, double scale) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  std::vector<Vec3> points;
  // A quarter of the points under the sanitizers (where the test otherwise takes 14 s).
  const int count = test::kSlowBuild ? 16 : 64;
  for (int i = 0; i < count; ++i) {
    points.push_back(centre + Vec3{unit(random), unit(random), unit(random)} * (2.0 * scale));
    points.push_back(centre + Vec3{unit(random), unit(random), unit(random)} * (300.0 * scale));
  }
  for (std::size_t t = 0; t < triangles.size(); t += test::kSlowBuild ? 20 : 5) {
    const Triangle& x = triangles[t];
    const Vec3 normal = x.areaVector();
    const double length = std::sqrt(lengthSquared(normal));
    const Vec3 up = length > 0.0 ? normal * (1.0 / length) : Vec3{0, 0, 1};
    for (const Vec3& on : {x.a, x.b, (x.a + x.b) * 0.5, x.centroid(), x.a + (x.a - x.c) * 0.5,
                           x.b + (x.b - x.a) * 1e-11})
      for (const double offset : {0.0, 1e-15, 1e-9, 1e-3, 1.0})
        points.push_back(on + up * (offset * scale));
  }
  return points;
}

/// The eight-lane kernel's squared distances against the scalar kernel's, for every run of up to
/// eight triangles of the prepared mesh and every point.
using Exact8 = void (*)(const QueryMeshData&, const Vec3&, const std::uint32_t*, std::size_t,
                        double*) noexcept;

void expectSameBits(const std::vector<Triangle>& triangles, const std::vector<Vec3>& points,
                    Exact8 exactDistancesSquared8) {
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> indices;
  for (const Triangle& t : triangles) {
    const auto first = static_cast<std::uint32_t>(vertices.size());
    vertices.insert(vertices.end(), {t.a, t.b, t.c});
    indices.push_back({first, first + 1, first + 2});
  }
  const QueryMesh query(Mesh(vertices, indices));
  const QueryMeshData& data = query.data();
  std::vector<std::uint32_t> sorted(data.size());
  for (std::uint32_t k = 0; k < sorted.size(); ++k)
    sorted[k] = k;
  std::size_t compared = 0;
  for (const Vec3& point : points)
    for (std::size_t first = 0; first < sorted.size(); first += 8) {
      // Runs of 8 and, at every seventh start, of fewer (the lanes beyond are padding).
      const std::size_t count =
          std::min<std::size_t>(first % 7 == 0 ? 3 : 8, sorted.size() - first);
      double lanes[8];
      exactDistancesSquared8(data, point, sorted.data() + first, count, lanes);
      for (std::size_t i = 0; i < count; ++i) {
        const double scalar =
            kernels::closestPointOnTriangle(point, data.triangle(sorted[first + i]))
                .distanceSquared;
        ASSERT_EQ(std::bit_cast<std::uint64_t>(lanes[i]), std::bit_cast<std::uint64_t>(scalar))
            << "point (" << point.x << ", " << point.y << ", " << point.z << "), triangle "
            << first + i << ": " << lanes[i] << " against " << scalar;
        ++compared;
      }
    }
  EXPECT_GT(compared, points.size() * triangles.size() / 2);
}

/// Every lane of `exact` against the scalar kernel on the awkward triangles and probes.
void expectEveryLaneIsTheScalarKernel(Exact8 exact) {
  std::mt19937_64 random(41);
  for (const Vec3& centre :
       {Vec3{0, 0, 0}, Vec3{1e3, -2e3, 5e2}, Vec3{1e6, 3e6, -2e6}, Vec3{-4e9, 1e9, 7e9}})
    for (const double scale : {1.0, 1e-6, 1e3}) {
      SCOPED_TRACE("centre x " + std::to_string(centre.x) + ", scale " + std::to_string(scale));
      const std::vector<Triangle> triangles = awkwardTriangles(random, centre, scale);
      expectSameBits(triangles, probes(random, triangles, centre, scale), exact);
    }
}

TEST(ExactLanes, EveryLaneOfEveryIsaIsTheScalarKernelBitForBit) {
  std::size_t tested = 0;
  for (const kernels::Isa isa : kernels::supportedIsas()) {
    const Exact8 exact = pointKernels(isa).exact;
    if (!exact) continue;  // no lanes: the scalar kernel itself
    SCOPED_TRACE(kernels::name(isa));
    expectEveryLaneIsTheScalarKernel(exact);
    ++tested;
  }
#if defined(__AVX2__) || defined(__aarch64__)
  EXPECT_GT(tested, 0u);  // built for a CPU with lanes: they ran
#endif
  if (tested == 0) GTEST_SKIP() << "no ISA with exact lanes on this CPU";
}

}  // namespace
}  // namespace delta::detail
