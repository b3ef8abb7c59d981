// `delta dem [SCENARIO]`: runs a DEM scenario (two-particles, settle, hopper, or one described by a
// config file), with a progress line, a summary (text or --json) and, with --out, a ParaView
// series and a CSV log (dem_output.h).
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/dem/checkpoint.h"
#include "delta/dem/scenarios.h"
#ifdef DELTA_WITH_MPI
#include "delta/dem/mpi/distributed_world.h"
#endif

#include "commands.h"
#include "dem_checkpoint.h"
#include "dem_output.h"
#include "dem_settings.h"
#include "dem_warnings.h"
#include "files.h"
#include "json.h"
#include "mesh_source.h"
#include "motion_options.h"
#include "progress.h"
#include "run_lock.h"
#include "stopwatch.h"

namespace delta::cli {
namespace {

/// The scenarios' defaults where a setting is not given (scenarios.h).
constexpr double kTwoParticlesRestitution = 0.9;
constexpr std::size_t kSettleParticles = 100;
constexpr std::size_t kHopperParticles = 1000;
constexpr std::uint64_t kSeed = 1;

struct DemOptions {
  std::string scenario;  ///< SCENARIO: a scenario's name or a config file
  std::string config;
  std::map<std::string, std::string> given;  ///< config key → text, from the options
  std::string out;
  std::string frames = "state";  ///< --frames: DemFrames by name
  bool framesGiven = false;      ///< --frames was given (a restart takes the checkpoint's)
  bool json = false;
  bool quiet = false;
  bool overwrite = false;           ///< --overwrite: replace an earlier run's output in --out
  std::size_t checkpointEvery = 0;  ///< --checkpoint-every N (0: only when stopped)
  std::string restart;              ///< --restart FILE
  bool continuing = false;          ///< --restart into the checkpoint's folder: its output goes on
};

/// --frames NAME as DemFrames; throws delta::Error on another name.
DemFrames framesOf(const DemOptions& options) {
  if (options.frames == "state") return DemFrames::State;
  if (options.frames == "triangles") return DemFrames::Triangles;
  if (options.frames == "both") return DemFrames::Both;
  throw Error("--frames '" + options.frames + "' is not state, triangles or both");
}

/// What --out does with an earlier run's files: --overwrite replaces them; otherwise refused.
/// (--restart continues instead: restart() passes EarlierOutput::Continue for its own folder.)
EarlierOutput earlierOutput(const DemOptions& options) {
  if (options.continuing) return EarlierOutput::Continue;
  return options.overwrite ? EarlierOutput::Overwrite : EarlierOutput::Refuse;
}

/// The config file, overridden by the options.
DemSettings resolve(const DemOptions& options) {
  DemSettings command;
  std::string config = options.config;
  if (!options.scenario.empty()) {
    if (isDemScenario(options.scenario)) {
      setDemSetting(command, "scenario", options.scenario, "SCENARIO");
    } else if (!std::filesystem::is_regular_file(options.scenario)) {
      throw Error("'" + options.scenario +
                  "' is neither a scenario (two-particles, settle, hopper) nor a config file");
    } else if (!config.empty()) {
      throw Error("two config files: '" + options.scenario + "' and --config '" + config + "'");
    } else {
      config = options.scenario;
    }
  }
  for (const auto& [key, text] : options.given) {
    std::string option = "--" + key;
    std::replace(option.begin(), option.end(), '_', '-');
    setDemSetting(command, key, text, option);
  }
  DemSettings settings =
      config.empty() ? command : mergedDemSettings(readDemConfig(config), command);
  checkDemCombination(settings);
  return settings;
}

/// The largest bounding radius and mass of the shapes the world's particles use.
std::pair<double, double> largestRadiusAndMass(const dem::World& world) {
  double radius = 0.0, mass = 0.0;
  for (const dem::Particle& particle : world.particles()) {
    const dem::ParticleShape& shape = world.shapes()[particle.shape];
    radius = std::max(radius, shape.boundingRadius());
    mass = std::max(mass, shape.mass());
  }
  return {radius, mass};
}

/// A closed mesh (file or builtin:) scaled about its centre of mass to bounding radius `radius`.
dem::ParticleShape particleShape(const std::string& source, double radius, double density,
                                 const std::string& origin) {
  try {
    Mesh mesh = loadMeshSource(source).mesh;
    const dem::ParticleShape asGiven(mesh, density);
    mesh.scale(radius / asGiven.boundingRadius(), asGiven.centroid());
    return dem::ParticleShape(mesh, density);
  } catch (const Error& error) {
    throw Error(origin + " '" + source + "': " + error.what());
  }
}

/// Moves the two particles of two-particles along x (their line of approach) so that the new
/// shape starts as far from the other as the spheres did: the scenario's run is timed for that
/// gap. The shape's extent along ±x is taken in its body frame (the particles start unturned).
void keepTheGap(std::vector<dem::ParticleState>& states, const dem::World& old,
                const dem::ParticleShape& shape, double scale) {
  dem::ParticleState& left = states[0];
  dem::ParticleState& right = states[1];
  const double sphereRadius = old.shapes()[old.particles()[0].shape].boundingRadius();
  const double gap = (right.position.x - left.position.x - 2.0 * sphereRadius) * scale;
  const double middle = 0.5 * (left.position.x + right.position.x);
  double ahead = -INFINITY, behind = INFINITY;
  for (const Vec3& vertex : shape.mesh().vertices()) {
    ahead = std::max(ahead, vertex.x);
    behind = std::min(behind, vertex.x);
  }
  left.position.x = middle - 0.5 * gap - ahead;
  right.position.x = middle + 0.5 * gap - behind;
}

/// The scenario made again with the settings it does not take itself: another restitution or
/// friction for settle and hopper, another particle shape for any. Particles keep their places
/// and motion; a new shape gets the stiffness scaled by its mass over the heaviest old one (the
/// scenarios size k for an impact depth of ε, k ∝ m), and the time step and the number of steps
/// follow so that the run covers the same simulated time. A new shape of bounding radius R
/// (--particle-radius) smaller than the scenario's largest r scales ε and h by s = R/r (they are
/// fractions of the particle size) and k by a further 1/s², so that impacts at the scenario's
/// speeds stop as deep into the shell as before; the time step shrinks by s. two-particles also
/// shrinks its gap by s and keeps its number of steps; settle and hopper keep their places and
/// drop heights, so their default number of steps grows by 1/s.
dem::Scenario remade(dem::Scenario scenario, const DemSettings& settings) {
  const dem::World& old = scenario.world;
  dem::Parameters parameters = old.parameters();
  if (settings.restitution) parameters.restitution = *settings.restitution;
  if (settings.friction) parameters.friction = *settings.friction;
  std::optional<dem::ParticleShape> shape;
  double scale = 1.0;
  if (!settings.particleMesh.empty()) {
    const auto [largest, heaviest] = largestRadiusAndMass(old);
    const double radius = settings.particleRadius.value_or(largest);
    if (radius > largest * (1.0 + 1e-12))
      throw Error(settings.origins.at("particle_radius") + " '" + toString(radius) +
                  "' is larger than the scenario's particles (" + toString(largest) +
                  "): they would overlap at the start");
    const std::string origin = settings.origins.at("particle_mesh");
    shape = particleShape(settings.particleMesh, radius, old.shapes().front().density(), origin);
    parameters.stiffness *= shape->mass() / heaviest;
    scale = radius / largest;  // exactly 1 without --particle-radius: nothing below changes
    parameters.epsilon *= scale;
    parameters.filterDistance *= scale;
    parameters.stiffness /= scale * scale;
  }
  dem::World world(parameters);
  if (shape)
    world.addShape(*shape);
  else
    for (const dem::ParticleShape& existing : old.shapes())
      world.addShape(existing);
  std::vector<dem::ParticleState> states;
  for (const dem::Particle& particle : old.particles())
    states.push_back(
        {particle.position, particle.orientation, particle.velocity, particle.angularVelocity});
  if (shape && scenario.name == "two-particles") keepTheGap(states, old, *shape, scale);
  for (std::size_t p = 0; p < states.size(); ++p)
    world.addParticle(shape ? 0 : old.particles()[p].shape, states[p]);
  for (const dem::Obstacle& obstacle : old.obstacles())
    world.addObstacle(obstacle.mesh, obstacle.motion);
  if (shape) {
    double stretch = parameters.timeStep / world.suggestedTimeStep();
    if (scenario.name == "two-particles") stretch *= scale;  // its gap shrank with the time step
    world.setTimeStep(world.suggestedTimeStep());
    const auto scaled = [&](std::size_t steps) {
      return std::max<std::size_t>(
          1, static_cast<std::size_t>(std::ceil(static_cast<double>(steps) * stretch)));
    };
    scenario.steps = scaled(scenario.steps);
    scenario.outputInterval = scaled(scenario.outputInterval);
  }
  scenario.world = std::move(world);
  return scenario;
}

dem::Scenario build(const DemSettings& settings) {
  const std::string name = settings.scenario.empty() ? "hopper" : settings.scenario;
  // The volume law's scenarios have closed obstacles (scenarios.h), so the law is chosen here.
  const dem::ContactModel model = settings.contactModel.empty()
                                      ? dem::ContactModel::point
                                      : dem::contactModelNamed(settings.contactModel);
  dem::Scenario scenario =
      name == "two-particles"
          ? dem::twoParticles(settings.restitution.value_or(kTwoParticlesRestitution),
                              settings.offset.value_or(0.0), settings.friction.value_or(0.0), model)
      : name == "settle"
          ? dem::settle(settings.particles.value_or(kSettleParticles),
                        settings.seed.value_or(kSeed), dem::ParticleKind::Mesh, model)
          : dem::hopper(settings.particles.value_or(kHopperParticles),
                        settings.seed.value_or(kSeed), dem::ParticleKind::Mesh, model);
  const bool lawChanges = name != "two-particles" && (settings.restitution || settings.friction);
  if (lawChanges || !settings.particleMesh.empty())
    scenario = remade(std::move(scenario), settings);
  return scenario;
}

/// "1 obstacle", "3 obstacles".
std::string counted(std::size_t count, const char* noun) {
  return std::to_string(count) + " " + noun + (count == 1 ? "" : "s");
}

/// What a run measured.
struct RunSummary {
  std::size_t steps = 0;
  std::size_t contacts = 0;  ///< summed over the steps
  std::size_t contactPairs = 0;
  std::size_t maxContacts = 0;
  std::size_t overlappingContacts = 0;
  double deepestRatio = 0.0;
  double stepSeconds = 0.0;  ///< Σ StepStatistics::totalSeconds (of the slowest rank)
  double contactDetectionSeconds = 0.0;
  double runSeconds = 0.0;  ///< wall clock of the steps alone
  double writeSeconds = 0.0;
  double restitution = NAN;
  double energyChange = NAN;          ///< (E_end − E_start) / |E_start|, total energy
  double energyChangeAbsolute = NAN;  ///< E_end − E_start
  std::vector<std::string> warnings;  ///< DemWarnings::all()
  double time = 0.0;                  ///< simulated, at the end
  std::string digest;                 ///< dem::stateDigest at the end
  std::size_t checkpoints = 0;        ///< written (dem_checkpoint.h)
  std::size_t checkpointBytes = 0;    ///< the last one's size
  double checkpointSeconds = 0.0;     ///< writing them, all
  /// A distributed run's: ranks (0: one process), rebalances and every rank's load.
  int ranks = 0;
  std::size_t rebalances = 0;
  std::vector<dem::RankLoad> loads;

