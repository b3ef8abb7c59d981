#include "delta/mesh/primitives.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/memory.h"
#include "delta/mesh/detail/convex_hull.h"

namespace delta::primitives {
namespace {

/// What a granulate needs a point, as an estimate: the sample, its hull vertex and two
/// triangles, and qhull's facets, ridges and vertex records (a few hundred bytes a point).
constexpr double kGranulateBytesPerPoint = 512.0;

[[noreturn]] void fail(const char* primitive, const std::string& what) {
  throw Error(std::string("primitives::") + primitive + ": " + what);
}

void requirePositive(const char* primitive, const char* parameter, double value) {
  if (!(std::isfinite(value) && value > 0.0))
    fail(primitive,
         std::string(parameter) + " " + toString(value) + " must be finite and positive");
}

void requirePositive(const char* primitive, const char* parameter, const Vec3& value) {
  if (!(isFinite(value) && value.x > 0.0 && value.y > 0.0 && value.z > 0.0))
    fail(primitive,
         std::string(parameter) + " " + toString(value) + " must be finite and positive");
}

void requireFinite(const char* primitive, const char* parameter, const Vec3& value) {
  if (!isFinite(value))
    fail(primitive, std::string(parameter) + " " + toString(value) + " is not finite");
}

/// The regular icosahedron on the unit sphere, faces counter-clockwise seen from outside.
void unitIcosahedron(std::vector<Vec3>& vertices, std::vector<TriangleIndices>& triangles) {
  const double phi = std::numbers::phi;
  vertices = {{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
              {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
              {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}};
  for (Vec3& v : vertices)
    v = normalized(v);
  triangles = {{0, 11, 5},  {0, 5, 1},  {0, 1, 7},  {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
               {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
               {3, 8, 9},   {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
}

/// Splits every triangle into four at its edge midpoints, pushed out onto the unit sphere. Each
/// edge's midpoint is made once (cached by its vertex pair), so neighbours share it.
void subdivide(std::vector<Vec3>& vertices, std::vector<TriangleIndices>& triangles) {
  std::unordered_map<std::uint64_t, std::uint32_t> midpoints;
  midpoints.reserve(triangles.size() * 3 / 2);
  const auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
    const std::uint64_t key = (std::uint64_t{std::min(a, b)} << 32) | std::max(a, b);
    const auto [slot, inserted] =
        midpoints.try_emplace(key, static_cast<std::uint32_t>(vertices.size()));
    if (inserted) vertices.push_back(normalized(vertices[a] + vertices[b]));
    return slot->second;
  };
  std::vector<TriangleIndices> finer;
  finer.reserve(4 * triangles.size());
  for (const TriangleIndices& t : triangles) {
    const std::uint32_t ab = midpoint(t[0], t[1]);
    const std::uint32_t bc = midpoint(t[1], t[2]);
    const std::uint32_t ca = midpoint(t[2], t[0]);
    finer.push_back({t[0], ab, ca});
    finer.push_back({t[1], bc, ab});
    finer.push_back({t[2], ca, bc});
    finer.push_back({ab, bc, ca});
  }
  triangles = std::move(finer);
}

/// A uniform double in [0, 1) from the top 53 bits of one 64-bit draw: the same on every
/// standard library, unlike std::uniform_real_distribution.
double unitInterval(std::mt19937_64& random) {
  return static_cast<double>(random() >> 11) * 0x1.0p-53;
}

/// A uniformly distributed unit vector, by Marsaglia's method ("Choosing a point from the surface
/// of a sphere", 1972): only +, ×, √, so bit-identical wherever IEEE arithmetic is.
Vec3 randomDirection(std::mt19937_64& random) {
  for (;;) {
    const double u = 2.0 * unitInterval(random) - 1.0;
    const double v = 2.0 * unitInterval(random) - 1.0;
    const double s = u * u + v * v;
    if (s >= 1.0) continue;
    const double scale = 2.0 * std::sqrt(1.0 - s);
    return {u * scale, v * scale, 1.0 - 2.0 * s};
  }
}

}  // namespace

Mesh icosphere(int subdivisions, double radius, const Vec3& center) {
  if (subdivisions < 0 || subdivisions > kMaxIcosphereSubdivisions)
    fail("icosphere", "subdivisions " + std::to_string(subdivisions) + " is outside 0–" +
                          std::to_string(kMaxIcosphereSubdivisions));
  requirePositive("icosphere", "radius", radius);
  requireFinite("icosphere", "center", center);
  std::vector<Vec3> vertices;
  std::vector<TriangleIndices> triangles;
  unitIcosahedron(vertices, triangles);
  for (int level = 0; level < subdivisions; ++level)
    subdivide(vertices, triangles);
  for (Vec3& v : vertices)
    v = center + v * radius;
  return Mesh(std::move(vertices), std::move(triangles));
}

Mesh box(const Vec3& size, const Vec3& center) {
  requirePositive("box", "size", size);
  requireFinite("box", "center", center);
  // Corner i has coordinate bits (x, y, z) = (i & 1, i >> 1 & 1, i >> 2 & 1).
  std::vector<Vec3> vertices;
  for (int i = 0; i < 8; ++i)
    vertices.push_back(center + Vec3{((i & 1) - 0.5) * size.x, (((i >> 1) & 1) - 0.5) * size.y,
                                     (((i >> 2) & 1) - 0.5) * size.z});
  std::vector<TriangleIndices> triangles = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5},
                                            {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},
                                            {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
  return Mesh(std::move(vertices), std::move(triangles));
}

Mesh cylinder(double radius, double height, int segments, const Vec3& center) {
  requirePositive("cylinder", "radius", radius);
  requirePositive("cylinder", "height", height);
  if (segments < 3)
    fail("cylinder", "segments " + std::to_string(segments) + " must be at least 3");
  // The vertices and triangles, checked before they are allocated (2n + 2 would wrap in 32 bits
  // from n = 2³¹ − 1).
  const double bytes = static_cast<double>(segments) * kCylinderBytesPerSegment;
  if (segments > kMaxCylinderSegments)
    fail("cylinder", "segments " + std::to_string(segments) + " is above the limit " +
                         std::to_string(kMaxCylinderSegments) +
                         " (4·segments triangles with 32-bit ids); it would need about " +
                         describeBytes(bytes) + " of memory");
  requireMemory(bytes, "primitives::cylinder: segments " + std::to_string(segments));
  requireFinite("cylinder", "center", center);
  const auto n = static_cast<std::uint32_t>(segments);
  // Vertices: bottom ring 0…n−1, top ring n…2n−1, bottom centre 2n, top centre 2n+1.
  std::vector<Vec3> vertices(2 * n + 2);
  for (std::uint32_t k = 0; k < n; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / n;
    const double x = radius * std::cos(angle);
    const double y = radius * std::sin(angle);
    vertices[k] = center + Vec3{x, y, -0.5 * height};
    vertices[n + k] = center + Vec3{x, y, 0.5 * height};
  }
  vertices[2 * n] = center + Vec3{0, 0, -0.5 * height};
  vertices[2 * n + 1] = center + Vec3{0, 0, 0.5 * height};
  std::vector<TriangleIndices> triangles;
  triangles.reserve(4 * n);
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::uint32_t next = (k + 1) % n;
    triangles.push_back({2 * n, next, k});
    triangles.push_back({2 * n + 1, n + k, n + next});
    triangles.push_back({k, next, n + next});
    triangles.push_back({k, n + next, n + k});
  }
  return Mesh(std::move(vertices), std::move(triangles));
}

Mesh quad(double sizeX, double sizeY, const Vec3& center) {
  requirePositive("quad", "sizeX", sizeX);
  requirePositive("quad", "sizeY", sizeY);
  requireFinite("quad", "center", center);
  const double hx = 0.5 * sizeX;
  const double hy = 0.5 * sizeY;
  std::vector<Vec3> vertices = {center + Vec3{-hx, -hy, 0}, center + Vec3{hx, -hy, 0},
                                center + Vec3{hx, hy, 0}, center + Vec3{-hx, hy, 0}};
  return Mesh(std::move(vertices), {{0, 1, 2}, {0, 2, 3}});
}

Mesh granulate(std::uint64_t seed, const Vec3& semiAxes, int points) {
  requirePositive("granulate", "semiAxes", semiAxes);
  if (points < 4) fail("granulate", "points " + std::to_string(points) + " must be at least 4");
  requireMemory(static_cast<double>(points) * kGranulateBytesPerPoint,
                "primitives::granulate: points " + std::to_string(points));
  std::mt19937_64 random(seed);
  std::vector<Vec3> samples(static_cast<std::size_t>(points));
  for (Vec3& p : samples) {
    const Vec3 direction = randomDirection(random);
    p = {semiAxes.x * direction.x, semiAxes.y * direction.y, semiAxes.z * direction.z};
  }
  try {
    return detail::convexHull(samples);
  } catch (const Error& error) {
    fail("granulate", "seed " + std::to_string(seed) + ", semiAxes " + toString(semiAxes) +
                          ", points " + std::to_string(points) + ": " + error.what());
  }
}

}  // namespace delta::primitives
