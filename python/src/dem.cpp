// delta.dem: Parameters, ParticleShape, World, RestitutionMeter, Scenario and the built-in
// scenarios. A World steps without the GIL; while it does, other threads' calls on it raise.
#include <Python.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/dem/checkpoint.h"
#include "delta/dem/particle_shape.h"
#include "delta/dem/scenarios.h"
#include "delta/dem/world.h"

#include "arrays.h"
#include "bindings.h"
#include "handles.h"
#include "records.h"

namespace delta::python {
namespace {

using namespace pybind11::literals;

constexpr const char* kWorld = "delta.dem.World";
/// Time between looks for a pending KeyboardInterrupt during World.run. By time, not by steps:
/// a look takes the GIL, and a run of short steps that took it every few microseconds starved
/// the thread that was to raise the interrupt (Python hands the GIL over on request only to a
/// thread that waited 5 ms without seeing it change hands).
constexpr auto kSignalCheckInterval = std::chrono::milliseconds(10);

static_assert(sizeof(Quaternion) == 4 * sizeof(double), "a Quaternion is (w, x, y, z)");
static_assert(std::is_trivially_copyable_v<dem::Particle> &&
              std::is_trivially_copyable_v<dem::Contact>);

/// A World and the restitution meters watching it.
///
/// Threading: used with the GIL held; run() steps without it, holding the busy flag, and every
/// other use checks the flag (RuntimeError while another thread runs the world).
class PyWorld {
 public:
  explicit PyWorld(dem::World world) : world_(std::move(world)) {}

  const dem::World& read() const {
    busy_.check(kWorld);
    return world_;
  }
  dem::World& write() {
    busy_.check(kWorld);
    return world_;
  }

  /// Advances by `steps` time steps without the GIL, the meters looking after each; stops with
  /// KeyboardInterrupt (between steps) when one is pending.
  void run(std::size_t steps) {
    const BusyFlag::Hold hold(busy_, kWorld);
    py::gil_scoped_release release;
    auto lookedAt = std::chrono::steady_clock::now();
    for (std::size_t step = 1; step <= steps; ++step) {
      world_.step();
      for (const std::shared_ptr<dem::RestitutionMeter>& meter : meters_)
        meter->observe(world_);
      if (step < steps && std::chrono::steady_clock::now() - lookedAt >= kSignalCheckInterval) {
        py::gil_scoped_acquire acquire;
        if (PyErr_CheckSignals() != 0) throw py::error_already_set();
        lookedAt = std::chrono::steady_clock::now();
      }
    }
  }

  std::shared_ptr<const dem::RestitutionMeter> addMeter(std::size_t first, std::size_t second) {
    meters_.push_back(std::make_shared<dem::RestitutionMeter>(read(), first, second));
    return meters_.back();
  }

  const BusyFlag& busy() const noexcept { return busy_; }

 private:
  dem::World world_;
  std::vector<std::shared_ptr<dem::RestitutionMeter>> meters_;
  BusyFlag busy_;
};

/// A restitution meter as Python holds it: with its world, whose busy flag guards its reading.
struct PyMeter {
  std::shared_ptr<PyWorld> world;
  std::shared_ptr<const dem::RestitutionMeter> meter;

