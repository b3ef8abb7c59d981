#include "delta/dem/world.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/dem/broad_phase.h"
#include "delta/dem/narrow_phase.h"
#include "delta/mesh/topology.h"
#include "delta/query/overlap.h"
#include "delta/query/point_distance.h"
#include "delta/query/self_intersections.h"
#include "delta/query/sphere_contacts.h"

namespace delta::dem {

/// A pair the broad phase found: two particles (local indices; `first` has the lower id), or a
/// particle and an obstacle.
struct World::Interaction {
  std::uint32_t first;
  std::uint32_t second;
  bool withObstacle;
  std::uint64_t key;  ///< first id << 32 | second id (or obstacle): the order forces are summed in
};

namespace {

/// Pairs per parallel chunk in the narrow phase: a pair costs from a few µs (distant boxes) to
/// a few hundred (large meshes in contact), so small chunks under dynamic scheduling balance.
constexpr std::size_t kPairGrain = 2;
/// Particles per parallel chunk when integrating: a few hundred ns each.
constexpr std::size_t kParticleGrain = 512;

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void requirePositive(double value, const char* name) {
  if (!std::isfinite(value) || !(value > 0.0))
    throw Error(std::string("dem parameters: ") + name + " = " + toString(value) +
                " must be finite and positive");
}

void requireFinite(const Vec3& value, const std::string& what) {
  if (!isFinite(value)) throw Error(what + " = " + toString(value) + " must be finite");
}

ContactLaw contactLawOf(const Parameters& parameters) {
  requirePositive(parameters.timeStep, "timeStep");
  requirePositive(parameters.epsilon, "epsilon");
  requirePositive(parameters.filterDistance, "filterDistance");
  requirePositive(parameters.stiffness, "stiffness");
  requirePositive(parameters.tangentialStiffnessRatio, "tangentialStiffnessRatio");
  if (!std::isfinite(parameters.friction) || parameters.friction < 0.0)
    throw Error("dem parameters: friction = " + toString(parameters.friction) +
                " must be finite and non-negative");
  requireFinite(parameters.gravity, "dem parameters: gravity");
  if (parameters.contactModel != ContactModel::point &&
      parameters.contactModel != ContactModel::volume)
    throw Error("dem parameters: contactModel = " +
                std::to_string(static_cast<int>(parameters.contactModel)) +
                " is neither point nor volume");
  ContactLaw law;
  law.epsilon = parameters.epsilon;
  law.stiffness = parameters.stiffness;
  law.dampingRatio = dampingRatio(parameters.restitution);  // throws outside [0, 1]
  law.friction = parameters.friction;
  law.tangentialStiffness = parameters.tangentialStiffnessRatio * parameters.stiffness;
  law.model = parameters.contactModel;
  return law;
}

/// Throws delta::Error (starting with `what`) unless the volume law can use `mesh`: closed,
/// consistently oriented, not crossing itself (what contactdetection::overlap needs).
void requireVolumeLawMesh(const QueryMesh& mesh, const std::string& what) {
  if (!mesh.closed())
    throw Error(what + "the volume contact law needs a closed, consistently oriented mesh (" +
                describeDefects(mesh.topology()) + ")");
  const std::size_t crossings = selfIntersections(mesh).count;
  if (crossings > 0)
    throw Error(what + "the volume contact law needs a mesh that does not cross itself (" +
                std::to_string(crossings) + " pairs of its triangles intersect)");
}

/// R·M·Rᵀ·v for the rotation q, without forming matrices; a·v where M = a·I (a sphere's inertia:
/// turning it changes nothing, and the two rotations were a fifth of a sphere step).
Vec3 rotatedApply(const Quaternion& q, const Mat3& m, const Vec3& v) noexcept {
  if (m(0, 1) == 0.0 && m(0, 2) == 0.0 && m(1, 0) == 0.0 && m(1, 2) == 0.0 && m(2, 0) == 0.0 &&
      m(2, 1) == 0.0 && m(0, 0) == m(1, 1) && m(1, 1) == m(2, 2))
    return v * m(0, 0);
  return q.rotate(m * q.conjugate().rotate(v));
}

/// The rotation by the vector ω·dt (angle |ω|·dt about ω), composed before q.
Quaternion turned(const Quaternion& q, const Vec3& angularVelocity, double timeStep) noexcept {
  const double rate = length(angularVelocity);
  if (!(rate > 0.0)) return q;
  const double half = 0.5 * rate * timeStep;
  const Vec3 axis = angularVelocity * (std::sin(half) / rate);
  return Quaternion{std::cos(half), axis.x, axis.y, axis.z} * q;  // renormalises
}

/// The box of `box` after a rigid motion (its eight corners moved).
Aabb movedBox(const Aabb& box, const RigidTransform& motion) noexcept {
  Aabb moved;
  for (int corner = 0; corner < 8; ++corner)
    moved.extend(motion.apply({(corner & 1) ? box.upper.x : box.lower.x,
                               (corner & 2) ? box.upper.y : box.lower.y,
                               (corner & 4) ? box.upper.z : box.lower.z}));
  return moved;
}

bool isIdentity(const RigidTransform& motion) noexcept {
  const Quaternion& q = motion.rotation;
  return q.w == 1.0 && q.x == 0.0 && q.y == 0.0 && q.z == 0.0 && motion.translation == Vec3{};
}

const TangentialSpring* springOf(
    const std::vector<std::pair<std::uint64_t, TangentialSpring>>& springs,
    std::uint64_t key) noexcept {
  const auto found = std::lower_bound(springs.begin(), springs.end(), key,
                                      [](const std::pair<std::uint64_t, TangentialSpring>& entry,
                                         std::uint64_t k) { return entry.first < k; });
  return found != springs.end() && found->first == key ? &found->second : nullptr;
}

}  // namespace

World::World(const Parameters& parameters)
    : parameters_(parameters), law_(contactLawOf(parameters)) {}

std::size_t World::addShape(const Mesh& mesh, double density) {
  return addShape(ParticleShape(mesh, density));
}

std::size_t World::addShape(const ParticleShape& shape) {
  if (shapes_.size() >= std::numeric_limits<std::uint32_t>::max())
    throw Error("dem: too many shapes for 32-bit ids");
  if (law_.model == ContactModel::volume) {
    const std::string what = "dem: addShape " + std::to_string(shapes_.size()) + ": ";
    if (shape.isSphere())
      throw Error(what + "the volume contact law needs triangulated particles, not sphere shapes");
    requireVolumeLawMesh(shape.queryMesh(), what);
  }
  shapes_.push_back(shape);
  return shapes_.size() - 1;
}

std::size_t World::addParticle(std::size_t shape, const ParticleState& state) {
  if (shape >= shapes_.size())
    throw Error("dem: addParticle: shape " + std::to_string(shape) + " does not exist (" +
                std::to_string(shapes_.size()) + " shapes)");
  if (particles_.size() >= std::numeric_limits<std::uint32_t>::max())
    throw Error("dem: too many particles for 32-bit ids");
  const std::string what = "dem: addParticle " + std::to_string(particles_.size()) + ": ";
  requireFinite(state.position, what + "position");
  requireFinite(state.velocity, what + "velocity");
  requireFinite(state.angularVelocity, what + "angular velocity");
  const Quaternion& q = state.orientation;
  Particle particle;
  particle.shape = static_cast<std::uint32_t>(shape);
  particle.position = state.position;
  particle.orientation = Quaternion::fromComponents(q.w, q.x, q.y, q.z);  // throws if invalid
  particle.velocity = state.velocity;
  particles_.push_back(particle);
  ids_.push_back(static_cast<std::uint32_t>(particles_.size() - 1));
  owned_ = particles_.size();
  setAngularVelocity(particles_.size() - 1, state.angularVelocity);
  return particles_.size() - 1;
}

std::size_t World::addObstacle(const Mesh& mesh, const ObstacleMotion& motion) {
  const std::string what = "dem: addObstacle " + std::to_string(obstacles_.size()) + ": ";
  requireFinite(motion.velocity, what + "velocity");
  requireFinite(motion.angularVelocity, what + "angular velocity");
  requireFinite(motion.pivot, what + "pivot");
  QueryMesh prepared(mesh);
  if (law_.model == ContactModel::volume) requireVolumeLawMesh(prepared, what);
  obstacles_.push_back(Obstacle{mesh, std::move(prepared), RigidTransform{}, motion});
  forcesCurrent_ = false;
  return obstacles_.size() - 1;
}

Particle& World::particleAt(std::size_t index, const char* operation) {
  if (index >= owned_)
    throw Error(std::string("dem: ") + operation + ": particle " + std::to_string(index) +
                " does not exist (" + std::to_string(owned_) + " particles)");
  forcesCurrent_ = false;
  return particles_[index];
}

void World::setTimeStep(double timeStep) {
  requirePositive(timeStep, "timeStep");
  parameters_.timeStep = timeStep;
}

void World::setPose(std::size_t index, const Vec3& position, const Quaternion& orientation) {
  Particle& particle = particleAt(index, "setPose");
  requireFinite(position, "dem: setPose: position");
  particle.position = position;
  particle.orientation =
      Quaternion::fromComponents(orientation.w, orientation.x, orientation.y, orientation.z);
  // The body keeps turning at the same rate; its angular momentum follows the new orientation.
  setAngularVelocity(index, particle.angularVelocity);
}

void World::setVelocity(std::size_t index, const Vec3& velocity) {
  Particle& particle = particleAt(index, "setVelocity");
  requireFinite(velocity, "dem: setVelocity: velocity");
  particle.velocity = velocity;
}

void World::setAngularVelocity(std::size_t index, const Vec3& angularVelocity) {
  Particle& particle = particleAt(index, "setAngularVelocity");
  requireFinite(angularVelocity, "dem: setAngularVelocity: angular velocity");
  particle.angularVelocity = angularVelocity;
  particle.angularMomentum =
      rotatedApply(particle.orientation, shapes_[particle.shape].inertia(), angularVelocity);
}

Vec3 World::angularVelocityOf(const Particle& particle,
                              const Quaternion& orientation) const noexcept {
  return rotatedApply(orientation, shapes_[particle.shape].inverseInertia(),
                      particle.angularMomentum);
}

std::vector<World::Interaction> World::findPairs() {
  const std::size_t count = particles_.size();  // ghosts included
  if (placed_.size() > count)
    placed_.erase(placed_.begin() + static_cast<std::ptrdiff_t>(count), placed_.end());
  for (std::size_t i = placed_.size(); i < count; ++i)
    placed_.push_back(shapes_[particles_[i].shape].queryMesh());
  std::vector<Sphere> spheres(count);
  parallelFor(0, count, kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Particle& particle = particles_[i];
      const ParticleShape& shape = shapes_[particle.shape];
      if (!shape.isSphere()) {  // a sphere's contacts never read its (display) mesh
        placed_[i] = shape.queryMesh();
        placed_[i].transform(particle.pose());
      }
      spheres[i] = boundingSphere(particle);
    }
  });
  const double reach = 2.0 * law_.epsilon;
  // A pair is evaluated where its lower id is owned (the only rule, in one process or many);
  // pairs of two ghosts are some other process's. Summed in the order of their ids, forces
  // come out the same however the particles are split.
  std::vector<Interaction> pairs;
  for (CandidatePair pair : nearbyPairs(spheres, reach)) {
    if (ids_[pair.second] < ids_[pair.first]) std::swap(pair.first, pair.second);
    if (pair.first >= owned_) continue;
    pairs.push_back({pair.first, pair.second, false,
                     (std::uint64_t{ids_[pair.first]} << 32) | ids_[pair.second]});
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const Interaction& a, const Interaction& b) { return a.key < b.key; });
  statistics_.particlePairsTested = pairs.size();

  std::vector<Aabb> obstacleBoxes;
  placedObstacles_.clear();
  for (const Obstacle& obstacle : obstacles_) {
    obstacleBoxes.push_back(movedBox(obstacle.queryMesh.bounds(), obstacle.pose));
    placedObstacles_.push_back(obstacle.queryMesh);
    if (!isIdentity(obstacle.pose)) placedObstacles_.back().transform(obstacle.pose);
  }
  // Particle–obstacle pairs: the bounding sphere within 2ε of the obstacle's box, then of its
  // surface (a nearest-triangle search stopped at r + 2ε): a funnel's box holds every particle
  // inside it, its surface only those near the wall.
  std::vector<std::uint8_t> near(owned_ * obstacles_.size(), 0);
  parallelFor(0, owned_, kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      for (std::size_t o = 0; o < obstacles_.size(); ++o) {
        const double limit = spheres[i].radius + reach;
        if (!(distanceSquared(spheres[i].center, obstacleBoxes[o]) < limit * limit)) continue;
        contactdetection::PointQuery query;
        query.epsilon = limit;
        near[i * obstacles_.size() + o] =
            contactdetection::distance(placedObstacles_[o], spheres[i].center, query).found();
      }
  });
  const std::size_t particlePairs = pairs.size();
  for (std::size_t i = 0; i < owned_; ++i)
    for (std::size_t o = 0; o < obstacles_.size(); ++o)
      if (near[i * obstacles_.size() + o])
        pairs.push_back({static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(o), true,
                         (std::uint64_t{ids_[i]} << 32) | o});
  std::sort(pairs.begin() + static_cast<std::ptrdiff_t>(particlePairs), pairs.end(),
            [](const Interaction& a, const Interaction& b) { return a.key < b.key; });
  statistics_.obstaclePairsTested = pairs.size() - statistics_.particlePairsTested;
  return pairs;
}

