#include "dem_output.h"

#include <cstdint>
#include <string>
#include <utility>

#include "delta/core/error.h"

#include "files.h"

namespace delta::cli {
namespace {

void append(io::VtkArray& array, const Vec3& v) {
  array.values.insert(array.values.end(), {v.x, v.y, v.z});
}

/// Every particle's triangles where the particle is, with the velocity of each vertex.
io::VtkPolyData particlesOf(const dem::World& world) {
  io::VtkPolyData data;
  io::VtkArray velocity{"velocity", 3, {}}, particleId{"particle", 1, {}}, shapeId{"shape", 1, {}};
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
      particleId.values.push_back(static_cast<double>(p));
      shapeId.values.push_back(static_cast<double>(particle.shape));
    }
  }
  data.pointData = {std::move(velocity)};
  data.cellData = {std::move(particleId), std::move(shapeId)};
  return data;
}

io::VtkPolyData contactsOf(const dem::World& world) {
  std::vector<Vec3> points;
  io::VtkArray force{"force", 3, {}}, direction{"direction", 3, {}};
  io::VtkArray depth{"depth", 1, {}}, distance{"distance", 1, {}}, overlap{"overlap", 1, {}};
  io::VtkArray first{"particle", 1, {}}, second{"other", 1, {}}, obstacle{"with_obstacle", 1, {}};
  for (const dem::Contact& contact : world.contacts()) {
    points.push_back(contact.point.x);
    append(force, contact.force);
    append(direction, contact.point.direction);
    depth.values.push_back(contact.depth);
    distance.values.push_back(contact.point.distance);
    overlap.values.push_back(contact.point.overlap ? 1.0 : 0.0);
    first.values.push_back(contact.first);
    second.values.push_back(contact.second);
    obstacle.values.push_back(contact.withObstacle ? 1.0 : 0.0);
  }
  io::VtkPolyData data = io::VtkPolyData::fromPoints(std::move(points));
  data.pointData = {force, direction, depth, distance, overlap, first, second, obstacle};
  return data;
}

/// The obstacles where they are now, with the velocity of each vertex.
io::VtkPolyData obstaclesOf(const dem::World& world) {
  io::VtkPolyData data;
  io::VtkArray velocity{"velocity", 3, {}}, obstacleId{"obstacle", 1, {}};
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

DemOutput::DemOutput(std::filesystem::path directory) : directory_(std::move(directory)) {
  makeOutputFolder(directory_);
}

DemOutput::~DemOutput() {
  if (log_) std::fclose(log_);
}

void DemOutput::begin(const dem::World& world) {
  io::writeVtp(obstaclesOf(world), directory_ / "obstacles.vtp");
  for (const dem::Obstacle& obstacle : world.obstacles())
    obstaclesMove_ = obstaclesMove_ || moves(obstacle);
  const std::filesystem::path path = directory_ / "log.csv";
  log_ = std::fopen(path.c_str(), "w");
  if (!log_) throw Error("cannot write '" + path.string() + "'");
  std::fprintf(log_,
               "step,time,kinetic_energy,potential_energy,elastic_energy,total_energy,contacts,"
               "contact_pairs,step_seconds,contact_detection_seconds\n");
}

void DemOutput::log(const dem::World& world) {
  const dem::Energies energies = world.energies();
  const dem::StepStatistics& statistics = world.statistics();
  std::fprintf(log_, "%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%zu,%zu,%.6g,%.6g\n", world.stepCount(),
               world.time(), energies.kinetic(), energies.gravitational, energies.elastic,
               energies.total(), world.contacts().size(), statistics.pairsInContact,
               world.stepCount() > 0 ? statistics.totalSeconds : 0.0,
               world.stepCount() > 0 ? statistics.contactDetectionSeconds : 0.0);
}

void DemOutput::frame(const dem::World& world) {
  const std::size_t frame = frames();
  const auto add = [&](std::vector<io::VtkSeriesEntry>& series, const char* name,
                       const io::VtkPolyData& data) {
    const std::string file = frameFileName(name, frame, ".vtp");
    io::writeVtp(data, directory_ / file);
    series.push_back({world.time(), file});
    io::writePvd(series, directory_ / (std::string(name) + ".pvd"));
  };
  add(particleSeries_, "particles", particlesOf(world));
  add(contactSeries_, "contacts", contactsOf(world));
  if (obstaclesMove_) add(obstacleSeries_, "obstacles", obstaclesOf(world));
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
