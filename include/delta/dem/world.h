#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/contact_point.h"
#include "delta/core/rotation.h"
#include "delta/core/sphere.h"
#include "delta/core/vec3.h"
#include "delta/dem/contact_model.h"
#include "delta/dem/narrow_phase.h"
#include "delta/dem/particle_shape.h"
#include "delta/mesh/mesh.h"
#include "delta/query/query_mesh.h"
#include "delta/query/sphere_contacts.h"

/// The Discrete Element Method case study: rigid triangulated (or spherical) particles and
/// obstacles, the seed's spring–dashpot contact law, and explicit time stepping (World); and its
/// pieces (broad phase, narrow phase, contact law) for DEM codes that have their own loop.
namespace delta::dem {

/// What a World simulates with. Lengths, masses and times in any consistent units (the
/// scenarios use SI). Every field is checked when a World is made or changed (delta::Error
/// naming the field and its value); the zeros below must be set.
///
/// Threading: a value type; no shared state.
struct Parameters {
  double timeStep = 0.0;  ///< dt > 0; see World::suggestedTimeStep
  /// ε, from 2⁻⁴⁸¹ to 2²⁰⁰ (what the contact queries take): surfaces closer than 2ε are in
  /// contact.
  double epsilon = 0.0;
  /// h, from 2⁻⁴⁸¹ to 2²⁰⁰: contact points of a pair closer than h are merged.
  double filterDistance = 0.0;
  double stiffness = 0.0;    ///< k > 0, the normal spring of a pair (contact_model.h)
  double restitution = 0.5;  ///< e in [0, 1], normal coefficient of restitution
  double friction = 0.0;     ///< μ ≥ 0, Coulomb coefficient; 0 is frictionless
  double tangentialStiffnessRatio = 2.0 / 7.0;  ///< k_t / k > 0, used when μ > 0
  Vec3 gravity{0.0, 0.0, -9.81};                ///< acceleration, finite
  /// The contact law (contact_model.h): the point law on the ε-shell, or the energy-conserving
  /// volume law, which needs closed meshes (particles and obstacles) and no sphere particles.
  ContactModel contactModel = ContactModel::point;
};

/// How a particle starts.
///
/// Threading: a value type; no shared state.
struct ParticleState {
  Vec3 position;           ///< of the centre of mass, world frame
  Quaternion orientation;  ///< body frame to world (renormalised on entry)
  Vec3 velocity;           ///< of the centre of mass
  Vec3 angularVelocity;    ///< world frame
};

/// A rigid particle as the World moves it. The angular momentum (world frame, about the centre
/// of mass) is the integrated state; the angular velocity follows from it, ω = R·I⁻¹·Rᵀ·L.
/// `force` and `torque` are the contact forces (gravity excluded) at the current state, the
/// torque about the centre of mass.
///
/// Threading: a value type; no shared state.
struct Particle {
  std::uint32_t shape = 0;  ///< index into World::shapes()
  Vec3 position;
  Quaternion orientation;
  Vec3 velocity;
  Vec3 angularVelocity;
  Vec3 angularMomentum;
  Vec3 force;
  Vec3 torque;

  /// Body frame to world: where the shape's mesh is now.
  RigidTransform pose() const noexcept { return {orientation, position}; }
};

/// A prescribed rigid motion of an obstacle: its `pivot` (a point moving with the obstacle,
/// given where it is at the start) moves at `velocity` and the obstacle turns about it at
/// `angularVelocity` (world frame). All zero: a static obstacle.
///
/// Threading: a value type; no shared state.
struct ObstacleMotion {
  Vec3 velocity;
  Vec3 angularVelocity;
  Vec3 pivot;
};

/// A wall, floor, container or funnel: a triangle mesh (open or closed) that pushes particles
/// and is not pushed back. The normal sense of an open mesh does not matter: a contact's
/// direction comes from the gap (from the wall toward the particle).
///
/// Threading: a value type whose QueryMesh shares its prepared data; read-only use from any
/// number of threads.
struct Obstacle {
  Mesh mesh;            ///< where it was given (time 0)
  QueryMesh queryMesh;  ///< prepared from `mesh`, pose identity
  RigidTransform pose;  ///< from where it was given to where it is now
  ObstacleMotion motion;