Sphere World::boundingSphere(const Particle& particle) const noexcept {
  return {particle.position, shapes_[particle.shape].boundingRadius()};
}

std::vector<std::span<const ContactPoint>> World::sphereObstacleContacts(
    std::span<const Interaction> pairs) {
  // One sphereContacts call per obstacle over every sphere paired with it, through the
  // obstacle's tree. Spheres go into the obstacle's prepared frame.
  std::vector<std::span<const ContactPoint>> found(pairs.size());
  sphereObstacleFound_.resize(obstacles_.size());
  std::vector<std::size_t> pairOf;
  std::vector<Sphere> spheres;
  for (std::size_t o = 0; o < obstacles_.size(); ++o) {
    sphereObstacleFound_[o].clear();
    pairOf.clear();
    spheres.clear();
    const QueryMesh& obstacle = placedObstacles_[o];
    for (std::size_t p = statistics_.particlePairsTested; p < pairs.size(); ++p) {
      const Particle& particle = particles_[pairs[p].first];
      if (pairs[p].second != o || !shapes_[particle.shape].isSphere()) continue;
      Sphere sphere = boundingSphere(particle);
      if (obstacle.moved()) sphere.center = obstacle.inversePose().apply(sphere.center);
      pairOf.push_back(p);
      spheres.push_back(sphere);
    }
    if (spheres.empty()) continue;
    sphereObstacleFound_[o] = contactdetection::sphereContacts(spheres, obstacle, law_.epsilon);
    const std::vector<ContactPoint>& all = sphereObstacleFound_[o];
    for (std::size_t begin = 0; begin < all.size();) {  // sorted by sphere
      std::size_t end = begin;
      while (end < all.size() && all[end].first == all[begin].first)
        ++end;
      found[pairOf[all[begin].first]] =
          std::span<const ContactPoint>(all).subspan(begin, end - begin);
      begin = end;
    }
  }
  return found;
}

