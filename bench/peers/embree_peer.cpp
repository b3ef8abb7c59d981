// Embree 3 as the points–mesh peer: closest-point queries (rtcPointQuery) on a triangle scene,
// the way Embree's closest_point tutorial and Open3D's RaycastingScene use them, with the
// textbook closest-point kernel in double in the callback. (Δ's own robust kernel there made
// W1 on armadillo 2.0–2.5 times slower: 9.7–12.0 s against 4.8; the peer runs as fast as Embree
// allows.)
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <string_view>

#include "delta/kernels/point_triangle.h"

#include "peers.h"

namespace delta::bench {
namespace {

/// The smallest float not below `value` (the query radius must never cull what a double compare
/// would keep).
float roundUp(double value) noexcept {
  float rounded = static_cast<float>(value);
  if (static_cast<double>(rounded) < value)
    rounded = std::nextafter(rounded, std::numeric_limits<float>::infinity());
  return rounded;
}

/// One query's state, reached from the callback through userPtr.
struct QueryState {
  const Mesh* mesh;
  Vec3 point;     ///< the query point in double (Embree's copy is float)
  double best;    ///< the least distance found, or the initial radius
  double margin;  ///< added to the radius Embree culls with (see EmbreePeer::margin_)
};

/// The squared distance from `p` to triangle abc by the textbook kernel an Embree user writes in
/// the callback (Ericson, Real-Time Collision Detection, 5.1.5: Voronoi regions of the vertices,
/// then of the edges, then the face), in double; NaN for a triangle of zero area whose face test
/// divides by zero (the caller then asks Δ's kernel, which handles it).
double textbookDistanceSquared(const Vec3& p, const Triangle& t) noexcept {
  const Vec3 ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0.0 && d2 <= 0.0) return lengthSquared(ap);
  const Vec3 bp = p - t.b;
  const double d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0.0 && d4 <= d3) return lengthSquared(bp);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return lengthSquared(ap - ab * (d1 / (d1 - d3)));
  const Vec3 cp = p - t.c;
  const double d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0.0 && d5 <= d6) return lengthSquared(cp);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return lengthSquared(ap - ac * (d2 / (d2 - d6)));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0)
    return lengthSquared(bp - (t.c - t.b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6))));
  const double denominator = 1.0 / (va + vb + vc);
  return lengthSquared(ap - ab * (vb * denominator) - ac * (vc * denominator));
}

/// The point-query callback: the closest point of triangle primID in double (the textbook
/// kernel; Δ's where that gives no number); a closer one shrinks the query radius (returning
/// true tells Embree that it did).
bool closestTriangle(RTCPointQueryFunctionArguments* args) {
  QueryState& state = *static_cast<QueryState*>(args->userPtr);
  const Triangle triangle = state.mesh->triangle(args->primID);
  double squared = textbookDistanceSquared(state.point, triangle);
  if (!std::isfinite(squared))
    squared = kernels::closestPointOnTriangle(state.point, triangle).distanceSquared;
  const double d = std::sqrt(squared);
  if (!(d < state.best)) return false;
  state.best = d;
  args->query->radius = roundUp(d + state.margin);
  return true;
}

bool countMemory(void* counter, ssize_t bytes, bool /*post*/) {
  static_cast<std::atomic<long long>*>(counter)->fetch_add(bytes, std::memory_order_relaxed);
  return true;
}

void check(RTCDevice device, const char* what) {
  const RTCError error = rtcGetDeviceError(device);
  if (error != RTC_ERROR_NONE)
    throw std::runtime_error(std::string("Embree: ") + what + " failed (error " +
                             std::to_string(static_cast<int>(error)) + ")");
}

