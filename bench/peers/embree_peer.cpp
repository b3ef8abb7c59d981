// Embree 3 as the points–mesh peer: closest-point queries (rtcPointQuery) on a triangle scene,
// the way Embree's closest_point tutorial and Open3D's RaycastingScene use them.
#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

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

/// The point-query callback: the exact closest point of triangle primID in double; a closer one
/// shrinks the query radius (returning true tells Embree that it did).
bool closestTriangle(RTCPointQueryFunctionArguments* args) {
  QueryState& state = *static_cast<QueryState*>(args->userPtr);
  const double d =
      std::sqrt(kernels::closestPointOnTriangle(state.point, state.mesh->triangle(args->primID))
                    .distanceSquared);
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
    const std::string config = "threads=" + std::to_string(threads);
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