void World::evaluateForces(bool halfStepVelocities, Exchange* exchange) {
  Clock::time_point start = Clock::now();
  const std::vector<Interaction> pairs = findPairs();
  statistics_.broadPhaseSeconds = secondsSince(start);

  start = Clock::now();
  if (outcomes_.size() < pairs.size()) outcomes_.resize(pairs.size());
  const std::span<PairOutcome> outcomes(outcomes_.data(), pairs.size());
  detectContacts(pairs, outcomes);
  statistics_.contactDetectionSeconds = secondsSince(start);

  start = Clock::now();
  applyContactLaw(pairs, outcomes, halfStepVelocities);
  const std::vector<GhostForce> imported =
      exchange ? exchangeGhostForces(pairs, outcomes, *exchange) : std::vector<GhostForce>{};
  sumForces(pairs, outcomes, imported);
  statistics_.forceSeconds = secondsSince(start) - statistics_.communicationSeconds;
  forcesCurrent_ = true;
}

void World::detectContacts(std::span<const Interaction> pairs, std::span<PairOutcome> outcomes) {
  const std::vector<std::span<const ContactPoint>> sphereObstacleFound =
      sphereObstacleContacts(pairs);
  const double epsilon = law_.epsilon, filterDistance = parameters_.filterDistance;
  const bool volumeLaw = law_.model == ContactModel::volume;
  contactdetection::OverlapOptions overlapOptions;
  overlapOptions.curves = false;
  parallelFor(0, pairs.size(), kPairGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
      const Interaction& pair = pairs[p];
      PairOutcome& outcome = outcomes[p];
      outcome.regions.clear();
      outcome.forces.points.clear();
      if (volumeLaw) {  // every shape and obstacle is a closed mesh (addShape, addObstacle)
        const QueryMesh& other =
            pair.withObstacle ? placedObstacles_[pair.second] : placed_[pair.second];
        contactdetection::Overlap found =
            contactdetection::overlap(placed_[pair.first], other, overlapOptions);
        outcome.contacts.points.clear();
        outcome.rawPoints = found.segments;
        outcome.regions = std::move(found.regions);
        continue;
      }
      const Particle& one = particles_[pair.first];
      const bool firstSphere = shapes_[one.shape].isSphere();
      PairContacts& found = outcome.contacts;
      if (pair.withObstacle) {
        const QueryMesh& obstacle = placedObstacles_[pair.second];
        if (firstSphere)
          finishSphereMeshContacts(sphereObstacleFound[p], obstacle, filterDistance, found);
        else
          found = pairContacts(placed_[pair.first], obstacle, epsilon, filterDistance, true);
      } else {
        const Particle& other = particles_[pair.second];
        const bool secondSphere = shapes_[other.shape].isSphere();
        if (firstSphere && secondSphere)
          sphereSphereContacts(boundingSphere(one), boundingSphere(other), epsilon, found);
        else if (firstSphere)
          found = sphereMeshContacts(boundingSphere(one), placed_[pair.second], epsilon,
                                     filterDistance);
        else if (secondSphere)
          found = meshSphereContacts(placed_[pair.first], boundingSphere(other), epsilon,
                                     filterDistance);
        else
          found = pairContacts(placed_[pair.first], placed_[pair.second], epsilon, filterDistance);
      }
      outcome.rawPoints = found.trianglePairs;
    }
  });
}

