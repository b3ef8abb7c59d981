#pragma once

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <span>
#include <string_view>
#include <utility>
#include <vector>

#include "delta/dem/world.h"
#include "delta/io/vtk.h"

namespace delta::cli {

/// What each frame of a DEM run shows of the particles (`delta dem --frames`).
enum class DemFrames {
  State,      ///< particles_state: one point per particle (the default)
  Triangles,  ///< particles: every particle's triangles where it is
  Both,
};

/// Writes a DEM run into a folder for ParaView and for plotting. The VTK files are compressed
/// (io/vtk.h: zlib, which ParaView reads); measured values are Float64 as computed, ids UInt32,
/// flags UInt8.
///
///   particles_state.pvd +                  one vertex per particle at its centre of mass; point
///   particles_state_NNNNNN.vtp             data `particle` (id), `shape` (index of shape_K.vtp),
///                                          `velocity`, `angular_velocity` (world frame),
///                                          `orientation` (unit quaternion w, x, y, z: body frame
///                                          to world) and `bounding_radius` (the shape's)
///   shape_K.vtp                            shape K's triangles in its body frame (centre of
///                                          mass at the origin), written once: a particle is
///                                          shape_K.vtp turned by `orientation` and moved to its
///                                          point, so a glyph of it at each point shows the
///                                          particles exactly (docs/guide.md says how)
///   particles.pvd + particles_NNNNNN.vtp   with DemFrames::Triangles or Both: every particle's
///                                          triangles in world coordinates; cell data `particle`
///                                          (id) and `shape`, point data `velocity` (of the
///                                          material point, v + ω × (x − c))
///   contacts.pvd + contacts_NNNNNN.vtp     one vertex per contact point; point data `force` (on
///                                          `particle`), `direction` (unit, from the other body
///                                          toward `particle`), `depth` (into the ε-shell),
///                                          `distance`, `overlap` (0/1), `converged` (0/1:
///                                          ContactPoint::converged), `particle`, `other`
///                                          (particle or obstacle index), `with_obstacle` (0/1)
///   obstacles.vtp                          the obstacles where they start; cell data `obstacle`,
///                                          point data `velocity`; when an obstacle moves also
///                                          obstacles.pvd + obstacles_NNNNNN.vtp, one per frame
///   log.csv                                one row per step (and one for the start): step, time,
///                                          kinetic_energy, potential_energy (gravity),
///                                          elastic_energy, total_energy, contacts,
///                                          contact_pairs, step_seconds,
///                                          contact_detection_seconds, energy_change (total
///                                          energy minus that of the first row logged)
///
/// The default, DemFrames::State, keeps a run's output small: a frame of the hopper's 1000
/// particles takes 87 kB on average, a frame of their 80,000 triangles 1.4 MB compressed (5.9 MB
/// before compression and integer ids): docs/performance.md, "Output sizes".
///
/// NNNNNN is the frame number; the .pvd files give each frame its simulated time and are
/// rewritten after every frame, after the frame's files (each file whole or not at all:
/// io/atomic_file.h), so a run stopped at any instant, kill -9 included, leaves series that
/// open and list only complete frames. log.csv starts as a whole file holding its header; each
/// row then goes to the operating system in one write(2) as it is logged (no buffer in the
/// process: the log never lags the frames and a killed run leaves whole rows; rows are not
/// fsynced, so a power cut, unlike a crash, may lose the last ones). A write that fails cuts
/// the file back to its last whole row before the error.
///
/// A run on P processes (`delta dem` under mpirun) writes a piece of each frame per rank,
/// particles_state_NNNNNN_K.vtp (particles_NNNNNN_K.vtp) and contacts_NNNNNN_K.vtp (K the rank,
/// each with the particles it owns and the contacts of the pairs it evaluated; `particle` and
/// `other` are particle ids), and rank 0 joins them in particles_state_NNNNNN.pvtp
/// (particles_NNNNNN.pvtp) and contacts_NNNNNN.pvtp, which the .pvd series play; rank 0 alone
/// writes the shapes, obstacles and log.csv.
///
/// Threading: one object per run (per rank), used from one thread.
class DemOutput {
 public:
  /// One line of log.csv.
  struct LogRow {
    std::size_t step = 0;
    double time = 0.0;
    dem::Energies energies;
    std::size_t contacts = 0;
    std::size_t contactPairs = 0;
    double stepSeconds = 0.0;
    double contactDetectionSeconds = 0.0;
  };

