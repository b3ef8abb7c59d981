#include "delta/mesh/bounding_sphere.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <string>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"

namespace delta {
namespace {

/// A ball in the local frame (coordinates relative to the point set's box centre).
struct Ball {
  Vec3 center;
  double radiusSquared = -1.0;  ///< negative: the empty ball, which contains nothing

  bool contains(const Vec3& p) const noexcept {
    return distanceSquared(p, center) <= radiusSquared;
  }
};

/// Below this sine-like measure of affine independence a support set is treated as degenerate:
/// its circumsphere would be dominated by rounding (collinear or coplanar points).
constexpr double kIndependence = 1e-10;

/// The points Welzl's algorithm keeps on the ball's boundary (at most 4 in 3-space), with the
/// smallest ball through each prefix of them: its centre lies in their affine hull.
class SupportSet {
 public:
  std::size_t size() const noexcept { return size_; }
  const Ball& ball() const noexcept { return balls_[size_]; }
  void pop() noexcept { --size_; }

  /// Adds `p` to the boundary; false (and nothing changes) when `p` is numerically affinely
  /// dependent on the boundary points, so that their circumsphere would not be meaningful.
  bool push(const Vec3& p) noexcept {
    Ball ball;
    const Vec3 origin = size_ == 0 ? p : points_[0];
    if (size_ == 0) {
      ball.center = p;
    } else if (size_ == 1) {
      ball.center = (origin + p) * 0.5;
    } else if (size_ == 2) {
      const Vec3 a = points_[1] - origin;
      const Vec3 b = p - origin;
      const Vec3 normal = cross(a, b);
      const double normalSquared = lengthSquared(normal);
      if (!(normalSquared > kIndependence * kIndependence * lengthSquared(a) * lengthSquared(b)))
        return false;
      ball.center =
          origin + (lengthSquared(a) * cross(b, normal) + lengthSquared(b) * cross(normal, a)) /
                       (2.0 * normalSquared);
    } else {
      const Vec3 a = points_[1] - origin;
      const Vec3 b = points_[2] - origin;
      const Vec3 d = p - origin;
      const double volume = dot(a, cross(b, d));
      if (!(std::fabs(volume) > kIndependence * length(a) * length(b) * length(d))) return false;
      ball.center = origin + (lengthSquared(a) * cross(b, d) + lengthSquared(b) * cross(d, a) +
                              lengthSquared(d) * cross(a, b)) /
                                 (2.0 * volume);
    }
    if (!isFinite(ball.center)) return false;
    // The largest distance to a boundary point, so that every one of them is inside as computed.
    ball.radiusSquared = distanceSquared(p, ball.center);
    for (std::size_t i = 0; i < size_; ++i)
      ball.radiusSquared = std::max(ball.radiusSquared, distanceSquared(points_[i], ball.center));
    points_[size_] = p;
    balls_[++size_] = ball;
    return true;
  }

 private:
  std::array<Vec3, 4> points_{};
  std::array<Ball, 5> balls_{};
  std::size_t size_ = 0;
};

/// Welzl's minimal enclosing ball of points[0, end) with the support set on its boundary, with
/// Gärtner's move-to-front heuristic ("Fast and robust smallest enclosing balls", 1999).
/// Recursion depth is at most 4, whatever the number of points.
Ball moveToFront(std::vector<Vec3>& points, std::size_t end, SupportSet& support) {
  Ball ball = support.ball();
  if (support.size() == 4) return ball;
  for (std::size_t i = 0; i < end; ++i) {
    if (ball.contains(points[i]) || !support.push(points[i])) continue;
    ball = moveToFront(points, i, support);
    support.pop();
    std::rotate(points.begin(), points.begin() + static_cast<std::ptrdiff_t>(i),
                points.begin() + static_cast<std::ptrdiff_t>(i) + 1);
  }
  return ball;
}

/// Projections of `p` on 13 directions: 3 axes, 6 face diagonals, 4 body diagonals (unnormalised;
/// written out, as multiplying by 0 and 1 cannot be optimised away under IEEE rules). The extreme
/// points along them seed the support search, as in Larsson's EPOS-26 ("Fast and tight fitting
/// bounding spheres", 2008).
constexpr std::size_t kDirections = 13;

inline std::array<double, kDirections> projections(const Vec3& p) noexcept {
  const double xy = p.x + p.y;
  const double xMinusY = p.x - p.y;
  return {p.x,       p.y,       p.z,      xy,       xMinusY,       p.x + p.z,    p.x - p.z,
          p.y + p.z, p.y - p.z, xy + p.z, xy - p.z, xMinusY + p.z, xMinusY - p.z};
}

/// The extreme points of the set along the 13 directions, and its box.
struct ExtremePoints {
  std::vector<std::size_t> indices;  ///< sorted, without repeats
  Aabb box;
};

/// One pass over the points: checks that each is finite and finds the extreme ones (the three
/// axes among the directions give the box). Projections are taken relative to the first point,
/// so that far from the origin they still tell nearby points apart.
ExtremePoints findExtremePoints(std::span<const Vec3> points) {
  const Vec3 reference = points[0];
  if (!isFinite(reference))
    throw Error("boundingSphere: point 0 is not finite: " + toString(reference));
  std::array<std::size_t, kDirections> highest{};
  std::array<std::size_t, kDirections> lowest{};
  std::array<double, kDirections> high{};
  std::array<double, kDirections> low{};
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (!isFinite(points[i]))
      throw Error("boundingSphere: point " + std::to_string(i) +
                  " is not finite: " + toString(points[i]));
    const std::array<double, kDirections> along = projections(points[i] - reference);
    for (std::size_t k = 0; k < kDirections; ++k) {
      if (along[k] > high[k]) high[k] = along[k], highest[k] = i;
      if (along[k] < low[k]) low[k] = along[k], lowest[k] = i;
    }
  }
  ExtremePoints extremes;
  for (std::size_t axis = 0; axis < 3; ++axis) {
    extremes.box.lower[axis] = points[lowest[axis]][axis];
    extremes.box.upper[axis] = points[highest[axis]][axis];
  }
  extremes.indices.assign(highest.begin(), highest.end());
  extremes.indices.insert(extremes.indices.end(), lowest.begin(), lowest.end());
  std::sort(extremes.indices.begin(), extremes.indices.end());
  extremes.indices.erase(std::unique(extremes.indices.begin(), extremes.indices.end()),
                         extremes.indices.end());
  return extremes;
}

}  // namespace