void World::applyContactLaw(std::span<const Interaction> pairs, std::span<PairOutcome> outcomes,
                            bool halfStepVelocities) {
  const bool volumeLaw = law_.model == ContactModel::volume;
  const double dt = parameters_.timeStep;
  // The dashpot and friction want the velocities at the time of the positions. Between the
  // kicks they are half a step behind: predict them with the previous forces (the first half
  // kick again), which keeps the velocity-dependent forces second order in dt.
  std::vector<BodyMotion> motions(particles_.size());
  const double predict = halfStepVelocities ? 0.5 * dt : 0.0;
  parallelFor(0, particles_.size(), kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Particle& particle = particles_[i];
      const ParticleShape& shape = shapes_[particle.shape];
      const Vec3 momentum = particle.angularMomentum + particle.torque * predict;
      motions[i] = {
          particle.position,
          particle.velocity + (particle.force / shape.mass() + parameters_.gravity) * predict,
          rotatedApply(particle.orientation, shape.inverseInertia(), momentum)};
    }
  });
  parallelFor(0, pairs.size(), kPairGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t p = begin; p < end; ++p) {
      if (outcomes[p].contacts.points.empty() && outcomes[p].regions.empty()) continue;
      const Interaction& pair = pairs[p];
      const Particle& one = particles_[pair.first];
      const double mass = shapes_[one.shape].mass();
      const BodyMotion& firstMotion = motions[pair.first];
      BodyMotion secondMotion;
      double effectiveMass = mass;
      const TangentialSpring* spring = nullptr;
      if (pair.withObstacle) {
        const Obstacle& obstacle = obstacles_[pair.second];
        const Vec3 pivot = obstacle.pose.apply(obstacle.motion.pivot);
        secondMotion = {pivot, obstacle.motion.velocity, obstacle.motion.angularVelocity};
        spring = springOf(obstacleSprings_, pair.key);
      } else {
        const Particle& other = particles_[pair.second];
        const double otherMass = shapes_[other.shape].mass();
        secondMotion = motions[pair.second];
        effectiveMass = mass * otherMass / (mass + otherMass);
        spring = springOf(particleSprings_, pair.key);
      }
      if (volumeLaw) {
        double radius = equivalentRadius(shapes_[one.shape].volume());
        if (!pair.withObstacle)
          radius =
              std::min(radius, equivalentRadius(shapes_[particles_[pair.second].shape].volume()));
        outcomes[p].forces =
            volumePairForces(outcomes[p].regions, firstMotion, secondMotion, effectiveMass,
                             volumeStiffness(law_.stiffness, radius),
                             spring ? *spring : TangentialSpring{}, dt, law_);
        continue;
      }
      pairForces(outcomes[p].contacts.points, firstMotion, secondMotion, effectiveMass,
                 spring ? *spring : TangentialSpring{}, dt, law_, outcomes[p].forces);
    }
  });
}