  /// The velocity of the obstacle's material point now at `x`.
  Vec3 velocityAt(const Vec3& x) const noexcept {
    return motion.velocity + cross(motion.angularVelocity, x - pose.apply(motion.pivot));
  }
};

/// A contact point of the last force evaluation with the force acting there, for output.
///
/// Threading: a value type; no shared state.
struct Contact {
  ContactPoint point;        ///< world frame; `first`/`second`: triangle ids (0 for a sphere)
  std::uint32_t first = 0;   ///< particle
  std::uint32_t second = 0;  ///< particle, or obstacle when `withObstacle`
  bool withObstacle = false;
  double depth = 0.0;  ///< δ into the ε-shell (the volume law: V/|S|, the mean depth)
  Vec3 force;          ///< on particle `first`; particle `second` gets −force
  /// A pure moment on particle `first` besides the force's (`second` gets −couple): the volume
  /// law's; zero in the point law.
  Vec3 couple;
  double volume = 0.0;  ///< the volume law's overlap V of this region; 0 in the point law
};

/// What the last step did and how long each phase took (wall-clock seconds).
///
/// Threading: a value type; no shared state.
struct StepStatistics {
  std::size_t particlePairsTested = 0;  ///< particle pairs whose bounding spheres come within 2ε
  /// particle–obstacle pairs whose bounding sphere may be within 2ε of the obstacle's surface
  /// (the neighbour list's bound: the class comment)
  std::size_t obstaclePairsTested = 0;
  std::size_t pairsInContact = 0;  ///< pairs with at least one contact point
  std::size_t rawContactPoints =
      0;                          ///< triangle (or sphere) pairs closer than 2ε, before filter(h)
  std::size_t contactPoints = 0;  ///< after filter(h): the points forces act at
  std::size_t overlappingContacts = 0;  ///< points where the surfaces interpenetrate
  double deepestRatio = 0.0;            ///< largest δ / 2ε (above 1: past the shell)
  /// placing the meshes; the neighbour list's test, and when remade its cell list and wall
  /// searches
  double broadPhaseSeconds = 0.0;
  double contactDetectionSeconds = 0.0;  ///< contacts() and filter(h) over all pairs
  double forceSeconds = 0.0;             ///< the contact law and summing the forces
  double integrationSeconds = 0.0;       ///< moving the particles and obstacles
  /// Handing particles, ghosts and forces to other processes and waiting for theirs
  /// (DistributedWorld); 0 in a World of one process.
  double communicationSeconds = 0.0;
  double totalSeconds = 0.0;
};

/// One process's share of the work of a simulation split over processes
/// (DistributedWorld::load); RankLoad{} in one process.
///
/// Threading: a value type; no shared state.
struct RankLoad {
  std::size_t particles = 0;   ///< owned now
  std::size_t ghosts = 0;      ///< copies of other processes' particles held for the last step
  std::size_t neighbours = 0;  ///< processes whose regions are near enough to exchange with
  std::size_t contacts = 0;    ///< contact points of the pairs this process evaluated, last step
  std::size_t steps = 0;       ///< steps summed below
  double contactDetectionSeconds = 0.0;  ///< Σ StepStatistics::contactDetectionSeconds
  double communicationSeconds = 0.0;     ///< Σ StepStatistics::communicationSeconds
  double stepSeconds = 0.0;              ///< Σ StepStatistics::totalSeconds
};

/// The energies of the current state.
///
/// Threading: a value type; no shared state.
struct Energies {
  double translational = 0.0;  ///< Σ ½·m·|v|²
  double rotational = 0.0;     ///< Σ ½·ω·L
  double gravitational = 0.0;  ///< Σ −m·g·x (zero at the origin)
  /// Σ over touching pairs ½·k·δ_max² (the point law's spring); the volume law: Σ ½·κ·V² over
  /// the overlap regions
  double elastic = 0.0;