// The exact minimal ball of a small active set, grown by the farthest point until every point is
// inside (Gärtner's pivoting, restricted to the active set): the active set starts with the
// extreme points along 13 directions and each round adds the point farthest from the current
// ball, so a few O(n) rounds give the minimal ball to rounding. A cap on the rounds keeps it
// O(n) for adversarial input, with Ritter's growth pass as a fallback; last, the radius is set to
// the largest distance as `Sphere::contains` computes it, plus a few ulps, so containment holds
// whatever the rounding along the way.
Sphere boundingSphere(std::span<const Vec3> points) {
  if (points.empty()) throw Error("boundingSphere: the point set is empty");
  const ExtremePoints extremes = findExtremePoints(points);
  const Aabb& box = extremes.box;
  // Work relative to the box centre so that far from the origin the support computations keep
  // their digits (points near 1e9 with a spread of 1).
  const Vec3 origin = box.lower * 0.5 + box.upper * 0.5;
  // A set so small that squared distances would underflow (below about 1e-120 across) is worked
  // on scaled up by a power of two, which is exact; elsewhere nothing is scaled.
  const double extent = maxAbs(box.extent());
  const int exponent = extent > 0.0 && extent < 0x1p-400 ? -std::ilogb(extent) : 0;
  const auto local = [&](std::size_t i) { return ldexp(points[i] - origin, exponent); };

  std::vector<Vec3> active;
  for (std::size_t i : extremes.indices)
    active.push_back(local(i));

  constexpr int kMaxRounds = 64;
  constexpr double kConverged = 1.0 + 1e-10;  // relative gap in squared radius worth a round
  Ball ball;
  bool converged = false;
  for (int round = 0; round < kMaxRounds && !converged; ++round) {
    SupportSet support;
    const Ball next = moveToFront(active, active.size(), support);
    // No growth means the point added last was rejected as degenerate (it lies on the ball to
    // rounding): keep the ball and let the final pass absorb the difference.
    if (!(next.radiusSquared > ball.radiusSquared)) break;
    ball = next;
    std::size_t farthest = 0;
    double farthestSquared = -1.0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double d = distanceSquared(local(i), ball.center);
      if (d > farthestSquared) farthestSquared = d, farthest = i;
    }
    converged = farthestSquared <= ball.radiusSquared * kConverged;
    active.push_back(local(farthest));
  }
  if (!converged) {
    // Out of rounds, or stalled: Ritter's growth pass moves the centre towards each point still
    // outside, just enough to reach it.
    double radius = std::sqrt(std::max(ball.radiusSquared, 0.0));
    for (std::size_t i = 0; i < points.size(); ++i) {
      const Vec3 p = local(i);
      const double d = distance(p, ball.center);
      if (d <= radius) continue;
      const double grown = 0.5 * (radius + d);
      ball.center += (p - ball.center) * ((grown - radius) / d);
      radius = grown;
    }
  }

  // The radius: each point's distance, at scale (accurate), and as `Sphere::contains` computes
  // it, unscaled: for a set below about 1e-154 across its squares are subnormal and round by up
  // to 1e-4 of the distance (an audit: 162 of 200 sets 1e-160 across had a point that contains()
  // refused), so the radius takes the larger.
  Sphere sphere{origin + ldexp(ball.center, -exponent), 0.0};
  for (const Vec3& p : points)
    sphere.radius =
        std::max({sphere.radius, std::ldexp(length(ldexp(p - sphere.center, exponent)), -exponent),
                  distance(p, sphere.center)});
  sphere.radius *= 1.0 + 4.0 * std::numeric_limits<double>::epsilon();
  if (!isFinite(sphere.center) || !std::isfinite(sphere.radius))
    throw Error("boundingSphere: the points span " + toString(box.lower) + " to " +
                toString(box.upper) +
                ", too far apart for Sphere::contains (squared distances overflow a double "
                "from about 1.3e154)");
  return sphere;
}

Sphere boundingSphere(const Mesh& mesh) {
  return boundingSphere(mesh.vertices());
}

}  // namespace delta