std::vector<World::GhostForce> World::exchangeGhostForces(std::span<const Interaction> pairs,
                                                          std::span<const PairOutcome> outcomes,
                                                          Exchange& exchange) {
  // Forces on ghosts go to their owners; theirs on this process's particles come back.
  std::vector<GhostForce> exported;
  for (std::size_t p = 0; p < statistics_.particlePairsTested; ++p)
    if (pairs[p].second >= owned_)
      for (const PointForce& point : outcomes[p].forces.points)
        exported.push_back(
            {pairs[p].key, ids_[pairs[p].second], point.point.x, point.force, point.couple});
  const Clock::time_point swap = Clock::now();
  std::vector<GhostForce> imported = exchange.swapGhostForces(std::move(exported));
  statistics_.communicationSeconds += secondsSince(swap);
  std::stable_sort(imported.begin(), imported.end(),
                   [](const GhostForce& a, const GhostForce& b) { return a.key < b.key; });
  return imported;
}

void World::sumForces(std::span<const Interaction> pairs, std::span<const PairOutcome> outcomes,
                      std::span<const GhostForce> imported) {
  const bool volumeLaw = law_.model == ContactModel::volume;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> indexOfId;  // owned: (id, index)
  if (!imported.empty()) {
    for (std::size_t i = 0; i < owned_; ++i)
      indexOfId.push_back({ids_[i], static_cast<std::uint32_t>(i)});
    std::sort(indexOfId.begin(), indexOfId.end());
  }
  std::size_t nextImported = 0;
  // Applies the imported forces of the pairs before `key`, as their owner would have.
  const auto importBefore = [&](std::uint64_t key) {
    for (; nextImported < imported.size() && imported[nextImported].key < key; ++nextImported) {
      const GhostForce& ghost = imported[nextImported];
      const auto found =
          std::lower_bound(indexOfId.begin(), indexOfId.end(),
                           std::pair<std::uint32_t, std::uint32_t>{ghost.particle, 0});
      Particle& particle = particles_[found->second];
      particle.force -= ghost.force;
      particle.torque -= cross(ghost.point - particle.position, ghost.force);
      if (volumeLaw) particle.torque -= ghost.couple;
    }
  };

  // Summed pair by pair in the order of their ids: bitwise the same for any thread count, and
  // for any number of processes a DistributedWorld splits the particles over.
  for (Particle& particle : particles_)
    particle.force = particle.torque = Vec3{};
  contacts_.clear();
  particleSprings_.clear();
  obstacleSprings_.clear();
  statistics_.pairsInContact = statistics_.rawContactPoints = statistics_.contactPoints = 0;
  statistics_.overlappingContacts = 0;
  statistics_.deepestRatio = 0.0;
  elasticEnergy_ = 0.0;
  const bool friction = law_.friction > 0.0;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const Interaction& pair = pairs[p];
    const PairOutcome& outcome = outcomes[p];
    importBefore(pair.withObstacle ? std::numeric_limits<std::uint64_t>::max() : pair.key);
    statistics_.rawContactPoints += outcome.rawPoints;
    if (outcome.forces.points.empty()) continue;
    ++statistics_.pairsInContact;
    statistics_.deepestRatio =
        std::max(statistics_.deepestRatio, outcome.forces.deepest / (2.0 * law_.epsilon));
    elasticEnergy_ += outcome.forces.springEnergy;
    if (friction)
      (pair.withObstacle ? obstacleSprings_ : particleSprings_)
          .push_back({pair.key, outcome.forces.spring});
    Particle& one = particles_[pair.first];
    Particle* other =
        pair.withObstacle || pair.second >= owned_ ? nullptr : &particles_[pair.second];
    for (const PointForce& point : outcome.forces.points) {
      one.force += point.force;
      one.torque += cross(point.point.x - one.position, point.force);
      if (other) {
        other->force -= point.force;
        other->torque -= cross(point.point.x - other->position, point.force);
      }
      if (volumeLaw) {  // the point law has no couples (and adds no signed zeros)
        one.torque += point.couple;
        if (other) other->torque -= point.couple;
      }
      statistics_.contactPoints += 1;
      statistics_.overlappingContacts += point.point.overlap ? 1 : 0;
      // Field by field into a value-initialised record: its padding bytes are zeros, so that
      // copies of the contacts (Python's arrays, checkpoints read back) compare byte for byte.
      Contact& contact = contacts_.emplace_back();
      contact.point = point.point;
      contact.first = ids_[pair.first];
      contact.second = pair.withObstacle ? pair.second : ids_[pair.second];
      contact.withObstacle = pair.withObstacle;
      contact.depth = point.depth;
      contact.force = point.force;
      contact.couple = point.couple;
      contact.volume = point.volume;
    }
  }
  importBefore(std::numeric_limits<std::uint64_t>::max());
}