  double kinetic() const noexcept { return translational + rotational; }
  double total() const noexcept { return translational + rotational + gravitational + elastic; }
};

/// A DEM simulation: rigid triangulated particles, obstacles, and a contact law of
/// contact_model.h between them (Parameters::contactModel), advanced by explicit time steps.
///
/// Each step (velocity Verlet, kick–drift–kick, as LAMMPS integrates granular media):
///  1. v += dt/2·(F/m + g), L += dt/2·τ                   (forces of the previous evaluation)
///  2. x += dt·v; q ← rotation(ω½·dt)·q, renormalised, with ω½ = R·I⁻¹·Rᵀ·L at the body
///     turned half way (q½ = rotation(ω·dt/2)·q, ω at the old q: the midpoint rule, second
///     order; ω at the old q alone made a free asymmetric spin gain energy, 0.7% in 100,000
///     steps at 50 rad/s, where the midpoint keeps it to 10⁻⁸); obstacles move by their
///     prescribed motion
///  3. forces at the new positions; the dashpot and friction see the velocities predicted for
///     that time from the half-step ones and the previous forces (v + dt/2·(F/m + g))
///  4. v += dt/2·(F/m + g), L += dt/2·τ; ω from L at the new q.
/// Integrating the world-frame angular momentum L (dL/dt = τ) is Euler's equations with the full
/// inertia tensor in the world frame; it makes total linear and angular momentum exactly
/// conserved by the scheme (forces on both bodies act at one point, equal and opposite), so only
/// round-off changes them in a closed system.
///
/// Forces: the broad phase (broad_phase.h) pairs particles whose bounding spheres (centred at
/// the centre of mass, radius ParticleShape::boundingRadius) come within 2ε, and particles with
/// obstacles whose surface their bounding sphere comes within 2ε of (the obstacle's box first,
/// then a nearest-triangle search, query/point_distance.h).
///
/// Neighbour list: the broad phase's candidates are kept from step to step (a Verlet list, as
/// LIGGGHTS and LAMMPS keep theirs): particle pairs within 2ε + skin, and particle–obstacle pairs
/// within 2ε + skin with their gap when listed, the skin a tenth of the smallest bounding radius.
/// Until a particle has moved half the skin since the list was made, or a particle and an
/// obstacle the whole of it between them (an obstacle's move bounded at the corners of its
/// box), no pair outside the list can have come within 2ε, and no cell list or wall search is
/// made; each step the listed particle pairs are tested against 2ε as the cell list would, and an
/// obstacle pair goes on while its listed gap less both bodies' moves is under 2ε. The pairs
/// evaluated, and so every result, are those of a broad phase made anew each step, bit for bit;
/// only StepStatistics::obstaclePairsTested counts some pairs a little beyond 2ε. A World of
/// several processes (DistributedWorld) makes its list anew every step, and so does a World
/// whose particles or obstacles were set or added since the last step.
///
/// Threads under load: threaded steps are judged together, a millisecond's worth at a time (one
/// long step, or several short ones: a stall lasts a scheduler's time slice, longer than a
/// sphere step). When the calling thread ran for less than 60% of their wall time (the rest put
/// aside by the operating system, or waiting for a worker that was: every core busy with other
/// processes) in two such windows in a row (one alone is most often a single stall: a virtual
/// machine's core taken for a moment, which sent a quiet hopper's next 64 steps, a fifth of a
/// run, to one thread), the next 64 steps run on the calling thread alone (detail::SerialLoops),
/// then the threads are judged again; while the cores stay busy the steps alone double, up to 1024.
/// The results are the same bits either way; a two-thread run on a machine whose cores are all
/// busy then steps about as fast as a one-thread run, where short steps of many parallel loops
/// each waiting for a descheduled worker took 1.6 to 1.8 times as long. Not in a
/// DistributedWorld (its steps wait for other ranks).
///
/// Contact caches: under the point law each pair of two meshes (particle–particle, or particle
/// and obstacle) keeps a contactdetection::ContactCache (query/contacts.h) with a skin of ε/2
/// while it stays in the broad phase's pairs: the triangle pairs within 2ε + ε/2 when it was
/// made, handed alone to the kernels until the two bodies have moved ε/2 against each other. The
/// contacts are those of a fresh query, bit for bit, so neither the thread count nor the process
/// count (a pair's cache is made anew where a pair moves to another process) changes a result.
/// Under the volume law each pair keeps a contactdetection::OverlapCache (query/overlap.h) with
/// the same skin: the triangle pairs whose boxes lay within ε/2 when it was made, the only ones
/// crossed until the bodies have moved ε/2 against each other; the same overlap, bit for bit.
///
/// The narrow phase, in parallel over
/// those pairs (delta::parallelFor, each pair into its own slot), runs pairContacts
/// (narrow_phase.h: contactdetection::contacts on the two placed meshes, the particle first, and
/// filter(h)), then the contact law. The forces are then summed pair by pair in a fixed order, so
/// results are bitwise the same for any thread count.
///
/// With the volume law (ContactModel::volume) the narrow phase of a pair is
/// contactdetection::overlap (query/overlap.h) of the two placed meshes (the particle first),
/// without curves, and the law is volumePairForces; the broad phase is the same (pairs whose
/// meshes do not overlap get no force). That law needs closed meshes that do not cross
/// themselves: addShape refuses sphere shapes (ParticleShape refuses a mesh that bounds no
/// solid), addObstacle open or self-intersecting meshes and those whose parts do not nest as a
/// solid's boundary (part_nesting.h) (delta::Error naming them).
///
/// Sphere particles (ParticleShape::sphere) go through the same broad phase, contact law and
/// integrator; only the narrow phase differs (narrow_phase.h): sphere–mesh particle pairs with
/// sphereMeshContacts, sphere–obstacle pairs with contactdetection::sphereContacts through a
/// cache of the triangles near each sphere (query/sphere_contacts.h: SphereContactCache, skin
/// ε/2; the same contacts, bit for bit) and finishSphereMeshContacts. A pair of two spheres, and
/// a sphere with one contact point on an obstacle (most), has the one-point law in batches
/// (contact_model.h: sphereSphereForces, onePointForces; the general law's values to rounding),
/// its point and forces held in one array: no per-pair buffers, and the pairs' square roots and
/// divisions overlap. The gap is always between the sphere's surface and the other surface, so a
/// sphere and a triangulated particle of the same surface behave alike.
///
/// Friction keeps one tangential and one torsion spring per touching pair from one step to the
/// next (keyed by the pair's indices); a pair that loses contact for a step forgets them.
///
/// No pass-through: contacts are found only where two surfaces are closer than 2ε, so two bodies
/// must not approach by 2ε or more in one step, or they could pass through each other unseen.
/// Before each step (in one process) the World bounds how far every body's surface moves in it:
/// a particle's by (|v| + |ω|·r)·dt with the velocities of the step's drift and r its bounding
/// radius, an obstacle's by its prescribed motion (about its pivot, r from the pivot to the
/// corners of its box). Where the two largest of these sum to less than 2ε nothing can pass
/// (one comparison a step). Otherwise each pair whose motions sum to 2ε or more is looked at:
/// two particles whose bounding spheres, grown by their turning and 2ε, can meet along the
/// straight drift of their centres, or a particle whose swept box comes within its bounding
/// radius, turning, 2ε and the obstacle's motion of an obstacle's box, make step() throw
/// delta::Error naming the particle, its speed and angular speed, the other body and the largest
/// time step that keeps their motions below 2ε, before moving anything; a fast body far from
/// everything is not stopped. The check only reads the state, so runs it never stops are bitwise
/// those of a World without it.
///
/// Throws delta::Error for invalid parameters, shapes, states or indices (naming them), and from
/// step() when a particle's state stops being finite (a time step too large for the stiffness)
/// or would move farther in the step than the contact shell catches (above).
///
/// Threading: not thread-safe: one thread at a time may change a World or step it, and no other
/// may read it meanwhile; const member functions may be called concurrently between steps.
/// step() runs in parallel itself (OpenMP, through core/parallel.h; OMP_NUM_THREADS).
class World {
 public:
  /// An empty world; throws delta::Error naming the first invalid parameter.
  explicit World(const Parameters& parameters);

