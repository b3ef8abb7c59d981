#include "soup_builder.h"

#include <cmath>
#include <limits>

#include "delta/core/error.h"

namespace delta::detail {
namespace {

constexpr std::size_t kEarClippingLimit = 4096;

/// A corner's position in the polygon's plane.
struct Point2 {
  double u = 0.0;
  double v = 0.0;
};

/// Twice the signed area of (a, b, c); positive for a left turn.
double turn(const Point2& a, const Point2& b, const Point2& c) noexcept {
  return (b.u - a.u) * (c.v - a.v) - (b.v - a.v) * (c.u - a.u);
}

bool samePoint(const Point2& a, const Point2& b) noexcept {
  return a.u == b.u && a.v == b.v;
}

/// Whether `p` lies in the closed triangle (a, b, c), which turns left.
bool inTriangle(const Point2& p, const Point2& a, const Point2& b, const Point2& c) noexcept {
  return turn(a, b, p) >= 0 && turn(b, c, p) >= 0 && turn(c, a, p) >= 0;
}

void fan(std::span<const std::uint32_t> corners, std::vector<TriangleIndices>& out) {
  for (std::size_t i = 1; i + 1 < corners.size(); ++i)
    out.push_back({corners[0], corners[i], corners[i + 1]});
}

/// The Newell normal of the polygon: its area vector, zero when its corners are on one line.
Vec3 newellNormal(std::span<const Vec3> vertices, std::span<const std::uint32_t> corners) {
  Vec3 normal;
  const Vec3 origin = vertices[corners[0]];
  for (std::size_t i = 1; i + 1 < corners.size(); ++i)
    normal += cross(vertices[corners[i]] - origin, vertices[corners[i + 1]] - origin);
  return normal;
}

/// The corners projected on the plane of the two axes other than the normal's largest, mirrored
/// where needed so that the polygon turns left (counter-clockwise) seen along the normal.
std::vector<Point2> project(std::span<const Vec3> vertices, std::span<const std::uint32_t> corners,
                            const Vec3& normal) {
  const double ax = std::abs(normal.x), ay = std::abs(normal.y), az = std::abs(normal.z);
  const int drop = ax >= ay && ax >= az ? 0 : (ay >= az ? 1 : 2);
  const int uAxis = (drop + 1) % 3, vAxis = (drop + 2) % 3;
  const double sign = normal[static_cast<std::size_t>(drop)] < 0 ? -1.0 : 1.0;
  std::vector<Point2> points;
  points.reserve(corners.size());
  for (const std::uint32_t corner : corners) {
    const Vec3& p = vertices[corner];
    points.push_back(
        {p[static_cast<std::size_t>(uAxis)], sign * p[static_cast<std::size_t>(vAxis)]});
  }
  return points;
}

bool isConvex(const std::vector<Point2>& points) {
  const std::size_t n = points.size();
  for (std::size_t i = 0; i < n; ++i)
    if (turn(points[(i + n - 1) % n], points[i], points[(i + 1) % n]) < 0) return false;
  return true;
}

/// Ear clipping (Meisters' two-ears theorem; O(n²) here: each cut searches from the start).
void clipEars(std::span<const std::uint32_t> corners, const std::vector<Point2>& points,
              std::vector<TriangleIndices>& out) {
  std::vector<std::size_t> left(corners.size());
  for (std::size_t i = 0; i < left.size(); ++i)
    left[i] = i;
  const auto isEar = [&](std::size_t at) {
    const std::size_t m = left.size();
    const Point2& a = points[left[(at + m - 1) % m]];
    const Point2& b = points[left[at]];
    const Point2& c = points[left[(at + 1) % m]];
    if (turn(a, b, c) <= 0) return false;  // reflex or straight: not an ear
    for (std::size_t k = 0; k < m; ++k) {
      const Point2& p = points[left[k]];
      if (samePoint(p, a) || samePoint(p, b) || samePoint(p, c)) continue;
      if (inTriangle(p, a, b, c)) return false;
    }
    return true;
  };
  while (left.size() > 3) {
    std::size_t ear = 0;
    while (ear < left.size() && !isEar(ear))
      ++ear;
    if (ear == left.size()) break;  // self-intersecting: fan what is left
    const std::size_t m = left.size();
    out.push_back(
        {corners[left[(ear + m - 1) % m]], corners[left[ear]], corners[left[(ear + 1) % m]]});
    left.erase(left.begin() + static_cast<std::ptrdiff_t>(ear));
  }
  std::vector<std::uint32_t> rest;
  rest.reserve(left.size());
  for (const std::size_t i : left)
    rest.push_back(corners[i]);
  fan(rest, out);
}

}  // namespace

void triangulatePolygon(std::span<const Vec3> vertices, std::span<const std::uint32_t> corners,
                        std::vector<TriangleIndices>& out) {
  if (corners.size() == 3) {
    out.push_back({corners[0], corners[1], corners[2]});
    return;
  }
  const Vec3 normal = newellNormal(vertices, corners);
  if (corners.size() > kEarClippingLimit || !isFinite(normal) || normal == Vec3{})
    return fan(corners, out);
  const std::vector<Point2> points = project(vertices, corners, normal);
  if (isConvex(points)) return fan(corners, out);
  clipEars(corners, points, out);
}

void SoupBuilder::addFace(std::span<const std::uint32_t> corners) {
  if (corners.size() == 1) return addPoints(1);
  if (corners.size() == 2) return addLines(1);
  if (corners.size() < 3) return;
  anyFace_ = true;
  triangulatePolygon(vertices_, corners, triangles_);
  if (!meshHasTriangles_) ++statistics_.meshes;
  meshHasTriangles_ = true;
}

TriangleSoup SoupBuilder::finish(bool pointsIfNoFaces) {
  TriangleSoup soup;
  soup.statistics = statistics_;
  if (!anyFace_ && pointsIfNoFaces) soup.statistics.pointsSkipped += vertices_.size();
  constexpr std::uint32_t kUnused = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> newIndex(vertices_.size(), kUnused);
  for (const TriangleIndices& triangle : triangles_)
    for (const std::uint32_t corner : triangle)
      newIndex[corner] = 0;
  std::uint32_t used = 0;
  for (std::uint32_t& index : newIndex)
    if (index != kUnused) index = used++;
  soup.positions.reserve(used);
  for (std::size_t v = 0; v < vertices_.size(); ++v)
    if (newIndex[v] != kUnused) soup.positions.push_back(vertices_[v]);
  soup.triangles = std::move(triangles_);
  for (TriangleIndices& triangle : soup.triangles)
    for (std::uint32_t& corner : triangle)
      corner = newIndex[corner];
  soup.statistics.sourceVertices = soup.positions.size();
  soup.statistics.precision = io::CoordinatePrecision::exact;
  return soup;
}

}  // namespace delta::detail
