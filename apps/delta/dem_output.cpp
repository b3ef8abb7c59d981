#include "dem_output.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <system_error>
#include <utility>

#include "delta/core/error.h"
#include "delta/io/atomic_file.h"

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
  io::VtkArray couple{"couple", 3, {}}, volume{"volume", 1, {}};  // the volume law's (else 0)
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
    append(couple, contact.couple);
    volume.values.push_back(contact.volume);
    distance.values.push_back(contact.point.distance);
    overlap.values.push_back(contact.point.overlap ? 1.0 : 0.0);
    converged.values.push_back(contact.point.converged ? 1.0 : 0.0);
    first.values.push_back(contact.first);
    second.values.push_back(contact.second);
    obstacle.values.push_back(contact.withObstacle ? 1.0 : 0.0);
  }
  io::VtkPolyData data = io::VtkPolyData::fromPoints(std::move(points));
  data.pointData = {force,   direction, depth, distance, couple,  volume,
                    overlap, converged, first, second,   obstacle};
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
  if (log_ >= 0) ::close(log_);
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
  // The header as a whole file first: a run killed at any instant leaves a log.csv that is
  // absent or starts with its header, never empty.
  const std::filesystem::path path = directory_ / "log.csv";
  io::writeFileAtomically(path, kLogHeader);
  log_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (log_ < 0)
    throw Error("cannot write '" + path.string() + "': " + std::generic_category().message(errno));
  logBytes_ = kLogHeader.size();
}

void DemOutput::writeLog(std::string_view line) {
  std::size_t written = 0;
  while (written < line.size()) {
    const ssize_t wrote = ::write(log_, line.data() + written, line.size() - written);
    if (wrote > 0) {
      written += static_cast<std::size_t>(wrote);
      continue;
    }
    if (wrote < 0 && errno == EINTR) continue;
    const int error = wrote < 0 ? errno : ENOSPC;
    // No half row: the file ends on its last whole row, as a reader expects of a CSV.
    if (::ftruncate(log_, static_cast<off_t>(logBytes_)) != 0) {
      // Nothing more to do: the error reported is the write's.
    }
    ::close(log_);
    log_ = -1;
    throw Error("writing '" + (directory_ / "log.csv").string() +
                "' failed: " + std::generic_category().message(error));
  }
  logBytes_ += line.size();
}

void DemOutput::log(const dem::World& world) {
  const dem::StepStatistics& statistics = world.statistics();
  const bool stepped = world.stepCount() > 0;
  log(LogRow{world.stepCount(), world.time(), world.energies(), world.contacts().size(),
             statistics.pairsInContact, stepped ? statistics.totalSeconds : 0.0,
             stepped ? statistics.contactDetectionSeconds : 0.0});
}

void DemOutput::log(const LogRow& row) {
  if (log_ < 0) return;
  const dem::Energies& energies = row.energies;
  if (!startEnergy_) startEnergy_ = energies.total();
  char line[512];
  const int length = std::snprintf(
      line, sizeof line, "%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%zu,%zu,%.6g,%.6g,%.17g\n", row.step,
      row.time, energies.kinetic(), energies.gravitational, energies.elastic, energies.total(),
      row.contacts, row.contactPairs, row.stepSeconds, row.contactDetectionSeconds,
      energies.total() - *startEnergy_);
  // A row a step, in one write: what a run cut short has logged is there, whole, and a full
  // disk stops the run at the row that does not fit.
  writeLog(
      std::string_view(line, static_cast<std::size_t>(std::min(length, int{sizeof line} - 1))));
}