  // Building. Each throws delta::Error for what it is given that is invalid (naming it) and
  // then adds nothing.

  /// Adds a particle shape (see ParticleShape for what is required; the volume law also refuses
  /// sphere shapes and meshes that cross themselves); returns its index.
  std::size_t addShape(const Mesh& mesh, double density);
  /// Adds a shape made before (shares its prepared mesh); returns its index.
  std::size_t addShape(const ParticleShape& shape);
  /// Adds a particle of shape `shape`; returns its index. Throws for an unknown shape, a state
  /// that is not finite, a bounding sphere beyond the coordinate range (coordinate_range.h), or
  /// a zero orientation (any other is normalised). Particles placed interpenetrating, or within
  /// 2ε, are accepted: the first step pushes them apart, with the force of the law's overlap
  /// rule, so place them apart unless that is meant.
  std::size_t addParticle(std::size_t shape, const ParticleState& state);
  /// Adds an obstacle (any valid mesh, open or closed, degenerate triangles included; with the
  /// volume law closed and consistently oriented, not crossing itself); returns its index.
  /// Throws for a non-finite motion, a mesh beyond the coordinate range or, with the volume
  /// law, a mesh it cannot use.
  std::size_t addObstacle(const Mesh& mesh, const ObstacleMotion& motion = {});

  // Changing the state (each but setTimeStep makes the next step re-evaluate the forces first;
  // the forces at a state do not depend on the step that follows it). Each throws
  // delta::Error for a particle index that does not exist or a value that is not finite (a
  // time step must also be positive; an orientation non-zero; a pose must keep the particle's
  // bounding sphere within the coordinate range; an angular momentum must be finite), and then
  // changes nothing: the next step is the one it would have been.

  void setTimeStep(double timeStep);
  void setPose(std::size_t particle, const Vec3& position, const Quaternion& orientation);
  void setVelocity(std::size_t particle, const Vec3& velocity);
  void setAngularVelocity(std::size_t particle, const Vec3& angularVelocity);

  // Running.

  /// Advances by one time step. Throws delta::Error when a particle's state stops being finite
  /// (a time step too large for the stiffness), when bodies would move farther in the step than
  /// the contact shell catches (the class comment: "No pass-through"), when a body leaves the
  /// coordinate range of the queries, or when memory runs out; a step that throws leaves the
  /// World as it was before it: particles, springs, obstacles, time, step count and energies, so
  /// that it may go on (with a smaller time step, say) or be saved. Only the contact records of
  /// the last evaluation may be lost with it: contacts() then throws until the next step. (A
  /// DistributedWorld's failed step leaves each part as that step made it; its ranks stop.)
  /// A world with no particles only moves its obstacles and its clock.
  void step();
  /// Advances by `steps` time steps (step() `steps` times; 0 does nothing).
  void run(std::size_t steps);

  // Reading.

  const Parameters& parameters() const noexcept { return parameters_; }
  const ContactLaw& contactLaw() const noexcept { return law_; }
  std::span<const ParticleShape> shapes() const noexcept { return shapes_; }
  /// The particles, by index (a DistributedWorld's part: those it owns). The span lasts until
  /// the World is stepped or changed: a step writes the moved particles into a buffer of its
  /// own (the one before is kept to undo a step that fails), so ask again after each.
  std::span<const Particle> particles() const noexcept { return {particles_.data(), owned_}; }
  std::span<const Obstacle> obstacles() const noexcept { return obstacles_; }
  /// The contact points of the last force evaluation (after the last step), sorted by pair
  /// (particle pairs by their indices, then particle–obstacle pairs) and within a pair as found.
  /// In a DistributedWorld's part, `first` and `second` are the particles' ids. The records are
  /// made from what the evaluation kept the first time they are asked for after it, so a step
  /// whose contacts nobody reads writes none (a tenth of a sphere step). The span lasts until
  /// the World is stepped or changed.
  ///
  /// Threading: as the class; concurrent calls make the records once (a lock).
  std::span<const Contact> contacts() const;
  const StepStatistics& statistics() const noexcept { return statistics_; }
  double time() const noexcept { return time_; }
  std::size_t stepCount() const noexcept { return stepCount_; }