void World::halfKick() {
  const double half = 0.5 * parameters_.timeStep;
  const Vec3 gravity = parameters_.gravity;
  parallelFor(0, owned_, kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Particle& particle = particles_[i];
      particle.velocity += (particle.force / shapes_[particle.shape].mass() + gravity) * half;
      particle.angularMomentum += particle.torque * half;
      particle.angularVelocity = angularVelocityOf(particle, particle.orientation);
    }
  });
}

void World::drift() {
  const double dt = parameters_.timeStep;
  parallelFor(0, owned_, kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      Particle& particle = particles_[i];
      particle.position += particle.velocity * dt;
      // The turn at the angular velocity of the half-turned body (midpoint rule): an asymmetric
      // body's ω changes as it turns at fixed L, and the start's ω made a free spin gain energy
      // at first order in dt (0.7% in 100,000 steps at 50 rad/s).
      const Quaternion halfway = turned(particle.orientation, particle.angularVelocity, 0.5 * dt);
      particle.orientation = turned(particle.orientation, angularVelocityOf(particle, halfway), dt);
      particle.angularVelocity = angularVelocityOf(particle, particle.orientation);
    }
  });
  for (Obstacle& obstacle : obstacles_) {
    const ObstacleMotion& motion = obstacle.motion;
    const Vec3 pivot = obstacle.pose.apply(motion.pivot);
    const Quaternion turn = turned(Quaternion{}, motion.angularVelocity, dt);
    obstacle.pose = RigidTransform::translationBy(motion.velocity * dt) *
                    RigidTransform::rotationAbout(turn, pivot) * obstacle.pose;
  }
}