  /// Counts one more step with these statistics (of the whole world).
  void add(const dem::StepStatistics& statistics) {
    ++steps;
    contacts += statistics.contactPoints;
    contactPairs += statistics.pairsInContact;
    maxContacts = std::max(maxContacts, statistics.contactPoints);
    overlappingContacts += statistics.overlappingContacts;
    deepestRatio = std::max(deepestRatio, statistics.deepestRatio);
    stepSeconds += statistics.totalSeconds;
    contactDetectionSeconds += statistics.contactDetectionSeconds;
  }
};

/// What simulate() does besides stepping: checkpoints (dem_checkpoint.h), and for a run
/// restarted from one, the output it continues.
struct Continuation {
  DemCheckpoints* checkpoints = nullptr;
  bool restarted = false;  ///< no restitution meter: it would start mid-run
  /// The output folder holds the stopped run's frames, these many, at these times: continue
  /// its series and log.csv (DemOutput::resume) instead of starting them.
  bool resumeOutput = false;
  std::vector<double> frameTimes;
};

RunSummary simulate(dem::Scenario& scenario, std::size_t steps, std::size_t outputEvery,
                    DemOutput* output, bool showLine, const Continuation& continuation = {}) {
  dem::World& world = scenario.world;
  std::optional<dem::RestitutionMeter> meter;
  if (scenario.name == "two-particles" && !continuation.restarted) meter.emplace(world);
  const double startEnergy = world.energies().total();
  RunSummary summary;
  DemWarnings warnings(true);
  warnings.atStart(world);
  Stopwatch writing;
  if (output && continuation.resumeOutput) {
    output->resume(world, continuation.frameTimes, world.stepCount());
  } else if (output) {
    output->begin(world);
    output->log(world);
    output->frame(world);
  }
  summary.writeSeconds += writing.seconds();
  Progress progress("dem " + scenario.name, steps, showLine);
  int stopSignal = 0;
  for (std::size_t step = 1; step <= steps && stopSignal == 0; ++step) {
    const Stopwatch stepping;
    world.step();
    summary.runSeconds += stepping.seconds();
    summary.add(world.statistics());
    if (step == 1 && !continuation.restarted) warnings.afterFirstStep(world.statistics());
    if (meter) meter->observe(world);
    if (output) {
      writing.restart();
      output->log(world);
      // By the step count, so that a restarted run writes the frames the whole run would.
      if (world.stepCount() % outputEvery == 0 || step == steps) output->frame(world);
      summary.writeSeconds += writing.seconds();
    }
    if (continuation.checkpoints) stopSignal = continuation.checkpoints->afterStep(world, output);
    progress.update(step);
  }
  if (continuation.checkpoints &&
      (stopSignal != 0 || steps == 0 || continuation.checkpoints->every() > 0))
    continuation.checkpoints->write(world, output);  // the latest state, kept
  if (output) output->finish();
  if (stopSignal != 0) throw StoppedBySignal{stopSignal, world.stepCount(), true};
  summary.checkpointSeconds = continuation.checkpoints ? continuation.checkpoints->seconds() : 0.0;
  summary.checkpointBytes = continuation.checkpoints ? continuation.checkpoints->bytes() : 0;
  summary.checkpoints = continuation.checkpoints ? continuation.checkpoints->written() : 0;
  summary.digest = world.stateDigest();
  summary.time = world.time();
  summary.energyChangeAbsolute = world.energies().total() - startEnergy;
  summary.energyChange = summary.energyChangeAbsolute / std::fabs(startEnergy);
  if (meter) summary.restitution = meter->restitution();
  summary.warnings = warnings.all();
  return summary;
}

#ifdef DELTA_WITH_MPI
/// Whether this process was started by mpirun (Open MPI, MPICH and PMIx set these).
bool startedByMpirun() {
  for (const char* variable : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"})
    if (std::getenv(variable)) return true;
  return false;
}

/// MPI for one `delta dem` run: initialised for OpenMP threads, finalised on the way out.
class MpiSession {
 public:
  MpiSession() {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    if (provided < MPI_THREAD_FUNNELED) {
      MPI_Finalize();
      throw Error("MPI gives no MPI_THREAD_FUNNELED (threads with MPI calls on one)");
    }
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  }
  ~MpiSession() { MPI_Finalize(); }
  MpiSession(const MpiSession&) = delete;
  MpiSession& operator=(const MpiSession&) = delete;
  int rank() const noexcept { return rank_; }

 private:
  int rank_ = 0;
};

/// Runs an error that only this rank meets (writing output) to its end: one line, and every
/// rank stopped, since the others wait for this one.
template <class Action>
void orAbort(Action&& action) {
  try {
    action();
  } catch (const std::exception& error) {
    std::fprintf(stderr, "delta: %s\n", error.what());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
}

/// simulate() on every rank of a DistributedWorld: rank 0 shows the progress, measures the
/// restitution (from the gathered particles) and writes log.csv; every rank writes its piece
/// of each frame.
RunSummary simulateDistributed(dem::Scenario& scenario, dem::DistributedWorld& world,
                               std::size_t steps, std::size_t outputEvery, DemOutput* output,
                               bool showLine, const Continuation& continuation = {}) {
  const bool root = world.rank() == 0;
  std::optional<dem::RestitutionMeter> meter;
  const bool measure = scenario.name == "two-particles" && !continuation.restarted;
  if (measure) {
    const std::vector<dem::Particle> particles = world.gatherParticles();
    if (root) meter.emplace(particles);
  }
  const double startEnergy = world.energies().total();
  RunSummary summary;
  summary.ranks = world.size();
  DemWarnings warnings(root);
  warnings.atStart(scenario.world);
  Stopwatch writing;
  const auto write = [&](bool frame) {
    const dem::Energies energies = world.energies();
    const dem::StepStatistics statistics = world.statistics();
    const bool stepped = world.stepCount() > 0;
    orAbort([&] {
      output->log({world.stepCount(), world.time(), energies, statistics.contactPoints,
                   statistics.pairsInContact, stepped ? statistics.totalSeconds : 0.0,
                   stepped ? statistics.contactDetectionSeconds : 0.0});
      if (frame) output->frame(world.part(), world.ids(), world.time());
    });
  };
  if (output && continuation.resumeOutput) {
    orAbort([&] { output->resume(world.part(), continuation.frameTimes, world.stepCount()); });
  } else if (output) {
    orAbort([&] { output->begin(scenario.world); });
    write(true);
  }
  // The whole state gathered on rank 0, which writes it (dem_checkpoint.h); once a step.
  DemCheckpoints* const checkpoints = continuation.checkpoints;
  std::size_t checkpointed = static_cast<std::size_t>(-1);
  const auto checkpoint = [&] {
    if (!checkpoints || !checkpoints->enabled() || checkpointed == world.stepCount()) return;
    const std::optional<dem::World> whole = world.gatherWorld();
    if (whole) orAbort([&] { checkpoints->write(*whole, output); });
    checkpointed = world.stepCount();
  };
  int stopSignal = 0;
  summary.writeSeconds += writing.seconds();
  Progress progress("dem " + scenario.name, steps, showLine && root);
  for (std::size_t step = 1; step <= steps && stopSignal == 0; ++step) {
    const Stopwatch stepping;
    world.step();
    summary.runSeconds += stepping.seconds();
    summary.add(world.statistics());
    if (step == 1 && !continuation.restarted) warnings.afterFirstStep(world.statistics());
    if (measure) {
      const std::vector<dem::Particle> particles = world.gatherParticles();
      const std::vector<dem::Contact> contacts = world.gatherContacts();
      if (meter) meter->observe(particles, contacts);
    }
    if (output) {
      writing.restart();
      write(world.stepCount() % outputEvery == 0 || step == steps);
      summary.writeSeconds += writing.seconds();
    }
    if (checkpoints) {  // every rank stops after the same step
      stopSignal = checkpoints->pendingSignal();
      MPI_Allreduce(MPI_IN_PLACE, &stopSignal, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
      if (stopSignal != 0 || checkpoints->due(world.stepCount())) checkpoint();
    }
    progress.update(step);
  }
  if (checkpoints && (stopSignal != 0 || steps == 0 || checkpoints->every() > 0)) checkpoint();
  if (output) orAbort([&] { output->finish(); });
  if (stopSignal != 0) throw StoppedBySignal{stopSignal, world.stepCount(), root};
  if (const std::optional<dem::World> whole = world.gatherWorld()) {
    summary.digest = whole->stateDigest();
    if (checkpoints) {
      summary.checkpointSeconds = checkpoints->seconds();
      summary.checkpointBytes = checkpoints->bytes();
      summary.checkpoints = checkpoints->written();
    }
  }
  const double endEnergy = world.energies().total();
  summary.time = world.time();
  summary.energyChangeAbsolute = endEnergy - startEnergy;
  summary.energyChange = summary.energyChangeAbsolute / std::fabs(startEnergy);
  if (meter) summary.restitution = meter->restitution();
  summary.warnings = warnings.all();
  summary.rebalances = world.rebalances();
  summary.loads = world.gatherLoads();
  return summary;
}
#endif

void printJson(const dem::Scenario& scenario, std::size_t triangles, double buildSeconds,
               const RunSummary& run, const DemOutput* output) {
  const dem::World& world = scenario.world;
  const auto perStep = [&](double total) { return total / static_cast<double>(run.steps); };
  JsonWriter json;
  json.beginObject()
      .value("scenario", scenario.name)
      .value("particles", world.particles().size())
      .value("triangles", triangles)
      .value("obstacles", world.obstacles().size())
      .value("steps", run.steps)
      .value("time_step", world.parameters().timeStep)
      .value("contact_model", dem::contactModelName(world.parameters().contactModel))
      .value("time", run.time)
      .value("steps_per_s", static_cast<double>(run.steps) / run.runSeconds)
      .value("contacts_per_step", perStep(static_cast<double>(run.contacts)))
      .value("max_contacts", run.maxContacts)
      .value("contact_pairs_per_step", perStep(static_cast<double>(run.contactPairs)))
      .value("overlapping_contacts", run.overlappingContacts)
      .value("max_depth_ratio", run.deepestRatio)
      .value("share_contact_detection", run.contactDetectionSeconds / run.stepSeconds)
      .value("build_s", buildSeconds)
      .value("run_s", run.runSeconds)
      .value("write_s", run.writeSeconds)
      .value("frames", output ? output->frames() : std::size_t{0})
      .value("threads", threadCount())
      .value("state_digest", run.digest);
  if (run.checkpoints > 0)
    json.value("checkpoints", run.checkpoints)
        .value("checkpoint_bytes", run.checkpointBytes)
        .value("checkpoint_s", run.checkpointSeconds);
  if (scenario.name == "two-particles") json.value("restitution", run.restitution);
  json.value("energy_change", run.energyChange)
      .value("energy_change_absolute", run.energyChangeAbsolute)
      .beginArray("warnings");
  for (const std::string& warning : run.warnings)
    json.value({}, warning);
  json.endArray();
  if (run.ranks > 0) {
    json.value("ranks", run.ranks).value("rebalances", run.rebalances).beginArray("rank_loads");
    for (std::size_t r = 0; r < run.loads.size(); ++r) {
      const dem::RankLoad& load = run.loads[r];
      json.beginObject()
          .value("rank", r)
          .value("particles", load.particles)
          .value("ghosts", load.ghosts)
          .value("neighbours", load.neighbours)
          .value("contacts", load.contacts)
          .value("contact_detection_s", load.contactDetectionSeconds)
          .value("communication_s", load.communicationSeconds)
          .value("step_s", load.stepSeconds)
          .endObject();
    }
    json.endArray();
  }
  std::printf("%s\n", json.endObject().str().c_str());
}

void printText(const dem::Scenario& scenario, std::size_t triangles, double buildSeconds,
               const RunSummary& run, const DemOutput* output) {
  const dem::World& world = scenario.world;
  std::printf("%s: %s (%s), %s, time step %.3g s, built in %.3f s\n", scenario.name.c_str(),
              counted(world.particles().size(), "particle").c_str(),
              counted(triangles, "triangle").c_str(),
              counted(world.obstacles().size(), "obstacle").c_str(), world.parameters().timeStep,
              buildSeconds);
  const std::string threads = counted(static_cast<std::size_t>(threadCount()), "thread");
  const std::string where =
      run.ranks > 0 ? counted(static_cast<std::size_t>(run.ranks), "rank") + " of " + threads
                    : threads;
  std::printf("%s (%.4g s simulated) in %.3f s on %s: %.3g steps/s\n",
              counted(run.steps, "step").c_str(), run.time, run.runSeconds, where.c_str(),
              static_cast<double>(run.steps) / run.runSeconds);
  std::printf(
      "%.1f contact points a step (at most %zu), %.0f%% of the step time in contact "
      "detection, deepest %.2f of the 2ε shell%s\n",
      static_cast<double>(run.contacts) / static_cast<double>(run.steps), run.maxContacts,
      100.0 * run.contactDetectionSeconds / run.stepSeconds, run.deepestRatio,
      // The volume law's contacts are overlaps: nothing to report there.
      run.overlappingContacts && world.parameters().contactModel == dem::ContactModel::point
          ? ", SURFACES OVERLAPPED"
          : "");
  if (scenario.name == "two-particles") {
    if (std::isnan(run.restitution))
      std::printf("restitution: not measured (the particles did not collide and part)\n");
    else
      std::printf("restitution %.4f (asked %.4g), total energy changed by %.3g%%\n",
                  run.restitution, world.parameters().restitution, 100.0 * run.energyChange);
  }
  std::printf("total energy changed by %.6g J (%.3g%% of the start's)\n", run.energyChangeAbsolute,
              100.0 * run.energyChange);
  for (const std::string& warning : run.warnings)
    std::printf("warning: %s\n", warning.c_str());
  if (run.ranks > 0) {
    std::printf(
        "%d ranks, split again %zu times; per rank (last step: particles, ghosts, "
        "ranks exchanged with, contact points; whole run: seconds):\n",
        run.ranks, run.rebalances);
    std::printf(
        "  rank  particles   ghosts  neighbours  contacts  contact detection  communication    "
        "step\n");
    for (std::size_t r = 0; r < run.loads.size(); ++r) {
      const dem::RankLoad& load = run.loads[r];
      std::printf("  %4zu  %9zu  %7zu  %10zu  %8zu  %17.3f  %13.3f  %6.3f\n", r, load.particles,
                  load.ghosts, load.neighbours, load.contacts, load.contactDetectionSeconds,
                  load.communicationSeconds, load.stepSeconds);
    }
  }
  if (output)
    std::printf("%zu frames written to %s in %.3f s\n", output->frames(),
                output->directory().string().c_str(), run.writeSeconds);
}

/// What run() and runDistributed() start from.
struct Prepared {
  dem::Scenario scenario;
  double buildSeconds = 0.0;
  std::size_t steps = 0;
  std::size_t outputEvery = 1;
  std::size_t triangles = 0;
};

Prepared prepare(const DemSettings& settings) {
  Stopwatch clock;
  Prepared prepared{build(settings)};
  prepared.buildSeconds = clock.seconds();
  const dem::Scenario& scenario = prepared.scenario;
  prepared.steps = settings.steps.value_or(scenario.steps);
  prepared.outputEvery = settings.outputEvery.value_or(scenario.outputInterval);
  for (const dem::Particle& particle : scenario.world.particles())
    prepared.triangles += scenario.world.shapes()[particle.shape].mesh().triangleCount();
  return prepared;
}

void report(const DemOptions& options, const Prepared& prepared, const RunSummary& summary,
            const DemOutput* output) {
  if (options.json)
    printJson(prepared.scenario, prepared.triangles, prepared.buildSeconds, summary, output);
  else
    printText(prepared.scenario, prepared.triangles, prepared.buildSeconds, summary, output);
}

/// The note a run's checkpoints carry (dem_checkpoint.h).
DemRunNote noteOf(const DemOptions& options, const Prepared& prepared) {
  DemRunNote note;
  note.scenario = prepared.scenario.name;
  note.steps = prepared.scenario.world.stepCount() + prepared.steps;
  note.outputEvery = prepared.outputEvery;
  note.frames = options.frames;
  note.checkpointEvery = options.checkpointEvery;
  note.run = newRunId();
  return note;
}

/// `delta dem --restart FILE`, checked and loaded: the run the checkpoint holds, to go on to
/// --steps in all (its own total by default), into --out (by default the checkpoint's folder,
/// whose series and log.csv it continues).
struct RestartPlan {
  Prepared prepared;
  DemRunNote note;
  DemOptions options;  ///< as given, with --out, --frames and `continuing` set from the checkpoint
  std::size_t checkpointEvery = 0;
  Continuation continuation;  ///< without its DemCheckpoints
};

RestartPlan planRestart(const DemOptions& options) {
  if (!options.scenario.empty() || !options.config.empty())
    throw Error("--restart continues the run its checkpoint holds: give no SCENARIO or --config");
  const auto refuse = [](const std::string& option) {
    throw Error("--restart continues the run its checkpoint holds: " + option +
                " cannot change it (only --steps, --out, --checkpoint-every, --json, --quiet, "
                "and --overwrite with another --out)");
  };
  for (const auto& [key, text] : options.given)
    if (key != "steps") {
      std::string option = "--" + key;
      std::replace(option.begin(), option.end(), '_', '-');
      refuse(option);
    }
  if (options.framesGiven) refuse("--frames");
  const std::filesystem::path file = options.restart;
  const Stopwatch clock;
  dem::Checkpoint checkpoint = dem::loadCheckpoint(file);
  DemRunNote note = DemRunNote::parse(checkpoint.note, file.string());
  std::size_t total = note.steps;
  if (options.given.count("steps")) {
    DemSettings command;
    setDemSetting(command, "steps", options.given.at("steps"), "--steps");
    total = command.steps.value_or(total);
  }
  const std::size_t done = checkpoint.world.stepCount();
  if (total < done)
    throw Error("--steps " + std::to_string(total) + " is fewer than the " + std::to_string(done) +
                " steps '" + file.string() + "' has run (--steps is the run's total)");
  // The run's total and checkpoint interval as this restart sets them: its checkpoints carry
  // them, so that a later restart goes on to the same end (they kept the first run's, and a
  // restart of a restart stopped there, with exit 0).
  note.steps = total;
  if (options.checkpointEvery > 0) note.checkpointEvery = options.checkpointEvery;
  const std::filesystem::path folder =
      file.has_parent_path() ? file.parent_path() : std::filesystem::path(".");
  RestartPlan plan{Prepared{dem::Scenario{note.scenario, std::move(checkpoint.world), note.steps,
                                          note.outputEvery}},
                   note, options,
                   options.checkpointEvery > 0 ? options.checkpointEvery : note.checkpointEvery,
                   Continuation{nullptr, true, false, {}}};
  plan.options.frames = note.frames;
  if (plan.options.out.empty()) plan.options.out = folder.string();
  // Its output goes on where the folder holds this run's (its marker names the run; a note of a
  // version without run identities trusts the folder, as that version did).
  std::error_code error;
  const bool ownFolder = std::filesystem::equivalent(plan.options.out, folder, error);
  plan.options.continuing =
      ownFolder && (note.run.empty() || runMarkerOf(plan.options.out) == note.run);
  if (ownFolder && options.overwrite)
    throw Error(
        "--restart into the checkpoint's own folder: --overwrite would remove its output "
        "(give another --out to start a new series there)");
  if (ownFolder && !plan.options.continuing) {
    std::vector<std::filesystem::path> others = demOutputFiles(plan.options.out);
    std::erase_if(others, [&](const std::filesystem::path& path) {
      return std::filesystem::equivalent(path, file, error);
    });
    if (!others.empty())
      throw Error("'" + plan.options.out + "' holds the output of another run than the one '" +
                  file.string() + "' continues (its " + kRunMarkerName +
                  " names another run, or none): give --out NEWDIR to start a new series from "
                  "the checkpoint");
  }
  plan.continuation.resumeOutput = plan.options.continuing;
  plan.continuation.frameTimes = note.frameTimes;
  Prepared& prepared = plan.prepared;
  prepared.buildSeconds = clock.seconds();
  prepared.steps = total - done;
  prepared.outputEvery = note.outputEvery;
  for (const dem::Particle& particle : prepared.scenario.world.particles())
    prepared.triangles += prepared.scenario.world.shapes()[particle.shape].mesh().triangleCount();
  return plan;
}

/// `delta dem --restart FILE` in one process.
void restart(const DemOptions& given) {
  RestartPlan plan = planRestart(given);
  const DemOptions& options = plan.options;
  makeOutputFolder(options.out);
  const RunLock lock(options.out, "delta dem");  // held until the output is closed
  if (!lock.note().empty()) std::fprintf(stderr, "delta: note: %s\n", lock.note().c_str());
  prepareOutputFolder(options.out, earlierOutput(options), options.restart);
  DemOutput output(options.out, framesOf(options));
  writeRunMarker(options.out, plan.note.run);
  DemCheckpoints checkpoints(options.out, plan.checkpointEvery, plan.note);
  plan.continuation.checkpoints = &checkpoints;
  const RunSummary summary =
      simulate(plan.prepared.scenario, plan.prepared.steps, plan.prepared.outputEvery, &output,
               showProgress(options.quiet || options.json), plan.continuation);
  report(options, plan.prepared, summary, &output);
}

#ifdef DELTA_WITH_MPI
/// `delta dem` under mpirun: the scenario built on every rank, split over the ranks
/// (dem::DistributedWorld), the summary from rank 0. An error every rank meets (bad settings)
/// is reported once, by rank 0.
void runDistributed(const DemOptions& given) {
  MpiSession mpi;
  const bool root = mpi.rank() == 0;
  try {
    std::optional<RestartPlan> restarting;  // --restart: the run and options a checkpoint holds
    std::optional<DemSettings> settings;
    if (!given.restart.empty())
      restarting.emplace(planRestart(given));
    else
      settings = resolve(given);
    if (given.checkpointEvery > 0 && given.out.empty() && !restarting)
      throw Error("--checkpoint-every needs --out DIR: the checkpoint is kept there");
    const DemOptions& options = restarting ? restarting->options : given;
    int ranks = 1;
    MPI_Comm_size(MPI_COMM_WORLD, &ranks);
    std::unique_ptr<RunLock> lock;  // rank 0's, held until the output is closed
    std::unique_ptr<DemOutput> output;
    if (!options.out.empty()) {  // rank 0 makes the folder, then the others find it
      const DemFrames frames = framesOf(options);
      if (root)
        orAbort([&] {
          makeOutputFolder(options.out);
          lock = std::make_unique<RunLock>(options.out, "delta dem");
          prepareOutputFolder(options.out, earlierOutput(options), options.restart);
          output = std::make_unique<DemOutput>(options.out, frames, 0, ranks);
        });
      MPI_Barrier(MPI_COMM_WORLD);
      if (!root)
        orAbort(
            [&] { output = std::make_unique<DemOutput>(options.out, frames, mpi.rank(), ranks); });
      // Every rank's piece of a frame is in place before rank 0 lists it (dem_output.h).
      output->setPieceBarrier([] { MPI_Barrier(MPI_COMM_WORLD); });
    }
    Prepared prepared = restarting ? std::move(restarting->prepared) : prepare(*settings);
    dem::DistributedWorld world(MPI_COMM_WORLD, prepared.scenario.world);
    // Rank 0's note is the one its checkpoints and the folder's marker carry.
    const DemRunNote note = restarting ? restarting->note : noteOf(options, prepared);
    if (root && output) orAbort([&] { writeRunMarker(options.out, note.run); });
    DemCheckpoints checkpoints(
        options.out, restarting ? restarting->checkpointEvery : options.checkpointEvery, note);
    Continuation continuation;
    if (restarting) continuation = restarting->continuation;
    continuation.checkpoints = &checkpoints;
    const RunSummary summary = simulateDistributed(
        prepared.scenario, world, prepared.steps, prepared.outputEvery, output.get(),
        showProgress(options.quiet || options.json), continuation);
    if (root) report(options, prepared, summary, output.get());
  } catch (const Error& error) {
    // Every rank meets it; rank 0 reports it before any rank leaves: mpirun stops the others
    // when one exits with a failure, and rank 0, slower under load, was sometimes stopped
    // before its line.
    if (root) {
      std::string line = error.what();
      for (char& c : line)
        if (c == '\n' || c == '\r') c = ' ';
      std::fprintf(stderr, "delta: %s\n", line.c_str());
      std::fflush(stderr);
    }
    MPI_Barrier(MPI_COMM_WORLD);
    throw QuietFailure{};
  }
}
#endif

void run(const DemOptions& options) {
#ifdef DELTA_WITH_MPI
  if (startedByMpirun()) return runDistributed(options);
#endif
  if (!options.restart.empty()) return restart(options);
  if (options.checkpointEvery > 0 && options.out.empty())
    throw Error("--checkpoint-every needs --out DIR: the checkpoint is kept there");
  const DemSettings settings = resolve(options);
  std::unique_ptr<DemOutput> output;
  const DemFrames frames = framesOf(options);
  std::unique_ptr<RunLock> lock;  // held until the output is closed (declared before it)
  if (!options.out.empty()) {     // fail early
    makeOutputFolder(options.out);
    lock = std::make_unique<RunLock>(options.out, "delta dem");
    if (!lock->note().empty()) std::fprintf(stderr, "delta: note: %s\n", lock->note().c_str());
    prepareOutputFolder(options.out, earlierOutput(options), options.restart);
    output = std::make_unique<DemOutput>(options.out, frames);
  }
  Prepared prepared = prepare(settings);
  const DemRunNote note = noteOf(options, prepared);
  if (output) writeRunMarker(options.out, note.run);
  DemCheckpoints checkpoints(options.out, options.checkpointEvery, note);
  const RunSummary summary = simulate(prepared.scenario, prepared.steps, prepared.outputEvery,
                                      output.get(), showProgress(options.quiet || options.json),
                                      Continuation{&checkpoints, false, false, {}});
  report(options, prepared, summary, output.get());
}

constexpr const char* kFooter = R"(Threads: delta --threads N dem ... (or OMP_NUM_THREADS).

Config file (SCENARIO or --config FILE): one 'key = value' a line, '#' starts a comment,
each key at most once; options given on the command line override it.
  scenario        = hopper        # two-particles, settle or hopper
  particles       = 1000          # settle (default 100), hopper (default 1000)
  seed            = 1             # settle, hopper: shapes, turns and placement
  restitution     = 0.5           # e in [0, 1] (two-particles 0.9, settle and hopper 0.5)
  friction        = 0.3           # Coulomb mu >= 0 (two-particles 0, settle 0.5, hopper 0.3)
  offset          = 0             # two-particles: sideways shift / sum of radii, in [0, 1)
  steps           = 20000         # default: the scenario's own run
  output_every    = 200           # steps between frames with --out (default: ~100 frames)
  particle_mesh   = rock.off      # every particle this closed mesh (file relative to the
                                  # config, or builtin:...) instead of the scenario's shapes
  particle_radius = 0.01          # its bounding radius in m (default and at most: the
                                  # scenario's largest particle)
  contact_model   = point         # point: spring-dashpot on the epsilon-shell (default);
                                  # volume: energy-conserving, on the overlap volume (closed
                                  # obstacles: settle's box and hopper's funnel and floor get
                                  # solid walls a grain thick)

--out DIR writes, compressed (zlib; ParaView reads it), particles_state.pvd
(particles_state_NNNNNN.vtp: a point per particle with its id, shape, velocity,
angular_velocity, orientation quaternion w,x,y,z and bounding_radius) and shape_K.vtp (each
shape in its body frame, to glyph at those points); with --frames triangles or both,
particles.pvd (particles_NNNNNN.vtp: every particle's triangles, particle id, shape,
velocity); contacts.pvd (contacts_NNNNNN.vtp: points with force, direction, depth, distance,
overlap, converged, particle, other, with_obstacle, volume and couple, the last two the volume
law's, 0 in the point law), obstacles.vtp and log.csv (energies, contacts, step times and
energy_change, one row per step). Every file is written whole or not at all, a frame before
the .pvd that lists it, so the folder is valid at any instant, kill -9 included. A run holds
DIR/.delta.lock while it writes: a second run into DIR is refused while the first is running,
and a run into a folder that holds an earlier run's output is refused unless --overwrite (which
removes only those files).

Guards: a time step above the stable one and particles that start overlapping are reported
(stderr and the summary's warnings); a state that stops being finite, or a particle that
would move farther in a step than the contact shell catches, stops the run with an error
naming the particle and the largest safe time step.

Checkpoints: --checkpoint-every N keeps DIR/checkpoint.delta (every N steps and at the end);
SIGINT, SIGTERM and SIGHUP finish the step, write it (with --out) and exit 130, 143 and 129.
delta dem --restart DIR/checkpoint.delta [--steps TOTAL] goes on from it, bit for bit: the
same state_digest (--json) as a run that was never stopped, on any thread or rank count.

Under mpirun (where delta was built with MPI): mpirun -np P delta dem ... splits the particles
over P ranks (recursive coordinate bisection, split again when the counts drift 10% apart),
with the same trajectories as one process; frames are .pvtp files of one piece per rank, and
the summary adds each rank's load. As root: mpirun --allow-run-as-root; more ranks than
cores: --oversubscribe.)";

}  // namespace

void addDemCommand(CLI::App& app) {
  auto options = std::make_shared<DemOptions>();
  CLI::App* dem = app.add_subcommand(
      "dem", "Run a DEM simulation of triangulated particles: built-in scenario or config file");
  dem->footer(kFooter);
  dem->add_option("SCENARIO", options->scenario,
                  "two-particles, settle or hopper (default), or a config file")
      ->type_name("SCENARIO|FILE");
  dem->add_option("--config", options->config, "Read the settings from FILE (format below)")
      ->type_name("FILE");
  const auto setting = [&](const char* option, const char* key, const char* type,
                           const char* help) {
    dem->add_option_function<std::string>(
           option, [options, key](const std::string& text) { options->given[key] = text; }, help)
        ->type_name(type);
  };
  setting("--steps", "steps", "N", "Time steps to run (default: the scenario's run)");
  setting("--particles", "particles", "N", "settle, hopper: how many particles");
  setting("--seed", "seed", "S", "settle, hopper: random seed of shapes and placement");
  setting("--restitution", "restitution", "E", "Coefficient of restitution e in [0, 1]");
  setting("--friction", "friction", "MU", "Coulomb friction coefficient mu >= 0");
  setting("--offset", "offset", "F",
          "two-particles: sideways offset as a fraction of the sum of radii, in [0, 1)");
  setting("--output-every", "output_every", "N", "Steps between frames written with --out");
  setting("--particle-mesh", "particle_mesh", "MESH",
          "Every particle this closed mesh (file or builtin:...) instead of the scenario's");
  setting("--particle-radius", "particle_radius", "R",
          "Bounding radius (m) the particle mesh is scaled to");
  setting("--contact-model", "contact_model", "point|volume",
          "Contact law: point (spring-dashpot on the epsilon-shell, the default) or volume "
          "(energy-conserving, on the overlap volume)");
  dem->add_option("--out", options->out,
                  "Write a ParaView series and log.csv into folder DIR (made if missing)")
      ->type_name("DIR");
  dem->add_option_function<std::string>(
         "--frames",
         [options](const std::string& text) {
           options->frames = text;
           options->framesGiven = true;
         },
         "What each frame shows of the particles with --out: state (a point per particle, the "
         "default), triangles (their surfaces, ~16x larger) or both")
      ->type_name("state|triangles|both");
  dem->add_flag("--overwrite", options->overwrite,
                "Replace the output of an earlier run in --out (a run is refused otherwise)");
  dem->add_flag("--json", options->json, "Print one JSON object instead of text");
  dem->add_flag("--quiet", options->quiet, "No progress line");
  // Parsed as the step counts are: CLI11's unsigned conversion wrapped -1 round and saturated
  // 2^64, and such a run went on without periodic checkpoints.
  dem->add_option_function<std::string>(
         "--checkpoint-every",
         [options](const std::string& text) {
           options->checkpointEvery = parseStepCount(text, "--checkpoint-every", 0);
         },
         "Keep a checkpoint of the run, DIR/checkpoint.delta (--out DIR), written every N steps "
         "and at the end (and when stopped by SIGINT, SIGTERM or SIGHUP)")
      ->type_name("N");
  dem->add_option("--restart", options->restart,
                  "Continue the run a checkpoint holds; --steps is then the run's total, --out "
                  "defaults to the checkpoint's folder")
      ->type_name("FILE");
  dem->callback([options] {
    try {
      run(*options);
    } catch (const StoppedBySignal& stopped) {
      // The files are closed and the lock released (unwound); say where to go on from.
      std::fflush(stdout);
      if (!stopped.report) std::exit(128 + stopped.signal);  // another rank's line says it
      const char* name = stopped.signal == SIGINT    ? "SIGINT"
                         : stopped.signal == SIGTERM ? "SIGTERM"
                                                     : "SIGHUP";
      // A new line ends the progress line where there is one; otherwise the message is the
      // only line.
      if (showProgress(options->quiet || options->json)) std::fputc('\n', stderr);
      if (options->out.empty() && options->restart.empty())
        std::fprintf(stderr, "delta: stopped by %s after step %zu (no --out: no checkpoint)\n",
                     name, stopped.step);
      else {
        const std::filesystem::path folder =
            !options->out.empty() ? std::filesystem::path(options->out)
            : std::filesystem::path(options->restart).has_parent_path()
                ? std::filesystem::path(options->restart).parent_path()
                : std::filesystem::path(".");
        const std::string path = (folder / kCheckpointName).string();
        std::fprintf(stderr,
                     "delta: stopped by %s after step %zu; checkpoint %s (continue: delta dem "
                     "--restart %s)\n",
                     name, stopped.step, path.c_str(), path.c_str());
      }
      std::fflush(stderr);
      std::exit(128 + stopped.signal);
    }
  });
}

}  // namespace delta::cli