  /// The energies of the current state (Energies). A sum beyond a double's range is +∞: a
  /// World holds any finite state, and a speed beyond about 1e154 m/s has a kinetic energy no
  /// double holds (the pass-through guard stops such a body before it could pass another).
  Energies energies() const noexcept;
  /// Σ m·v.
  Vec3 linearMomentum() const noexcept;
  /// Σ (x × m·v + L), about the origin.
  Vec3 angularMomentum() const noexcept;
  /// suggestedTimeStep(k, smallest particle mass) (contact_model.h), for either law (the
  /// volume law is softer than k where it acts); 0 without particles.
  double suggestedTimeStep() const noexcept;

  // Checkpoints (dem/checkpoint.h: what they hold, the format, the errors).

  /// Writes a checkpoint of this World to `path`, atomically; throws delta::Error naming the
  /// path and the reason. Loading it and stepping M times ends bit for bit where stepping this
  /// World M times does.
  void save(const std::filesystem::path& path) const;
  /// The World a checkpoint file holds; throws delta::Error naming the path when it is missing,
  /// not a checkpoint, of another version, truncated or corrupt.
  static World load(const std::filesystem::path& path);
  /// stateDigest(*this) (dem/checkpoint.h): 16 hex digits; equal states, equal digests.
  std::string stateDigest() const;

 private:
  /// A pair the broad phase found: two particles (local indices; `first` has the lower id), or
  /// a particle and an obstacle.
  struct Interaction {
    std::uint32_t first;
    std::uint32_t second;
    bool withObstacle;
    std::uint64_t key;  ///< first id << 32 | second id (or obstacle): the order forces are summed
  };
  /// The broad phase's candidates kept from one force evaluation to the next (a Verlet list):
  /// the particle pairs whose bounding spheres came within 2ε + skin, and the particle–obstacle
  /// pairs whose bounding sphere came within 2ε + skin of the obstacle's surface, when the list
  /// was made. Until the particles and obstacles have moved `budget` between them (a pair's two
  /// displacements added), no other pair can have come within 2ε, so the cell list and the wall
  /// searches are not redone (findPairs).
  struct NeighbourList {
    std::vector<Interaction> particlePairs;  ///< sorted by key
    /// A particle–obstacle pair and its gap when listed: the distance from the bounding
    /// sphere's surface to the obstacle's; less the two bodies' moves since, a lower bound on
    /// the gap now.
    struct ListedObstacle {
      Interaction pair;
      double gap;
    };
    std::vector<ListedObstacle> obstaclePairs;  ///< sorted by key
    std::vector<Vec3> positions;                ///< each particle's position when made
    std::vector<RigidTransform> obstaclePoses;
    std::vector<double> moved;          ///< how far each particle has moved since (findPairs)
    std::vector<double> obstacleMoved;  ///< how far each obstacle's surface has moved, at most
    double budget = 0.0;                ///< the skin less the rounding allowance
    double allowance = 0.0;  ///< rounding: 64 ulps of the largest coordinate or length met
    bool valid = false;
  };
  /// What the narrow phase and the contact law found for one pair; kept from step to step
  /// (outcomes_) so that their buffers are reused.
  struct PairOutcome {
    PairContacts contacts;  ///< after filter(h)
    /// The volume law's: the overlap's regions (empty where the meshes do not overlap).
    std::vector<contactdetection::OverlapRegion> regions;
    PairForces forces;
  };
  // A DistributedWorld keeps its process's part of a simulation in a World: the particles it
  // owns, then ghosts (copies of other processes' particles near its part), and steps it with an
  // Exchange between the phases.
  friend class DistributedWorld;
  friend class CheckpointCodec;  // dem/checkpoint.cpp: reads and restores every member

  /// A contact point's force on a ghost, for the process that owns it: a pair is evaluated by
  /// the process owning its first particle (the lower id), so the ghost is the pair's second,
  /// and its owner subtracts `force` at `point` as this process would.
  struct GhostForce {
    std::uint64_t key = 0;       ///< the pair: first id << 32 | second id
    std::uint32_t particle = 0;  ///< the ghost's id
    Vec3 point;
    Vec3 force;   ///< on the pair's first particle
    Vec3 couple;  ///< a pure moment on the pair's first particle (the volume law's)
  };
  /// What a process owning part of a simulation does between the phases of a step. Every call
  /// is collective: all processes make it in the same order.
  class Exchange {
   public:
    virtual ~Exchange() = default;
    /// Before a force evaluation: hands on the owned particles that left this process's part,
    /// takes in those that entered it, and replaces the ghosts.
    virtual void refreshGhosts(World& world) = 0;
    /// Sends the forces found here on other processes' particles; returns the forces they found
    /// on this process's.
    virtual std::vector<GhostForce> swapGhostForces(std::vector<GhostForce> found) = 0;
    /// The least of `local` over every process: a particle id that is no longer finite in the
    /// high half, a friction spring's pair's lower id in the low half (all ones: none), so that
    /// every process names the same.
    virtual std::uint64_t firstNonFinite(std::uint64_t local) = 0;
  };