void World::step() {
  advance(nullptr);
}

void World::requireFiniteParticles(Exchange* exchange) const {
  std::uint32_t failed = std::numeric_limits<std::uint32_t>::max();
  for (std::size_t i = 0; i < owned_; ++i) {
    const Particle& particle = particles_[i];
    if (!isFinite(particle.position) || !isFinite(particle.velocity) ||
        !isFinite(particle.angularMomentum))
      failed = std::min(failed, ids_[i]);
  }
  if (exchange) failed = exchange->firstNonFinite(failed);
  if (failed != std::numeric_limits<std::uint32_t>::max())
    throw Error("dem: particle " + std::to_string(failed) + " is no longer finite at step " +
                std::to_string(stepCount_ + 1) + " (time step " + toString(parameters_.timeStep) +
                " too large for stiffness " + toString(parameters_.stiffness) +
                "? the suggested one is " + toString(suggestedTimeStep()) + ")");
}

void World::advance(Exchange* exchange) {
  const Clock::time_point start = Clock::now();
  double communication = 0.0;
  const auto refreshGhosts = [&] {
    if (!exchange) return;
    const Clock::time_point begin = Clock::now();
    exchange->refreshGhosts(*this);
    communication += secondsSince(begin);
  };
  if (!forcesCurrent_) {
    refreshGhosts();
    statistics_.communicationSeconds = 0.0;
    evaluateForces(false, exchange);
    communication += statistics_.communicationSeconds;
  }
  Clock::time_point phase = Clock::now();
  // One process only: a DistributedWorld would need every rank to agree to stop (dem/mpi).
  if (!exchange) requireCatchableMotion();
  halfKick();
  drift();
  requireFiniteParticles(exchange);  // before the broad phase meets it
  double integration = secondsSince(phase);
  refreshGhosts();
  statistics_.communicationSeconds = 0.0;
  evaluateForces(true, exchange);
  communication += statistics_.communicationSeconds;
  phase = Clock::now();
  halfKick();
  requireFiniteParticles(exchange);
  integration += secondsSince(phase);
  statistics_.communicationSeconds = communication;
  statistics_.integrationSeconds = integration;
  time_ += parameters_.timeStep;
  ++stepCount_;
  statistics_.totalSeconds = secondsSince(start);
}