  /// log.csv's header line (with its newline).
  static constexpr std::string_view kLogHeader =
      "step,time,kinetic_energy,potential_energy,elastic_energy,total_energy,contacts,"
      "contact_pairs,step_seconds,contact_detection_seconds,energy_change\n";

  /// Makes `directory` (and its parents) unless it exists. Throws delta::Error naming it when it
  /// is a file or cannot be made. Writes nothing else yet. `frames`: what the particle frames
  /// show. `piece` and `pieces`: this rank and the number of ranks of a distributed run;
  /// pieces = 0: one process.
  explicit DemOutput(std::filesystem::path directory, DemFrames frames = DemFrames::State,
                     int piece = 0, int pieces = 0);
  ~DemOutput();
  DemOutput(const DemOutput&) = delete;
  DemOutput& operator=(const DemOutput&) = delete;

  /// Writes the shapes (with DemFrames::State or Both), obstacles.vtp and opens log.csv with its
  /// header (rank 0). Call once, before the first step, with the world or any rank's part (their
  /// shapes and obstacles are the same).
  void begin(const dem::World& world);
  /// Appends the world's current step to log.csv.
  void log(const dem::World& world);
  /// Appends a row to log.csv (rank 0; the others ignore it) in one write; throws delta::Error
  /// naming the file and the reason when it cannot be written (a full disk), leaving the file
  /// at its last whole row.
  void log(const LogRow& row);
  /// Writes a frame of particles (as DemFrames says) and contacts (and of moving obstacles) and
  /// updates the series.
  void frame(const dem::World& world) { frame(world, {}, world.time()); }
  /// Writes this rank's piece of a frame: the particles of `part` with their ids (empty: their
  /// indices), at simulated time `time`; rank 0 also joins the pieces and updates the series.
  void frame(const dem::World& part, std::span<const std::uint32_t> ids, double time);
  /// Closes log.csv; throws delta::Error when that fails.
  void finish();
  /// Puts the rows of log.csv written so far on the disk (fdatasync): a checkpoint written after
  /// them must not outlive them in a power loss, which would leave a gap in the log of the run
  /// its restart continues. Throws delta::Error when that fails.
  void syncLog() const;

  /// Continues the output of a run restarted from a checkpoint (`delta dem --restart`) instead
  /// of begin(): the series list the `frameTimes.size()` frames written before the checkpoint
  /// (their files as frame() named them; later ones, of a run stopped after its checkpoint, are
  /// dropped from the series and written again), log.csv keeps its header and its rows up to
  /// step `step` and new rows are appended (energy_change still from its first row), and
  /// shape_K.vtp and obstacles.vtp are written only where missing. Throws delta::Error naming a
  /// file that cannot be read or written.
  void resume(const dem::World& world, std::span<const double> frameTimes, std::size_t step);
  /// The simulated time of every frame written (resumed ones first).
  std::vector<double> frameTimes() const;
  /// Sets what every rank calls after writing its piece of a frame and before rank 0 joins the
  /// pieces (an MPI barrier), so that a .pvtp, and the .pvd after it, name only pieces that
  /// are in place. Collective once set: every rank writes every frame. None: no waiting.
  void setPieceBarrier(std::function<void()> barrier) { pieceBarrier_ = std::move(barrier); }

  std::size_t frames() const noexcept { return contactSeries_.size(); }
  const std::filesystem::path& directory() const noexcept { return directory_; }

 private:
  /// Writes `line` (whole rows) to log.csv; on failure cuts it back to its last whole row,
  /// closes it and throws delta::Error naming it and the reason.
  void writeLog(std::string_view line);

  std::filesystem::path directory_;
  DemFrames frames_ = DemFrames::State;
  int piece_ = 0, pieces_ = 0;
  int log_ = -1;                       ///< log.csv, open for appending; -1: not written here
  std::uintmax_t logBytes_ = 0;        ///< its length up to its last whole row
  std::optional<double> startEnergy_;  ///< the total energy of the first row logged
  bool obstaclesMove_ = false;
  std::vector<io::VtkSeriesEntry> stateSeries_, particleSeries_, contactSeries_, obstacleSeries_;
  std::function<void()> pieceBarrier_;
};

}  // namespace delta::cli