void DemOutput::frame(const dem::World& part, std::span<const std::uint32_t> ids, double time) {
  const std::size_t frame = frames();
  const auto add = [&](std::vector<io::VtkSeriesEntry>& series, const char* name,
                       const io::VtkPolyData& data, bool pieced) {
    std::string file = frameFileName(name, frame, ".vtp");
    if (pieced && pieces_ > 0) {
      const std::string stem = frameFileName(name, frame, "");
      io::writeVtp(data, directory_ / (stem + "_" + std::to_string(piece_) + ".vtp"));
      if (pieceBarrier_) pieceBarrier_();  // every piece in place before the .pvtp names it
      if (piece_ != 0) {                   // rank 0 keeps the series; the others only count frames
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
  if (log_ < 0) return;
  const int closed = ::close(log_);
  log_ = -1;
  if (closed != 0)
    throw Error("writing '" + (directory_ / "log.csv").string() +
                "' failed: " + std::generic_category().message(errno));
}

void DemOutput::syncLog() const {
  if (log_ < 0) return;
  // EINVAL: a file (system) that cannot be synced, where the rows stand as they are.
  if (::fdatasync(log_) != 0 && errno != EINVAL)
    throw Error("writing '" + (directory_ / "log.csv").string() +
                "' failed: " + std::generic_category().message(errno));
}

std::vector<double> DemOutput::frameTimes() const {
  std::vector<double> times;
  for (const io::VtkSeriesEntry& entry : contactSeries_)
    times.push_back(entry.time);
  return times;
}

void DemOutput::resume(const dem::World& world, std::span<const double> frameTimes,
                       std::size_t step) {
  for (const dem::Obstacle& obstacle : world.obstacles())
    obstaclesMove_ = obstaclesMove_ || moves(obstacle);
  // Each earlier frame by the file that holds it: the run before may have written it on another
  // number of processes (.pvtp of pieces, or one .vtp). A frame that is in neither form is not
  // this run's output: the series would list a file that does not exist.
  const auto earlierFile = [&](const char* name, std::size_t frame, bool pieced) {
    const std::string first = frameFileName(name, frame, pieced && pieces_ > 0 ? ".pvtp" : ".vtp");
    if (std::filesystem::exists(directory_ / first)) return first;
    const std::string other = frameFileName(name, frame, pieces_ > 0 ? ".vtp" : ".pvtp");
    if (pieced && std::filesystem::exists(directory_ / other)) return other;
    throw Error("'" + directory_.string() + "' lacks " + first + " (frame " +
                std::to_string(frame) +
                " of the series the checkpoint continues): give --out NEWDIR to start a new "
                "series from the checkpoint");
  };
  const auto series = [&](std::vector<io::VtkSeriesEntry>& entries, const char* name, bool pieced) {
    entries.clear();
    for (std::size_t frame = 0; frame < frameTimes.size(); ++frame)
      entries.push_back(
          {frameTimes[frame], piece_ == 0 ? std::filesystem::path(earlierFile(name, frame, pieced))
                                          : std::filesystem::path()});
    if (piece_ == 0) io::writePvd(entries, directory_ / (std::string(name) + ".pvd"));
  };
  if (frames_ != DemFrames::Triangles) series(stateSeries_, "particles_state", true);
  if (frames_ != DemFrames::State) series(particleSeries_, "particles", true);
  series(contactSeries_, "contacts", true);
  if (obstaclesMove_ && piece_ == 0) series(obstacleSeries_, "obstacles", false);
  if (piece_ != 0) return;
  if (frames_ != DemFrames::Triangles)
    for (std::size_t k = 0; k < world.shapes().size(); ++k) {
      const std::filesystem::path shape = directory_ / ("shape_" + std::to_string(k) + ".vtp");
      if (!std::filesystem::exists(shape))
        io::writeVtp(io::VtkPolyData::fromMesh(world.shapes()[k].mesh()), shape);
    }
  if (!std::filesystem::exists(directory_ / "obstacles.vtp"))
    io::writeVtp(obstaclesOf(world), directory_ / "obstacles.vtp");

  // log.csv: the header and the rows up to `step`, whole, then appended to.
  const std::filesystem::path path = directory_ / "log.csv";
  std::string kept(kLogHeader);
  if (std::filesystem::exists(path)) {
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file)
      throw Error("cannot read '" + path.string() + "': " + std::generic_category().message(errno));
    std::string text;
    char buffer[1 << 16];
    for (std::size_t got; (got = std::fread(buffer, 1, sizeof buffer, file)) > 0;)
      text.append(buffer, got);
    std::fclose(file);
    std::size_t begin = text.find('\n');
    if (begin != std::string::npos) {
      kept = text.substr(0, begin + 1);
      for (++begin; begin < text.size();) {
        const std::size_t end = text.find('\n', begin);
        if (end == std::string::npos) break;  // a part row: dropped
        const std::string row = text.substr(begin, end - begin);
        char* digitsEnd = nullptr;
        const unsigned long long rowStep = std::strtoull(row.c_str(), &digitsEnd, 10);
        if (digitsEnd == row.c_str() || rowStep > step) break;
        if (!startEnergy_) {  // total_energy, the sixth column, of the first row
          std::size_t column = 0;
          for (int comma = 0; comma < 5 && column != std::string::npos; ++comma)
            column = row.find(',', column + 1);
          // A value that is not a finite number (a log edited by hand) is not taken: every later
          // row's energy_change would be NaN; the restart's own energy stands in.
          if (column != std::string::npos) {
            const double energy = std::strtod(row.c_str() + column + 1, nullptr);
            if (std::isfinite(energy)) startEnergy_ = energy;
          }
        }
        kept += row + "\n";
        begin = end + 1;
      }
    }
  }
  io::writeFileAtomically(path, kept);
  log_ = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (log_ < 0)
    throw Error("cannot write '" + path.string() + "': " + std::generic_category().message(errno));
  logBytes_ = kept.size();
}

}  // namespace delta::cli
