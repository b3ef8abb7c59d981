// CGAL's AABB tree as the points–mesh peer: closest-point queries on a tree of triangles with the
// KD-tree of hints that accelerate_distance_queries() builds, as CGAL's AABB_tree manual shows.
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <CGAL/version.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

#include "peers.h"

namespace delta::bench {
namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Point = Kernel::Point_3;
using Triangles = std::vector<Kernel::Triangle_3>;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, Triangles::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point point(const Vec3& v) {
  return {v.x, v.y, v.z};
}

class CgalPeer final : public PointDistancePeer {
 public:
  explicit CgalPeer(const Mesh& mesh) {
    const std::size_t heapBefore = heapBytesInUse();
    const auto start = std::chrono::steady_clock::now();
    triangles_.reserve(mesh.triangleCount());
    for (std::size_t t = 0; t < mesh.triangleCount(); ++t) {
      const Triangle corners = mesh.triangle(t);
      triangles_.emplace_back(point(corners.a), point(corners.b), point(corners.c));
    }
    tree_.rebuild(triangles_.begin(), triangles_.end());
    tree_.accelerate_distance_queries();
    buildSeconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const std::size_t heapAfter = heapBytesInUse();
    bytes_ = heapAfter > heapBefore ? heapAfter - heapBefore : 0;
  }

  double buildSeconds() const noexcept override { return buildSeconds_; }
  std::size_t memoryBytes() const noexcept override { return bytes_; }
  const char* memoryMethod() const noexcept override { return "heap growth over the build"; }

  void distances(std::span<const Vec3> points, double radius,
                 std::span<double> out) const override {
    constexpr double kInfinity = std::numeric_limits<double>::infinity();
    if (std::isinf(radius)) {
      parallelOverPoints(points.size(), [&](std::size_t i) {
        out[i] = std::sqrt(tree_.squared_distance(point(points[i])));
      });
      return;
    }
    parallelOverPoints(points.size(), [&](std::size_t i) {
      const Vec3& p = points[i];
      const CGAL::Bbox_3 cube(p.x - radius, p.y - radius, p.z - radius, p.x + radius, p.y + radius,
                              p.z + radius);
      out[i] = kInfinity;
      if (!tree_.do_intersect(cube)) return;
      const double d = std::sqrt(tree_.squared_distance(point(p)));
      if (d < radius) out[i] = d;
    });
  }

 private:
  Triangles triangles_;
  Tree tree_;
  double buildSeconds_ = 0.0;
  std::size_t bytes_ = 0;
};

}  // namespace

std::unique_ptr<PointDistancePeer> makeCgalPeer(const Mesh& mesh) {
  return std::make_unique<CgalPeer>(mesh);
}

const char* cgalVersion() noexcept {
  return CGAL_VERSION_STR;
}

}  // namespace delta::bench
