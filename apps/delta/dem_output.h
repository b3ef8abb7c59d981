#pragma once

#include <cstdio>
#include <filesystem>
#include <vector>

#include "delta/dem/world.h"
#include "delta/io/vtk.h"

namespace delta::cli {

/// Writes a DEM run into a folder for ParaView and for plotting:
///
///   particles.pvd + particles_NNNNNN.vtp   every particle's triangles in world coordinates;
///                                          cell data `particle` (index) and `shape`, point data
///                                          `velocity` (of the material point, v + ω × (x − c))
///   contacts.pvd + contacts_NNNNNN.vtp     one vertex per contact point; point data `force` (on
///                                          `particle`), `direction` (unit, from the other body
///                                          toward `particle`), `depth` (into the ε-shell),
///                                          `distance`, `overlap` (0/1), `particle`, `other`
///                                          (particle or obstacle index), `with_obstacle` (0/1)
///   obstacles.vtp                          the obstacles where they start; cell data `obstacle`,
///                                          point data `velocity`; when an obstacle moves also
///                                          obstacles.pvd + obstacles_NNNNNN.vtp, one per frame
///   log.csv                                one row per step (and one for the start): step, time,
///                                          kinetic_energy, potential_energy (gravity),
///                                          elastic_energy, total_energy, contacts,
///                                          contact_pairs, step_seconds,
///                                          contact_detection_seconds
///
/// NNNNNN is the frame number; the .pvd files give each frame its simulated time and are
/// rewritten after every frame, so a run cut short leaves a series that opens.
///
/// Threading: one object per run, used from one thread.
class DemOutput {
 public:
  /// Makes `directory` (and its parents) unless it exists. Throws delta::Error naming it when it
  /// is a file or cannot be made. Writes nothing else yet.
  explicit DemOutput(std::filesystem::path directory);
  ~DemOutput();
  DemOutput(const DemOutput&) = delete;
  DemOutput& operator=(const DemOutput&) = delete;

  /// Writes obstacles.vtp and opens log.csv with its header. Call once, before the first step.
  void begin(const dem::World& world);
  /// Appends the world's current step to log.csv.
  void log(const dem::World& world);
  /// Writes a frame of particles and contacts (and of moving obstacles) and updates the series.
  void frame(const dem::World& world);
  /// Flushes log.csv; throws delta::Error when anything could not be written.
  void finish();

  std::size_t frames() const noexcept { return particleSeries_.size(); }
  const std::filesystem::path& directory() const noexcept { return directory_; }

 private:
  std::filesystem::path directory_;
  std::FILE* log_ = nullptr;
  bool obstaclesMove_ = false;
  std::vector<io::VtkSeriesEntry> particleSeries_, contactSeries_, obstacleSeries_;
};

}  // namespace delta::cli
