#include "dem_output.h"

#include <cerrno>
#include <cstdint>
#include <string>
#include <system_error>
#include <utility>

#include "delta/core/error.h"

#include "files.h"

namespace delta::cli {
namespace {

void append(io::VtkArray& array, const Vec3& v) {
  array.values.insert(array.values.end(), {v.x, v.y, v.z});
}

/// Every particle's triangles where the particle is, with the velocity of each vertex.
io::VtkPolyData particlesOf(const dem::World& world, std::span<const std::uint32_t> ids) {
  io::VtkPolyData data;
  io::VtkArray velocity{"velocity", 3, {}};
  io::VtkArray particleId{"particle", 1, {}, io::VtkType::UInt32};
  io::VtkArray shapeId{"shape", 1, {}, io::VtkType::UInt32};
  const std::span<const dem::Particle> particles = world.particles();
  for (std::size_t p = 0; p < particles.size(); ++p) {
    const dem::Particle& particle = particles[p];
    const Mesh& mesh = world.shapes()[particle.shape].mesh();
    const RigidTransform pose = particle.pose();
    const auto base = static_cast<std::uint32_t>(data.points.size());
    for (const Vec3& vertex : mesh.vertices()) {
      const Vec3 x = pose.apply(vertex);
      data.points.push_back(x);
      append(velocity, particle.velocity + cross(particle.angularVelocity, x - particle.position));
    }
    for (const TriangleIndices& triangle : mesh.triangles()) {
      data.triangles.push_back({base + triangle[0], base + triangle[1], base + triangle[2]});
      particleId.values.push_back(static_cast<double>(ids.empty() ? p : ids[p]));
      shapeId.values.push_back(static_cast<double>(particle.shape));
    }
  }
  data.pointData = {std::move(velocity)};
  data.cellData = {std::move(particleId), std::move(shapeId)};
  return data;
}

/// Every particle as a point at its centre of mass, with what places its shape there.
io::VtkPolyData statesOf(const dem::World& world, std::span<const std::uint32_t> ids) {
  std::vector<Vec3> points;
  io::VtkArray particleId{"particle", 1, {}, io::VtkType::UInt32};
  io::VtkArray shapeId{"shape", 1, {}, io::VtkType::UInt32};
  io::VtkArray velocity{"velocity", 3, {}}, angularVelocity{"angular_velocity", 3, {}};
  io::VtkArray orientation{"orientation", 4, {}}, boundingRadius{"bounding_radius", 1, {}};
  const std::span<const dem::Particle> particles = world.particles();
  points.reserve(particles.size());
  for (std::size_t p = 0; p < particles.size(); ++p) {
    const dem::Particle& particle = particles[p];
    points.push_back(particle.position);
    particleId.values.push_back(static_cast<double>(ids.empty() ? p : ids[p]));
    shapeId.values.push_back(particle.shape);
    append(velocity, particle.velocity);
    append(angularVelocity, particle.angularVelocity);
    const Quaternion& q = particle.orientation;
    orientation.values.insert(orientation.values.end(), {q.w, q.x, q.y, q.z});
    boundingRadius.values.push_back(world.shapes()[particle.shape].boundingRadius());
  }
  io::VtkPolyData data = io::VtkPolyData::fromPoints(std::move(points));
  data.pointData = {std::move(particleId),      std::move(shapeId),     std::move(velocity),
                    std::move(angularVelocity), std::move(orientation), std::move(boundingRadius)};
  return data;
}

io::VtkPolyData contactsOf(const dem::World& world) {
  std::vector<Vec3> points;
  io::VtkArray force{"force", 3, {}}, direction{"direction", 3, {}};
  io::VtkArray depth{"depth", 1, {}}, distance{"distance", 1, {}};
  io::VtkArray overlap{"overlap", 1, {}, io::VtkType::UInt8};
  io::VtkArray converged{"converged", 1, {}, io::VtkType::UInt8};
  io::VtkArray first{"particle", 1, {}, io::VtkType::UInt32};
  io::VtkArray second{"other", 1, {}, io::VtkType::UInt32};
  io::VtkArray obstacle{"with_obstacle", 1, {}, io::VtkType::UInt8};
  for (const dem::Contact& contact : world.contacts()) {
    points.push_back(contact.point.x);
    append(force, contact.force);
    append(direction, contact.point.direction);
    depth.values.push_back(contact.depth);
    distance.values.push_back(contact.point.distance);
    overlap.values.push_back(contact.point.overlap ? 1.0 : 0.0);
    converged.values.push_back(contact.point.converged ? 1.0 : 0.0);
    first.values.push_back(contact.first);
    second.values.push_back(contact.second);
    obstacle.values.push_back(contact.withObstacle ? 1.0 : 0.0);
  }
  io::VtkPolyData data = io::VtkPolyData::fromPoints(std::move(points));
  data.pointData = {force, direction, depth, distance, overlap, converged, first, second, obstacle};
  return data;
}

/// The obstacles where they are now, with the velocity of each vertex.
io::VtkPolyData obstaclesOf(const dem::World& world) {
  io::VtkPolyData data;
  io::VtkArray velocity{"velocity", 3, {}};
  io::VtkArray obstacleId{"obstacle", 1, {}, io::VtkType::UInt32};
  const std::span<const dem::Obstacle> obstacles = world.obstacles();
  for (std::size_t o = 0; o < obstacles.size(); ++o) {
    const dem::Obstacle& obstacle = obstacles[o];
    const auto base = static_cast<std::uint32_t>(data.points.size());
    for (const Vec3& vertex : obstacle.mesh.vertices()) {
      const Vec3 x = obstacle.pose.apply(vertex);
      data.points.push_back(x);
      append(velocity, obstacle.velocityAt(x));
    }
    for (const TriangleIndices& triangle : obstacle.mesh.triangles()) {
      data.triangles.push_back({base + triangle[0], base + triangle[1], base + triangle[2]});
      obstacleId.values.push_back(static_cast<double>(o));
    }
  }
  data.pointData = {std::move(velocity)};
  data.cellData = {std::move(obstacleId)};
  return data;
}

bool moves(const dem::Obstacle& obstacle) {
  return obstacle.motion.velocity != Vec3{} || obstacle.motion.angularVelocity != Vec3{};
}

}  // namespace

DemOutput::DemOutput(std::filesystem::path directory, DemFrames frames, int piece, int pieces)
    : directory_(std::move(directory)), frames_(frames), piece_(piece), pieces_(pieces) {
  makeOutputFolder(directory_);
}

DemOutput::~DemOutput() {
  if (log_) std::fclose(log_);
}

void DemOutput::begin(const dem::World& world) {
  for (const dem::Obstacle& obstacle : world.obstacles())
    obstaclesMove_ = obstaclesMove_ || moves(obstacle);
  if (piece_ != 0) return;
  if (frames_ != DemFrames::Triangles)
    for (std::size_t k = 0; k < world.shapes().size(); ++k)
      io::writeVtp(io::VtkPolyData::fromMesh(world.shapes()[k].mesh()),
                   directory_ / ("shape_" + std::to_string(k) + ".vtp"));
  io::writeVtp(obstaclesOf(world), directory_ / "obstacles.vtp");
  const std::filesystem::path path = directory_ / "log.csv";
  log_ = std::fopen(path.c_str(), "w");
  if (!log_)
    throw Error("cannot write '" + path.string() + "': " + std::generic_category().message(errno));
  std::fprintf(log_,
               "step,time,kinetic_energy,potential_energy,elastic_energy,total_energy,contacts,"
               "contact_pairs,step_seconds,contact_detection_seconds\n");
  flushLog();
}

void DemOutput::flushLog() {
  errno = 0;
  if (std::fflush(log_) == 0 && !std::ferror(log_)) return;
  const int error = errno;
  std::fclose(log_);
  log_ = nullptr;
  throw Error("writing '" + (directory_ / "log.csv").string() + "' failed: " +
              (error != 0 ? std::generic_category().message(error) : "a write failed"));
}

void DemOutput::log(const dem::World& world) {
  const dem::StepStatistics& statistics = world.statistics();
  const bool stepped = world.stepCount() > 0;
  log(LogRow{world.stepCount(), world.time(), world.energies(), world.contacts().size(),
             statistics.pairsInContact, stepped ? statistics.totalSeconds : 0.0,
             stepped ? statistics.contactDetectionSeconds : 0.0});
}

void DemOutput::log(const LogRow& row) {
  if (!log_) return;
  const dem::Energies& energies = row.energies;
  std::fprintf(log_, "%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%zu,%zu,%.6g,%.6g\n", row.step, row.time,
               energies.kinetic(), energies.gravitational, energies.elastic, energies.total(),
               row.contacts, row.contactPairs, row.stepSeconds, row.contactDetectionSeconds);
  flushLog();  // a row a step: what a run cut short has logged is on disk, and a full disk stops it
}

void DemOutput::frame(const dem::World& part, std::span<const std::uint32_t> ids, double time) {
  const std::size_t frame = frames();
  const auto add = [&](std::vector<io::VtkSeriesEntry>& series, const char* name,
                       const io::VtkPolyData& data, bool pieced) {
    std::string file = frameFileName(name, frame, ".vtp");
    if (pieced && pieces_ > 0) {
      const std::string stem = frameFileName(name, frame, "");
      io::writeVtp(data, directory_ / (stem + "_" + std::to_string(piece_) + ".vtp"));
      if (piece_ != 0) {  // rank 0 keeps the series; the others only count frames
        series.push_back({time, {}});
        return;
      }
      std::vector<std::filesystem::path> pieces;
      for (int k = 0; k < pieces_; ++k)
        pieces.push_back(stem + "_" + std::to_string(k) + ".vtp");
      file = stem + ".pvtp";
      io::writePvtp(data, pieces, directory_ / file);
    } else {
      io::writeVtp(data, directory_ / file);
    }
    series.push_back({time, file});
    io::writePvd(series, directory_ / (std::string(name) + ".pvd"));
  };
  if (frames_ != DemFrames::Triangles)
    add(stateSeries_, "particles_state", statesOf(part, ids), true);
  if (frames_ != DemFrames::State) add(particleSeries_, "particles", particlesOf(part, ids), true);
  add(contactSeries_, "contacts", contactsOf(part), true);
  if (obstaclesMove_ && piece_ == 0) add(obstacleSeries_, "obstacles", obstaclesOf(part), false);
}

void DemOutput::finish() {
  if (!log_) return;
  const bool failed = std::ferror(log_) != 0;
  const int closed = std::fclose(log_);
  log_ = nullptr;
  if (failed || closed != 0)
    throw Error("writing '" + (directory_ / "log.csv").string() + "' failed");
}

}  // namespace delta::cli