class EmbreePeer final : public PointDistancePeer {
 public:
  EmbreePeer(const Mesh& mesh, int threads) : mesh_(mesh) {
    // Embree picks the widest ISA the CPU has; DELTA_ISA (which lowers Δ's, kernels/isa.h)
    // lowers Embree's the same way, so that both run at, say, AVX2 on this machine.
    std::string config = "threads=" + std::to_string(threads);
    if (const char* isa = std::getenv("DELTA_ISA"); isa && *isa)
      config += std::string(",max_isa=") + (std::string_view(isa) == "avx512" ? "avx512"
                                            : std::string_view(isa) == "avx2" ? "avx2"
                                                                              : "sse2");
    device_ = rtcNewDevice(config.c_str());
    if (!device_) throw std::runtime_error("Embree: rtcNewDevice(\"" + config + "\") failed");
    rtcSetDeviceMemoryMonitorFunction(device_, countMemory, &allocated_);
    allocated_.store(0);
    const auto start = std::chrono::steady_clock::now();

    // Float vertices, padded by one float: Embree reads the last vertex with a 16-byte load.
    vertices_.resize(mesh.vertexCount() * 3 + 1, 0.0f);
    double roundingError = 0.0, scale = 0.0;
    for (std::size_t v = 0; v < mesh.vertexCount(); ++v) {
      const Vec3& p = mesh.vertices()[v];
      for (std::size_t axis = 0; axis < 3; ++axis) {
        const float rounded = static_cast<float>(p[axis]);
        vertices_[3 * v + axis] = rounded;
        roundingError = std::max(roundingError, std::abs(p[axis] - static_cast<double>(rounded)));
        scale = std::max(scale, std::abs(p[axis]));
      }
    }
    indices_.reserve(mesh.triangleCount() * 3);
    for (const TriangleIndices& t : mesh.triangles())
      indices_.insert(indices_.end(), {t[0], t[1], t[2]});
    // Embree culls nodes by the float query point and float radius against float boxes of the
    // float vertices. The radius it culls with is the best double distance plus this margin:
    // the vertices' rounding (0 for meshes read through assimp, which are float already), the
    // query point's rounding and the culling test's (a few ulps of the coordinates), so no
    // triangle the double comparison would keep is ever culled.
    margin_ = 2.0 * std::sqrt(3.0) * roundingError + 0x1p-20 * scale;
    scale_ = scale;

    scene_ = rtcNewScene(device_);
    // Embree's default: RTC_BUILD_QUALITY_HIGH measured the same queries (W1 4.90 s against
    // 4.91, W2 0.092 against 0.095 on armadillo) at five times the build.
    rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
    RTCGeometry geometry = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                               vertices_.data(), 0, 3 * sizeof(float), mesh.vertexCount());
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                               indices_.data(), 0, 3 * sizeof(unsigned), mesh.triangleCount());
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene_, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene_);
    check(device_, "rtcCommitScene");
    buildSeconds_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  }

  ~EmbreePeer() override {
    if (scene_) rtcReleaseScene(scene_);
    rtcReleaseDevice(device_);
  }
  EmbreePeer(const EmbreePeer&) = delete;
  EmbreePeer& operator=(const EmbreePeer&) = delete;

  double buildSeconds() const noexcept override { return buildSeconds_; }
  std::size_t memoryBytes() const noexcept override {
    const long long monitored = allocated_.load();
    return static_cast<std::size_t>(std::max(0LL, monitored)) + vertices_.size() * sizeof(float) +
           indices_.size() * sizeof(unsigned);
  }
  const char* memoryMethod() const noexcept override {
    return "device memory monitor + user buffers";
  }

  void distances(std::span<const Vec3> points, double radius,
                 std::span<double> out) const override {
    constexpr double kInfinity = std::numeric_limits<double>::infinity();
    parallelOverPoints(points.size(), [&](std::size_t i) {
      const Vec3& p = points[i];
      const double pointScale = std::max({std::abs(p.x), std::abs(p.y), std::abs(p.z)});
      QueryState state{&mesh_, p, radius, margin_ + 0x1p-20 * std::max(0.0, pointScale - scale_)};
      RTCPointQuery query;
      query.x = static_cast<float>(p.x);
      query.y = static_cast<float>(p.y);
      query.z = static_cast<float>(p.z);
      query.time = 0.0f;
      query.radius = std::isinf(radius) ? std::numeric_limits<float>::infinity()
                                        : roundUp(radius + state.margin);
      RTCPointQueryContext context;
      rtcInitPointQueryContext(&context);
      rtcPointQuery(scene_, &query, &context, closestTriangle, &state);
      out[i] = state.best < radius ? state.best : kInfinity;
    });
  }

 private:
  const Mesh& mesh_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::atomic<long long> allocated_{0};
  std::vector<float> vertices_;
  std::vector<unsigned> indices_;
  double margin_ = 0.0;
  double scale_ = 0.0;
  double buildSeconds_ = 0.0;
};

}  // namespace

std::unique_ptr<PointDistancePeer> makeEmbreePeer(const Mesh& mesh, int threads) {
  return std::make_unique<EmbreePeer>(mesh, threads);
}

const char* embreeVersion() noexcept {
  return RTC_VERSION_STRING;
}

}  // namespace delta::bench
