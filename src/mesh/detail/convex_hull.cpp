#include "delta/mesh/detail/convex_hull.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/error.h"

extern "C" {
#include <libqhull_r/libqhull_r.h>
}

namespace delta::detail {
namespace {

/// Owns one qhull run: its own qhT (so concurrent runs share nothing) and an in-memory stream
/// that catches every message qhull writes, so that it never prints.
class QhullRun {
 public:
  QhullRun() : messages_(open_memstream(&buffer_, &bufferSize_)) {
    if (messages_ == nullptr) throw Error("convex hull: cannot open a buffer for qhull's messages");
    QHULL_LIB_CHECK
  }
  QhullRun(const QhullRun&) = delete;
  QhullRun& operator=(const QhullRun&) = delete;
  ~QhullRun() {
    release();
    std::fclose(messages_);
    std::free(buffer_);
  }

  /// Runs qhull on `coordinates` (x, y, z per point, kept alive by the caller) and returns its
  /// exit code: 0 on success.
  int run(std::vector<double>& coordinates, const char* options) {
    release();
    qh_zero(&qh_, messages_);
    std::string command = options;
    const int exitCode =
        qh_new_qhull(&qh_, 3, static_cast<int>(coordinates.size() / 3), coordinates.data(), False,
                     command.data(), nullptr, messages_);
    ran_ = true;
    return exitCode;
  }

  qhT* handle() noexcept { return &qh_; }

  /// The first line qhull wrote, to quote in an error message.
  std::string firstMessage() {
    std::fflush(messages_);
    std::string text = buffer_ == nullptr ? std::string() : std::string(buffer_, bufferSize_);
    const std::size_t end = text.find('\n');
    return end == std::string::npos ? text : text.substr(0, end);
  }

 private:
  void release() noexcept {
    if (!ran_) return;
    int longCount = 0;
    int longBytes = 0;
    qh_freeqhull(&qh_, !qh_ALL);
    qh_memfreeshort(&qh_, &longCount, &longBytes);
    ran_ = false;
  }

  char* buffer_ = nullptr;
  std::size_t bufferSize_ = 0;
  std::FILE* messages_ = nullptr;
  qhT qh_{};
  bool ran_ = false;
};

/// The hull qhull left in `qh`: its vertices, renumbered in input order, and its triangles,
/// counter-clockwise seen from outside.
Mesh hullMesh(qhT* qh, const std::vector<double>& coordinates) {
  const std::size_t pointCount = coordinates.size() / 3;
  std::vector<TriangleIndices> triangles;
  std::vector<std::uint32_t> renumbered(pointCount, 0);
  facetT* facet = nullptr;
  vertexT* vertex = nullptr;
  vertexT** vertexp = nullptr;
  FORALLfacets {
    if (!facet->simplicial || qh_setsize(qh, facet->vertices) != 3)
      throw Error("convex hull: qhull returned a facet that is not a triangle");
    TriangleIndices t{};
    std::size_t k = 0;
    FOREACHvertex_(facet->vertices) {
      t[k++] = static_cast<std::uint32_t>(qh_pointid(qh, vertex->point));
    }
    // qhull's vertex sets are sorted by id, not oriented: toporient says which of the two
    // orders is which. qh_facet3vertex keeps the set's order when toporient ^ qh_ORIENTclock;
    // that order turns clockwise seen from outside (its right-hand normal is opposite to
    // facet->normal, checked on every facet of hulls with and without merged facets), so
    // counter-clockwise is the other one.
    if (facet->toporient ^ qh_ORIENTclock) std::swap(t[0], t[1]);
    for (std::uint32_t index : t)
      renumbered[index] = 1;
    triangles.push_back(t);
  }
  std::vector<Vec3> vertices;
  for (std::size_t i = 0; i < pointCount; ++i)
    if (renumbered[i] != 0) {
      renumbered[i] = static_cast<std::uint32_t>(vertices.size());
      vertices.push_back({coordinates[3 * i], coordinates[3 * i + 1], coordinates[3 * i + 2]});
    }
  for (TriangleIndices& t : triangles)
    for (std::uint32_t& index : t)
      index = renumbered[index];
  return Mesh(std::move(vertices), std::move(triangles));
}

}  // namespace

Mesh convexHull(std::span<const Vec3> points) {
  if (points.size() < 4)
    throw Error("convex hull: " + std::to_string(points.size()) +
                " points, fewer than the 4 a solid needs");
  if (points.size() > static_cast<std::size_t>(std::numeric_limits<int>::max()))
    throw Error("convex hull: " + std::to_string(points.size()) + " points, more than qhull takes");
  std::vector<double> coordinates;
  coordinates.reserve(3 * points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!isFinite(points[i]))
      throw Error("convex hull: point " + std::to_string(i) + " is not finite");
    coordinates.insert(coordinates.end(), {points[i].x, points[i].y, points[i].z});
  }
  // 'Qt' triangulates facets that qhull merged (coplanar points); if qhull still reports a
  // precision problem, 'QJ' joggles the input, which always gives simplicial facets. Flat input
  // (qh_ERRsingular) is not retried: joggling it would invent a hull of rounding-error width.
  QhullRun qhull;
  int exitCode = qhull.run(coordinates, "qhull Qt");
  if (exitCode == qh_ERRprec) exitCode = qhull.run(coordinates, "qhull QJ");
  if (exitCode != 0)
    throw Error("convex hull: qhull failed (exit code " + std::to_string(exitCode) +
                "): " + qhull.firstMessage());
  return hullMesh(qhull.handle(), coordinates);
}

}  // namespace delta::detail