  const dem::RestitutionMeter& read() const {
    world->busy().check(kWorld);
    return *meter;
  }
};

/// A scenario as Python holds it: the World moved into a PyWorld.
struct PyScenario {
  std::string name;
  std::shared_ptr<PyWorld> world;
  std::size_t steps = 0;
  std::size_t outputInterval = 1;
  std::shared_ptr<PyMeter> meter;  ///< two-particles: measures the collision; else null
};

PyScenario adopt(dem::Scenario&& scenario) {
  PyScenario adopted{scenario.name, std::make_shared<PyWorld>(std::move(scenario.world)),
                     scenario.steps, scenario.outputInterval, nullptr};
  if (adopted.name == "two-particles")
    adopted.meter =
        std::make_shared<PyMeter>(PyMeter{adopted.world, adopted.world->addMeter(0, 1)});
  return adopted;
}

template <typename Make>
PyScenario scenario(const Make& make) {
  dem::Scenario made = [&] {
    py::gil_scoped_release release;
    return make();
  }();
  return adopt(std::move(made));
}

dem::ParticleKind kindNamed(const std::string& kind) {
  if (kind == "mesh") return dem::ParticleKind::Mesh;
  if (kind == "sphere") return dem::ParticleKind::Sphere;
  throw Error("kind '" + kind + "': use mesh or sphere");
}

py::dtype particleDtype() {
  using dem::Particle;
  return recordDtype({{"shape", "u4", offsetof(Particle, shape)},
                      {"position", "(3,)f8", offsetof(Particle, position)},
                      {"orientation", "(4,)f8", offsetof(Particle, orientation)},
                      {"velocity", "(3,)f8", offsetof(Particle, velocity)},
                      {"angular_velocity", "(3,)f8", offsetof(Particle, angularVelocity)},
                      {"angular_momentum", "(3,)f8", offsetof(Particle, angularMomentum)},
                      {"force", "(3,)f8", offsetof(Particle, force)},
                      {"torque", "(3,)f8", offsetof(Particle, torque)}},
                     sizeof(Particle));
}

py::dtype worldContactDtype() {
  using dem::Contact;
  py::list names = contactFieldNames(), formats = contactFieldFormats(),
           offsets = contactFieldOffsets(offsetof(Contact, point));
  const auto add = [&](const char* name, const char* format, std::size_t offset) {
    names.append(name);
    formats.append(format);
    offsets.append(offset);
  };
  add("first", "u4", offsetof(Contact, first));
  add("second", "u4", offsetof(Contact, second));
  add("with_obstacle", "?", offsetof(Contact, withObstacle));
  add("depth", "f8", offsetof(Contact, depth));
  add("force", "(3,)f8", offsetof(Contact, force));
  add("couple", "(3,)f8", offsetof(Contact, couple));
  add("volume", "f8", offsetof(Contact, volume));
  return py::dtype(names, formats, offsets, static_cast<py::ssize_t>(sizeof(Contact)));
}

/// A copy of `records` as a NumPy array of `dtype` (laid over T).
template <typename T>
py::array recordCopy(std::span<const T> records, const py::dtype& dtype) {
  py::array array(dtype, std::vector<py::ssize_t>{static_cast<py::ssize_t>(records.size())});
  if (!records.empty()) std::memcpy(array.mutable_data(), records.data(), records.size_bytes());
  return array;
}

/// One Vec3 of every particle, (n, 3).
template <typename Member>
py::array particleVectors(const PyWorld& world, Member member) {
  std::vector<Vec3> values;
  for (const dem::Particle& particle : world.read().particles())
    values.push_back(particle.*member);
  return vec3Array(values);
}

void bindParameters(py::module_& dem) {
  py::class_<dem::Parameters>(dem, "Parameters", R"(What a World simulates with.

Parameters(time_step, epsilon, filter_distance, stiffness, restitution=0.5, friction=0.0,
tangential_stiffness_ratio=2/7, gravity=(0, 0, -9.81), contact_model='point'), any consistent
units (the scenarios use SI): dt > 0; surfaces closer than 2*epsilon are in contact; contact
points of a pair closer than filter_distance (h) are merged; stiffness k > 0 of the normal
spring; e in [0, 1]; Coulomb friction mu >= 0; contact_model 'point' (the spring-dashpot on the
epsilon-shell) or 'volume' (energy-conserving, on the overlap volume of closed meshes). Checked
when a World is made (delta.Error naming the field).)")
      .def(py::init([](double timeStep, double epsilon, double filterDistance, double stiffness,
                       double restitution, double friction, double tangentialStiffnessRatio,
                       const Vec3& gravity, const std::string& contactModel) {
             return dem::Parameters{timeStep,
                                    epsilon,
                                    filterDistance,
                                    stiffness,
                                    restitution,
                                    friction,
                                    tangentialStiffnessRatio,
                                    gravity,
                                    dem::contactModelNamed(contactModel)};
           }),
           "time_step"_a, "epsilon"_a, "filter_distance"_a, "stiffness"_a,
           "restitution"_a = dem::Parameters{}.restitution, "friction"_a = 0.0,
           "tangential_stiffness_ratio"_a = dem::Parameters{}.tangentialStiffnessRatio,
           py::arg_v("gravity", dem::Parameters{}.gravity, "(0, 0, -9.81)"),
           "contact_model"_a = "point", "The parameters of a World; see the class.")
      .def_readwrite("time_step", &dem::Parameters::timeStep, "dt > 0.")
      .def_readwrite("epsilon", &dem::Parameters::epsilon,
                     "Surfaces closer than 2*epsilon are in contact.")
      .def_readwrite("filter_distance", &dem::Parameters::filterDistance,
                     "h: contact points of a pair closer than h are merged (delta.filter).")
      .def_readwrite("stiffness", &dem::Parameters::stiffness,
                     "k > 0, the normal spring of a pair.")
      .def_readwrite("restitution", &dem::Parameters::restitution,
                     "e in [0, 1], the normal coefficient of restitution.")
      .def_readwrite("friction", &dem::Parameters::friction,
                     "mu >= 0, the Coulomb coefficient (0: frictionless).")
      .def_readwrite("tangential_stiffness_ratio", &dem::Parameters::tangentialStiffnessRatio,
                     "k_t / k, used when friction > 0.")
      .def_property(
          "gravity", [](const dem::Parameters& p) { return p.gravity; },
          [](dem::Parameters& p, const Vec3& gravity) { p.gravity = gravity; },
          "The acceleration of gravity, (3,).")
      .def_property(
          "contact_model",
          [](const dem::Parameters& p) {
            return std::string(dem::contactModelName(p.contactModel));
          },
          [](dem::Parameters& p, const std::string& name) {
            p.contactModel = dem::contactModelNamed(name);
          },
          "'point' (the spring-dashpot on the epsilon-shell) or 'volume' (energy-conserving, on "
          "the overlap volume; closed meshes only, no sphere particles).")
      .def("__repr__", [](const dem::Parameters& p) {
        return py::str(
                   "Parameters(time_step={!r}, epsilon={!r}, filter_distance={!r}, "
                   "stiffness={!r}, restitution={!r}, friction={!r}, contact_model={!r})")
            .format(p.timeStep, p.epsilon, p.filterDistance, p.stiffness, p.restitution, p.friction,
                    dem::contactModelName(p.contactModel))
            .cast<std::string>();
      });
}

void bindParticleShape(py::module_& dem) {
  py::class_<dem::ParticleShape>(dem, "ParticleShape", R"(The shape of a rigid particle.

ParticleShape(mesh, density): a closed, outward-oriented Mesh (delta.Error otherwise) prepared
for contacts, with the mass properties of the solid it bounds; its body frame has the centre of
mass at the origin (`centroid` says where that was in the mesh's coordinates).
ParticleShape.sphere(radius, density) is an exact ball. Shared by every particle made from it.)")
      .def(py::init([](const PyMesh& mesh, double density) {
             const std::shared_ptr<const Mesh> snapshot = mesh.snapshot();
             py::gil_scoped_release release;
             return dem::ParticleShape(*snapshot, density);
           }),
           "mesh"_a, "density"_a,
           "The shape of this closed mesh at this density (mass properties, prepared mesh).")
      .def_static("sphere", &dem::ParticleShape::sphere, "radius"_a, "density"_a,
                  "display_subdivisions"_a = 2,
                  "A ball of `radius` (exact contacts and mass); shown as an icosphere.")
      .def_property_readonly("is_sphere", &dem::ParticleShape::isSphere,
                             "An exact ball (ParticleShape.sphere), not a mesh.")
      .def_property_readonly(
          "mesh", [](const dem::ParticleShape& shape) { return PyMesh(shape.mesh()); },
          "The surface in the body frame (a copy).")
      .def_property_readonly(
          "query_mesh", [](const dem::ParticleShape& shape) { return shape.queryMesh(); },
          "The surface prepared for queries, body frame (a copy).")
      .def_property_readonly("density", &dem::ParticleShape::density, "Mass per volume.")
      .def_property_readonly("volume", &dem::ParticleShape::volume, "The volume of the solid.")
      .def_property_readonly("mass", &dem::ParticleShape::mass, "density * volume.")
      .def_property_readonly("inertia", &dem::ParticleShape::inertia,
                             "Inertia tensor about the centre of mass, body frame, (3, 3).")
      .def_property_readonly("bounding_radius", &dem::ParticleShape::boundingRadius,
                             "The largest distance from the centre of mass to the surface.")
      .def_property_readonly("centroid", &dem::ParticleShape::centroid,
                             "The centre of mass in the coordinates of the mesh given.");
}

void bindWorld(py::module_& dem) {
  py::class_<PyMeter, std::shared_ptr<PyMeter>>(
      dem, "RestitutionMeter",
      "Measures the normal coefficient of restitution of a collision of two particles: their "
      "relative velocity along the line of centres after they part over the one before they "
      "met. Made by World.meter_restitution; it looks at the world after every step.")
      .def_property_readonly(
          "collided", [](const PyMeter& m) { return m.read().collided(); },
          "The particles have touched.")
      .def_property_readonly(
          "separated", [](const PyMeter& m) { return m.read().separated(); },
          "They touched and are apart again.")
      .def_property_readonly(
          "restitution", [](const PyMeter& m) { return m.read().restitution(); },
          "|v_after . n| / |v_before . n|; NaN until the particles touched and parted.");

  py::class_<PyWorld, std::shared_ptr<PyWorld>>(dem, "World", R"(A DEM simulation.

World(parameters): rigid particles (closed triangle meshes or spheres) and obstacles (walls,
floors, funnels: any mesh, with a prescribed motion), advanced by velocity Verlet with the seed's
spring-dashpot contact law at Delta's mesh-mesh contact points. `step()` and `run(n)` run without
the GIL and in parallel (Delta's thread pool; OMP_NUM_THREADS), bitwise the same for any thread
count.

Reading: `particles` (a structured array copy: shape, position, orientation (w, x, y, z),
velocity, angular_velocity, angular_momentum, force, torque), `positions`, `velocities`,
`angular_velocities` (n, 3) and `orientations` (n, 4) copies, `contacts` (the last step's contact
points with their forces), `statistics`, `energies()`, `time`, `step_count`.

Threading: one Python thread at a time; a call while another thread runs the world raises
RuntimeError.)")
      .def(py::init([](const dem::Parameters& parameters) {
             return std::make_shared<PyWorld>(dem::World(parameters));
           }),
           "parameters"_a, "An empty world with these Parameters (delta.Error when invalid).")
      .def(
          "add_shape",
          [](PyWorld& world, const PyMesh& mesh, double density) {
            return world.write().addShape(mesh.mesh(), density);
          },
          "mesh"_a, "density"_a, "Adds a particle shape from a closed mesh; returns its index.")
      .def(
          "add_shape",
          [](PyWorld& world, const dem::ParticleShape& shape) {
            return world.write().addShape(shape);
          },
          "shape"_a, "Adds a ParticleShape (sharing its prepared mesh); returns its index.")
      .def(
          "add_particle",
          [](PyWorld& world, std::size_t shape, const Vec3& position, const Quaternion& orientation,
             const Vec3& velocity, const Vec3& angularVelocity) {
            return world.write().addParticle(shape,
                                             {position, orientation, velocity, angularVelocity});
          },
          "shape"_a, "position"_a, py::arg_v("orientation", Quaternion{}, "Quaternion()"),
          py::arg_v("velocity", Vec3{}, "(0, 0, 0)"),
          py::arg_v("angular_velocity", Vec3{}, "(0, 0, 0)"),
          "Adds a particle of shape index `shape` with its centre of mass at `position`; returns "
          "its index.")
      .def(
          "add_obstacle",
          [](PyWorld& world, const PyMesh& mesh, const Vec3& velocity, const Vec3& angularVelocity,
             const Vec3& pivot) {
            return world.write().addObstacle(mesh.mesh(), {velocity, angularVelocity, pivot});
          },
          "mesh"_a, py::arg_v("velocity", Vec3{}, "(0, 0, 0)"),
          py::arg_v("angular_velocity", Vec3{}, "(0, 0, 0)"),
          py::arg_v("pivot", Vec3{}, "(0, 0, 0)"),
          "Adds an obstacle (open or closed mesh), moving at `velocity` and turning about "
          "`pivot` at `angular_velocity`; returns its index.")
      .def(
          "set_time_step",
          [](PyWorld& world, double timeStep) { world.write().setTimeStep(timeStep); },
          "time_step"_a,
          "Changes dt from the next step on (the forces at the current state stay: they do not "
          "depend on the step that follows).")
      .def(
          "set_pose",
          [](PyWorld& world, std::size_t particle, const Vec3& position,
             const Quaternion& orientation) {
            world.write().setPose(particle, position, orientation);
          },
          "particle"_a, "position"_a, "orientation"_a,
          "Puts a particle's centre of mass at `position`, turned by `orientation`.")
      .def(
          "set_velocity",
          [](PyWorld& world, std::size_t particle, const Vec3& velocity) {
            world.write().setVelocity(particle, velocity);
          },
          "particle"_a, "velocity"_a, "Sets a particle's velocity.")
      .def(
          "set_angular_velocity",
          [](PyWorld& world, std::size_t particle, const Vec3& angularVelocity) {
            world.write().setAngularVelocity(particle, angularVelocity);
          },
          "particle"_a, "angular_velocity"_a, "Sets a particle's angular velocity (world frame).")
      .def(
          "step", [](PyWorld& world) { world.run(1); },
          "Advances by one time step. A step that fails raises delta.Error and leaves the world "
          "as it was before it (only the last step's contacts may be gone with it).")
      .def("run", &PyWorld::run, "steps"_a,
           "Advances by `steps` time steps without the GIL (Ctrl-C stops it between steps); a "
           "step that fails raises delta.Error and leaves the world as the steps before it left "
           "it.")
      .def(
          "meter_restitution",
          [](const std::shared_ptr<PyWorld>& world, std::size_t first, std::size_t second) {
            return std::make_shared<PyMeter>(PyMeter{world, world->addMeter(first, second)});
          },
          "first"_a = 0, "second"_a = 1,
          "A RestitutionMeter for the collision of two particles from now on.")
      .def(
          "save",
          // A path, not a string: pybind11 refuses an embedded NUL (TypeError) where the C
          // calls would stop at it and write another file.
          [](const PyWorld& world, const std::filesystem::path& path) {
            const dem::World& read = world.read();
            py::gil_scoped_release release;
            read.save(path);
          },
          "path"_a,
          "Writes a checkpoint of the whole state to `path`, atomically (delta.Error naming the "
          "path and the reason). World.load(path) continues bit for bit where this world "
          "would.")
      .def_static(
          "load",
          [](const std::filesystem::path& path) {
            std::optional<dem::World> loaded;
            {
              py::gil_scoped_release release;
              loaded.emplace(dem::World::load(path));
            }
            return std::make_shared<PyWorld>(std::move(*loaded));
          },
          "path"_a,
          "The World a checkpoint file holds (delta.Error when it is missing, not a checkpoint, "
          "of another version, truncated or corrupt).")
      .def_property_readonly(
          "state_digest", [](const PyWorld& world) { return world.read().stateDigest(); },
          "16 hex digits of a hash of the state (time, step, every particle's pose, velocities, "
          "angular momentum, forces, and the friction springs): equal states, equal digests.")
      .def(py::pickle(
          [](const PyWorld& world) { return py::bytes(dem::checkpointBytes(world.read())); },
          [](const py::bytes& bytes) {
            return std::make_shared<PyWorld>(
                std::move(dem::readCheckpoint(std::string(bytes), "pickled World").world));
          }))
      .def_property_readonly(
          "parameters", [](const PyWorld& world) { return world.read().parameters(); },
          "The Parameters (a copy).")
      .def_property_readonly(
          "shapes",
          [](const PyWorld& world) {
            const std::span<const dem::ParticleShape> shapes = world.read().shapes();
            return std::vector<dem::ParticleShape>(shapes.begin(), shapes.end());
          },
          "The particle shapes (copies sharing the prepared meshes).")
      .def_property_readonly(
          "particle_count", [](const PyWorld& world) { return world.read().particles().size(); },
          "The number of particles.")
      .def_property_readonly(
          "obstacle_count", [](const PyWorld& world) { return world.read().obstacles().size(); },
          "The number of obstacles.")
      .def_property_readonly(
          "particles",
          [](const PyWorld& world) {
            return recordCopy(world.read().particles(), particleDtype());
          },
          "Every particle's state, a structured array (a copy).")
      .def_property_readonly(
          "positions",
          [](const PyWorld& world) { return particleVectors(world, &dem::Particle::position); },
          "Centres of mass, (n, 3) float64 (a copy).")
      .def_property_readonly(
          "velocities",
          [](const PyWorld& world) { return particleVectors(world, &dem::Particle::velocity); },
          "Velocities of the centres of mass, (n, 3) float64 (a copy).")
      .def_property_readonly(
          "angular_velocities",
          [](const PyWorld& world) {
            return particleVectors(world, &dem::Particle::angularVelocity);
          },
          "Angular velocities, world frame, (n, 3) float64 (a copy).")
      .def_property_readonly(
          "orientations",
          [](const PyWorld& world) {
            const std::span<const dem::Particle> particles = world.read().particles();
            py::array_t<double> wxyz({static_cast<py::ssize_t>(particles.size()), py::ssize_t{4}});
            auto out = wxyz.mutable_unchecked<2>();
            for (std::size_t i = 0; i < particles.size(); ++i) {
              const Quaternion& q = particles[i].orientation;
              const auto row = static_cast<py::ssize_t>(i);
              out(row, 0) = q.w;
              out(row, 1) = q.x;
              out(row, 2) = q.y;
              out(row, 3) = q.z;
            }
            return wxyz;
          },
          "Orientations (w, x, y, z), body frame to world, (n, 4) float64 (a copy).")
      .def_property_readonly(
          "contacts",
          [](const PyWorld& world) {
            return recordCopy(world.read().contacts(), worldContactDtype());
          },
          "The contact points of the last force evaluation with their forces, a structured "
          "array (a copy): the fields of delta.contact_dtype (triangle ids; 0 for a sphere), "
          "first and second (particle indices; second an obstacle where with_obstacle), depth "
          "(into the 2*epsilon shell) and force (on particle first).")
      .def_property_readonly(
          "statistics",
          [](const PyWorld& world) {
            const dem::StepStatistics& s = world.read().statistics();
            return py::dict(
                "particle_pairs_tested"_a = s.particlePairsTested,
                "obstacle_pairs_tested"_a = s.obstaclePairsTested,
                "pairs_in_contact"_a = s.pairsInContact,
                "raw_contact_points"_a = s.rawContactPoints, "contact_points"_a = s.contactPoints,
                "overlapping_contacts"_a = s.overlappingContacts,
                "deepest_ratio"_a = s.deepestRatio, "broad_phase_seconds"_a = s.broadPhaseSeconds,
                "contact_detection_seconds"_a = s.contactDetectionSeconds,
                "force_seconds"_a = s.forceSeconds, "integration_seconds"_a = s.integrationSeconds,
                "total_seconds"_a = s.totalSeconds);
          },
          "What the last step did, a dict (pairs, contact points, seconds per phase).")
      .def(
          "energies",
          [](const PyWorld& world) {
            const dem::Energies e = world.read().energies();
            return py::dict("translational"_a = e.translational, "rotational"_a = e.rotational,
                            "gravitational"_a = e.gravitational, "elastic"_a = e.elastic,
                            "kinetic"_a = e.kinetic(), "total"_a = e.total());
          },
          "The energies of the current state, a dict.")
      .def_property_readonly(
          "linear_momentum", [](const PyWorld& world) { return world.read().linearMomentum(); },
          "Sum of m v, (3,).")
      .def_property_readonly(
          "angular_momentum", [](const PyWorld& world) { return world.read().angularMomentum(); },
          "About the origin.")
      .def_property_readonly(
          "suggested_time_step",
          [](const PyWorld& world) { return world.read().suggestedTimeStep(); },
          "A stable time step for the stiffness and the lightest particle (0 without any).")
      .def_property_readonly(
          "time", [](const PyWorld& world) { return world.read().time(); }, "Simulated time.")
      .def_property_readonly(
          "step_count", [](const PyWorld& world) { return world.read().stepCount(); },
          "Steps taken.");
}

void bindScenarios(py::module_& dem) {
  py::class_<PyScenario>(dem, "Scenario",
                         "A World ready to run (`world`), with a sensible run length (`steps`), "
                         "the interval between output frames, and for two-particles a "
                         "`restitution_meter`.")
      .def_readonly("name", &PyScenario::name, "two-particles, settle or hopper.")
      .def_readonly("world", &PyScenario::world, "The World, ready to run.")
      .def_readonly("steps", &PyScenario::steps, "A sensible run, in time steps.")
      .def_readonly("output_interval", &PyScenario::outputInterval,
                    "Steps between frames for about a hundred frames.")
      .def_readonly("restitution_meter", &PyScenario::meter,
                    "For two-particles, the meter of their collision; None otherwise.")
      .def(
          "run",
          [](PyScenario& scenario, std::optional<std::size_t> steps) {
            scenario.world->run(steps.value_or(scenario.steps));
          },
          "steps"_a = py::none(), "Runs the world for `steps` (default: the scenario's run).");

  dem.def(
      "two_particles",
      [](double restitution, double offset, double friction, const std::string& contactModel) {
        const dem::ContactModel model = dem::contactModelNamed(contactModel);
        return scenario([&] { return dem::twoParticles(restitution, offset, friction, model); });
      },
      "restitution"_a = 0.9, "offset"_a = 0.0, "friction"_a = 0.0, "contact_model"_a = "point",
      "Two icospheres (1280 triangles, radius 1 cm) approaching head-on at 1 m/s (or offset "
      "sideways by `offset` times the sum of radii), no gravity; `delta dem two-particles`.");
  dem.def(
      "settle",
      [](std::size_t count, std::uint64_t seed, const std::string& kind,
         const std::string& contactModel) {
        const dem::ParticleKind particles = kindNamed(kind);
        const dem::ContactModel model = dem::contactModelNamed(contactModel);
        return scenario([&] { return dem::settle(count, seed, particles, model); });
      },
      "count"_a = 100, "seed"_a = 1, "kind"_a = "mesh", "contact_model"_a = "point",
      "`count` granulates (or spheres, kind='sphere') falling into an open box and settling "
      "(contact_model='volume': the box with solid walls).");
  dem.def(
      "hopper",
      [](std::size_t count, std::uint64_t seed, const std::string& kind,
         const std::string& contactModel) {
        const dem::ParticleKind particles = kindNamed(kind);
        const dem::ContactModel model = dem::contactModelNamed(contactModel);
        return scenario([&] { return dem::hopper(count, seed, particles, model); });
      },
      "count"_a = 1000, "seed"_a = 1, "kind"_a = "mesh", "contact_model"_a = "point",
      "`count` granulates (or spheres) flowing through a conical funnel onto a floor "
      "(contact_model='volume': a funnel and a floor with solid walls).");
  dem.def(
      "open_box",
      [](double width, double depth, double height, double floor) {
        return PyMesh(dem::openBox(width, depth, height, floor));
      },
      "width"_a, "depth"_a, "height"_a, "floor"_a = 0.0,
      "An open-top box (10 triangles, normals inward), an obstacle.");
  dem.def(
      "funnel",
      [](double outletRadius, double topRadius, double outletHeight, double topHeight, int segments,
         int rows) {
        return PyMesh(
            dem::funnel(outletRadius, topRadius, outletHeight, topHeight, segments, rows));
      },
      "outlet_radius"_a, "top_radius"_a, "outlet_height"_a, "top_height"_a, "segments"_a = 48,
      "rows"_a = 12, "A funnel about the z axis (a truncated cone, open), an obstacle.");
  const auto meshes = [](const std::vector<Mesh>& pieces) {
    std::vector<PyMesh> list;
    for (const Mesh& piece : pieces)
      list.emplace_back(piece);
    return list;
  };
  dem.def(
      "open_box_walls",
      [meshes](double width, double depth, double height, double floor, double thickness) {
        return meshes(dem::openBoxWalls(width, depth, height, floor, thickness));
      },
      "width"_a, "depth"_a, "height"_a, "floor"_a, "thickness"_a,
      "open_box made solid for contact_model='volume': five closed convex boxes `thickness` "
      "thick behind its faces, each an obstacle of its own.");
  dem.def(
      "funnel_walls",
      [meshes](double outletRadius, double topRadius, double outletHeight, double topHeight,
               int segments, double thickness) {
        return meshes(dem::funnelWalls(outletRadius, topRadius, outletHeight, topHeight, segments,
                                       thickness));
      },
      "outlet_radius"_a, "top_radius"_a, "outlet_height"_a, "top_height"_a, "segments"_a,
      "thickness"_a,
      "funnel made solid for contact_model='volume': `segments` closed convex pieces `thickness` "
      "thick behind its faces, each an obstacle of its own.");
}

}  // namespace

void bindDem(py::module_& dem) {
  dem.attr("particle_dtype") = particleDtype();
  dem.attr("contact_dtype") = worldContactDtype();
  bindParameters(dem);
  bindParticleShape(dem);
  bindWorld(dem);
  bindScenarios(dem);
}

}  // namespace delta::python