  /// One step (step()), with `exchange` between the phases when not null: advanceOnce, which
  /// in a World of one process is undone when it throws (keepStepStart, restoreStepStart).
  void advance(Exchange* exchange);
  void advanceOnce(Exchange* exchange);
  void keepStepStart();
  /// The particles' forces and torques into stepStart_, before a step's first evaluation.
  void keepStartForces();
  void restoreStepStart() noexcept;
  /// The forces at the current state, in phases: findPairs (the broad phase), detectContacts,
  /// applyContactLaw, exchangeGhostForces (with `exchange`), sumForces.
  void evaluateForces(bool halfStepVelocities, Exchange* exchange);
  /// Each pair's contact points (the point law) or overlap regions (the volume law), in runs of
  /// pairs: detectPair on each, then finishBatchedPairs.
  void detectContacts(std::span<const Interaction> pairs, std::span<PairOutcome> outcomes);
  struct DetectionRun;  // world.cpp
  /// Pair p's contacts or regions into `outcome`; a mesh pair with a contact cache has its
  /// step 1 added to the run's kernel batch instead (dem::addPairContacts).
  void detectPair(const Interaction& pair, std::size_t p, PairOutcome& outcome, DetectionRun& run);
  /// The run's kernel batch run, and the pairs added to it finished (dem::batchedPairContacts).
  void finishBatchedPairs(std::span<const Interaction> pairs, std::span<PairOutcome> outcomes,
                          DetectionRun& run);
  /// The law of the pairs of two spheres (spherePairs_), detection and forces at once: their
  /// routes_ and onePoints_.
  void sphereSphereLaw(std::span<const Interaction> pairs);
  /// The law of the obstacle pairs with one contact point (held in onePoints_), in batches.
  void onePointLaw(std::span<const Interaction> pairs);
  struct LawRun;  // world.cpp
  /// What the batched one-point law reads of pair p (its motions, dashpots, spring) and where
  /// its forces go (onePoints_[p]).
  OnePointLaw pairLaw(const Interaction& pair, std::size_t p, LawRun& run) noexcept;
  /// Carries the contact caches of the pairs still found over to this evaluation's pairs (new
  /// ones empty, those of pairs gone dropped) and points cacheOf_ at them.
  void routeContactCaches(std::span<const Interaction> pairs);
  /// Each pair's forces from its contacts, with the velocities predicted to the positions' time
  /// when `halfStepVelocities`.
  void applyContactLaw(std::span<const Interaction> pairs, std::span<PairOutcome> outcomes);
  /// Each particle's and obstacle's motion for the contact law (motions_, obstacleMotions_),
  /// with the particles' velocities predicted to the positions' time when `halfStepVelocities`.
  void predictMotions(bool halfStepVelocities);
  /// m₁m₂/(m₁+m₂) of a particle pair, m₁ against an obstacle.
  double effectiveMass(const Interaction& pair) const noexcept;
  /// Sends the forces on ghosts to their owners; returns theirs on this process's particles,
  /// sorted by pair.
  std::vector<GhostForce> exchangeGhostForces(std::span<const Interaction> pairs,
                                              std::span<const PairOutcome> outcomes,
                                              Exchange& exchange);
  /// Every particle's force and torque, summed pair by pair in the order of their ids (with the
  /// imported ghost forces in their places), the contact records, springs and statistics.
  void sumForces(std::span<const Interaction> pairs, std::span<const PairOutcome> outcomes,
                 std::span<const GhostForce> imported);
  /// The contact records of the last evaluation's pairs into records_ (contacts()).
  void makeContacts() const;
  /// Pair p's point forces of this evaluation, wherever its route keeps them.
  std::span<const PointForce> pointForces(std::size_t p,
                                          std::span<const PairOutcome> outcomes) const;
  /// Throws delta::Error naming the lowest id of a particle (on any process) that is no longer
  /// finite in any field a checkpoint holds, or else of one whose friction spring is not.
  void requireFiniteParticles(Exchange* exchange) const;
  /// Throws delta::Error naming the lowest id of a particle (on any process) whose bounding
  /// sphere reaches beyond the queries' coordinate range (coordinate_range.h), or else the
  /// first moving obstacle that does: a body far from all others is met by no query, and would
  /// otherwise fly on beyond the range unrefused.
  void requireBodiesInRange(Exchange* exchange) const;
  /// Throws delta::Error when the coming drift could carry two surfaces through each other
  /// unseen (the class comment: "No pass-through"); reads the state only (src/dem/guards.cpp).
  void requireCatchableMotion() const;
  /// The broad phase: the pairs whose bounding spheres come within 2ε (particles), or within
  /// 2ε of the obstacle's surface (obstacles; with the neighbour list, within 2ε + skin), sorted
  /// by key, particle pairs first. Reuses the neighbour list when `reuseList` and it still holds.
  const std::vector<Interaction>& findPairs(bool reuseList);
  /// Sets placed_ and spheres_ (each particle's mesh and bounding sphere where it is now) and
  /// placedObstacles_.
  void placeBodies();
  /// Whether the neighbour list still holds every pair within 2ε: made for these particles and
  /// no two bodies moved more than its budget between them since. Sets its `moved` and
  /// `obstacleMoved`.
  bool neighbourListHolds() noexcept;
  /// Makes the neighbour list from spheres_ and placedObstacles_.
  void makeNeighbourList();
  Sphere boundingSphere(const Particle& particle) const noexcept;
  /// v += dt/2·(F/m + g), L += dt/2·τ, ω from L: steps 1 and 4 of the class comment.
  void halfKick();
  void kick(Particle& particle, double half) const noexcept;
  /// Steps 1 and 2 of the class comment, particle by particle in one pass; the obstacles moved.
  /// With `keepStart`, the particles as they were stay in stepStart_ (keepStepStart).
  void kickAndDrift(bool keepStart);
  Vec3 angularVelocityOf(const Particle& particle, const Quaternion& orientation) const noexcept;
  /// ω = R·I⁻¹·Rᵀ·L of the particle's shape at `orientation`, for the angular momentum given.
  Vec3 angularVelocityOf(const Particle& particle, const Quaternion& orientation,
                         const Vec3& angularMomentum) const noexcept;
  /// The owned particle `index`, or delta::Error naming `operation`.
  Particle& particleAt(std::size_t index, const char* operation);
  /// A setter's change: the next step evaluates the forces first, and the neighbour list anew.
  void stateChanged() noexcept;
  /// R·I·Rᵀ·ω of the particle's shape at `orientation`: its angular momentum; delta::Error
  /// starting with `what` where it is not finite.
  Vec3 angularMomentumOf(const Particle& particle, const Quaternion& orientation,
                         const Vec3& angularVelocity, const std::string& what) const;