void World::run(std::size_t steps) {
  for (std::size_t s = 0; s < steps; ++s)
    step();
}

Energies World::energies() const noexcept {
  Energies energies;
  for (const Particle& particle : particles()) {
    const double mass = shapes_[particle.shape].mass();
    energies.translational += 0.5 * mass * lengthSquared(particle.velocity);
    energies.rotational += 0.5 * dot(particle.angularVelocity, particle.angularMomentum);
    energies.gravitational -= mass * dot(parameters_.gravity, particle.position);
  }
  energies.elastic = forcesCurrent_ ? elasticEnergy_ : 0.0;
  return energies;
}

Vec3 World::linearMomentum() const noexcept {
  Vec3 sum;
  for (const Particle& particle : particles())
    sum += particle.velocity * shapes_[particle.shape].mass();
  return sum;
}

Vec3 World::angularMomentum() const noexcept {
  Vec3 sum;
  for (const Particle& particle : particles())
    sum += cross(particle.position, particle.velocity * shapes_[particle.shape].mass()) +
           particle.angularMomentum;
  return sum;
}

double World::suggestedTimeStep() const noexcept {
  if (owned_ == 0) return 0.0;
  double smallest = std::numeric_limits<double>::infinity();
  for (const Particle& particle : particles())
    smallest = std::min(smallest, shapes_[particle.shape].mass());
  return dem::suggestedTimeStep(law_.stiffness, smallest);
}

}  // namespace delta::dem