  Parameters parameters_;
  ContactLaw law_;
  std::vector<ParticleShape> shapes_;
  std::vector<Particle> particles_;  ///< [0, owned_) integrated here; the rest are ghosts
  std::vector<std::uint32_t> ids_;   ///< each particle's id: its index, unless distributed
  std::size_t owned_ = 0;
  std::vector<Obstacle> obstacles_;
  /// A pair's cache on the heap, made with the pair's skin: routeContactCaches moves only its
  /// pointer from step to step. Copied with the World (a moved-from one copies as empty).
  template <class Cache>
  class Held {
   public:
    explicit Held(double skin) : held_(std::make_unique<Cache>(skin)) {}
    Held(const Held& other)
        : held_(other.held_ ? std::make_unique<Cache>(*other.held_) : nullptr) {}
    Held(Held&&) noexcept = default;
    Held& operator=(const Held& other) {
      if (this != &other) held_ = other.held_ ? std::make_unique<Cache>(*other.held_) : nullptr;
      return *this;
    }
    Held& operator=(Held&&) noexcept = default;
    ~Held() = default;
    Cache* get() const noexcept { return held_.get(); }

   private:
    std::unique_ptr<Cache> held_;
  };
  /// Each mesh pair's contact cache (query/contacts.h), keyed and sorted like the springs:
  /// the pairs of the last evaluation that had triangles on both sides, under the point law.
  using ContactCaches = std::vector<std::pair<std::uint64_t, Held<contactdetection::ContactCache>>>;
  ContactCaches particleCaches_, obstacleCaches_;
  ContactCaches spareCaches_;  ///< routeContactCaches' scratch (the caches of pairs gone)
  /// Each pair's cache for this evaluation (null: none), for detectContacts.
  std::vector<contactdetection::ContactCache*> cacheOf_;
  /// Each sphere–obstacle pair's cache (query/sphere_contacts.h), keyed and sorted likewise.
  using SphereCaches =
      std::vector<std::pair<std::uint64_t, Held<contactdetection::SphereContactCache>>>;
  SphereCaches sphereObstacleCaches_, spareSphereCaches_;
  std::vector<contactdetection::SphereContactCache*> sphereCacheOf_;
  /// Under the volume law, each pair's overlap cache (query/overlap.h), keyed and sorted likewise.
  using OverlapCaches = std::vector<std::pair<std::uint64_t, Held<contactdetection::OverlapCache>>>;
  OverlapCaches particleOverlapCaches_, obstacleOverlapCaches_, spareOverlapCaches_;
  std::vector<contactdetection::OverlapCache*> overlapCacheOf_;
  /// Each particle's shape at its pose, for the narrow phase (sized and set by findPairs).
  std::vector<QueryMesh> placed_;
  std::vector<QueryMesh> placedObstacles_;  ///< each obstacle where it is now
  std::vector<Sphere> spheres_;             ///< each particle's bounding sphere (findPairs)
  NeighbourList neighbours_;
  std::vector<Interaction> pairs_;           ///< this evaluation's pairs (findPairs; scratch)
  std::vector<BodyMotion> motions_;          ///< each particle's, for the contact law (scratch)
  std::vector<BodyMotion> obstacleMotions_;  ///< each obstacle's (scratch)
  /// Where each pair's forces of this evaluation are (detectContacts): a pair of two spheres,
  /// and a sphere with one contact point on an obstacle, has its forces at once, held in
  /// onePoints_ (one array, read in order, rather than a buffer a pair); the others in their
  /// PairOutcome.
  enum class PairRoute : std::uint8_t { general, onePoint, apart };
  struct RoutedPair {
    PairRoute route = PairRoute::general;
    std::size_t rawPoints = 0;  ///< triangle (or sphere) pairs within 2ε, before filter(h)
  };
  std::vector<RoutedPair> routes_;
  /// The pairs of two spheres, then the obstacle pairs of one point (scratch).
  std::vector<std::size_t> spherePairs_;
  /// The pairs the general law acts on this step (applyContactLaw's scratch).
  std::vector<std::size_t> lawPairs_;
  std::vector<OnePointForces> onePoints_;  ///< the onePoint pairs' (scratch)
  /// Each pair's contacts and forces of this evaluation (scratch, kept for its buffers).
  std::vector<PairOutcome> outcomes_;
  /// The last evaluation's contact records, made by contacts() when `pending` (then from
  /// pairs_, routes_, onePoints_ and outcomes_, which stay as that evaluation left them), under
  /// `mutex`. A copy of the World reads them under the source's mutex, so copying may run beside
  /// contacts() as any const use may (a copy made while they were pending makes them itself);
  /// it gets its own mutex.
  struct ContactRecords {
    std::vector<Contact> contacts;
    bool pending = false;
    mutable std::mutex mutex;

    ContactRecords() = default;
    ContactRecords(const ContactRecords& other) {
      const std::lock_guard<std::mutex> lock(other.mutex);
      contacts = other.contacts;
      pending = other.pending;
    }
    ContactRecords(ContactRecords&& other) noexcept
        : contacts(std::move(other.contacts)), pending(other.pending) {}
    ContactRecords& operator=(const ContactRecords& other) {
      if (this != &other) {
        const std::scoped_lock lock(mutex, other.mutex);
        contacts = other.contacts;
        pending = other.pending;
      }
      return *this;
    }
    ContactRecords& operator=(ContactRecords&& other) noexcept {
      contacts = std::move(other.contacts);
      pending = other.pending;
      return *this;
    }
  };
  mutable ContactRecords records_;
  /// Tangential springs of touching pairs, keyed (first id << 32 | second id or obstacle),
  /// sorted.
  std::vector<std::pair<std::uint64_t, TangentialSpring>> particleSprings_;
  std::vector<std::pair<std::uint64_t, TangentialSpring>> obstacleSprings_;
  StepStatistics statistics_;
  double elasticEnergy_ = 0.0;
  /// Force evaluations begun (evaluateForces): whether a failed step overwrote the last one's
  /// contact records.
  std::uint64_t evaluations_ = 0;
  /// Set when a failed step overwrote the records contacts() makes (contacts() then throws);
  /// cleared by the next evaluation.
  bool contactsLost_ = false;
  /// What a step changes, as it was at the step's start (keepStepStart): a step that throws is
  /// undone from it (restoreStepStart; time_ and stepCount_ change only once it succeeded). The
  /// buffers are kept, so that a step allocates nothing here once the sizes settle.
  struct StepStart {
    /// The particles before kickAndDrift moved them (particlesMoved: it has, in this step).
    std::vector<Particle> particles;
    bool particlesMoved = false;
    /// The particles' contact forces and torques before a first evaluation changed them
    /// (forcesKept: one ran in this step, before kickAndDrift).
    std::vector<std::pair<Vec3, Vec3>> forces;
    bool forcesKept = false;
    std::vector<std::pair<std::uint64_t, TangentialSpring>> particleSprings, obstacleSprings;
    std::vector<RigidTransform> obstaclePoses;
    StepStatistics statistics;
    double elasticEnergy = 0.0;
    std::uint64_t evaluations = 0;
    bool forcesCurrent = false;
    bool contactsPending = false;
    bool contactsLost = false;
  };
  StepStart stepStart_;
  double time_ = 0.0;
  std::size_t stepCount_ = 0;
  bool forcesCurrent_ = false;
  /// Steps still to run on the calling thread alone (threads under load: World::advance), and
  /// how many the next judgement of busy cores gives (64, doubling to 1024 while they stay busy).
  std::size_t serialSteps_ = 0;
  std::size_t serialPeriod_ = 64;
  /// Judged windows in a row whose calling thread was held up (two go to steps alone).
  std::size_t loadedWindows_ = 0;
  /// The threaded steps being judged together: when they began, and the calling thread's CPU
  /// clock then.
  struct LoadWindow {
    bool open = false;
    std::chrono::steady_clock::time_point start;
    double cpuStart = 0.0;
  };
  LoadWindow loadWindow_;
};

}  // namespace delta::dem
