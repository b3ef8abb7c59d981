#include "delta/dem/world.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <tuple>
#include <utility>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/dem/broad_phase.h"
#include "delta/dem/narrow_phase.h"
#include "delta/mesh/coordinate_range.h"
#include "delta/mesh/topology.h"
#include "delta/query/overlap.h"
#include "delta/query/part_nesting.h"
#include "delta/query/point_distance.h"
#include "delta/query/self_intersections.h"
#include "delta/query/sphere_contacts.h"

#include "detail/finite_state.h"
#include "detail/two_lanes.h"

namespace delta::dem {

namespace {

/// Pairs per parallel chunk of the general contact law (applyContactLaw), which runs on the pairs
/// it acts on only (0.1 to a few µs each): a few microseconds a chunk and more. (Chunks of two
/// made the threads take turns at the chunk counter's cache line more than the law worked.)
constexpr std::size_t kLawGrain = 8;
/// Pairs per parallel chunk in contact detection, and per kernel batch of the pairs whose
/// caches hold (World::detectContacts): a pair at rest costs about a µs.
constexpr std::size_t kDetectionGrain = 16;
/// Pairs of two spheres per parallel chunk and per batch of their law: a few hundred
/// nanoseconds of work each.
constexpr std::size_t kSphereGrain = 64;
/// Particles per parallel chunk when integrating: a few hundred ns each, so a chunk is tens of
/// µs; smaller than a step's share of the pool, so that the caller takes most of a short loop
/// while a worker wakes (with 512, 1000 particles' kicks and drifts ran no faster on two threads
/// than on one).
constexpr std::size_t kParticleGrain = 128;

using Clock = std::chrono::steady_clock;
/// Threads under load (World::advance): steps run on the calling thread alone after a step held
/// up by other processes, and the shortest step judged (a shorter one is all noise).
constexpr std::size_t kSerialSteps = 64;
/// ... doubling while the cores stay busy, up to this many.
constexpr std::size_t kLongestSerial = 1024;
/// Threaded steps are judged together until they have taken this long (seconds): a step of a
/// few hundred microseconds is too short to judge (a stall lasts a scheduler's time slice), and
/// its thread's CPU clock is a system call.
constexpr double kJudgedWall = 1e-3;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

void requirePositive(double value, const char* name) {
  if (!std::isfinite(value) || !(value > 0.0))
    throw Error(std::string("dem parameters: ") + name + " = " + toString(value) +
                " must be finite and positive");
}

/// A distance of the contact law (ε, the filter's): positive and within what the contact queries
/// take, from 2⁻⁴⁸¹ (below, their squares underflow: contacts.h) to the coordinate range
/// (beyond, the broad phase's margins overflow), so that no step refuses it half-way.
void requireContactDistance(double value, const char* name) {
  requirePositive(value, name);
  if (!(value >= 0x1p-481 && value <= kLargestCoordinate))
    throw Error(std::string("dem parameters: ") + name + " = " + toString(value) +
                " must lie between 2^-481 (" + toString(0x1p-481) + ") and the coordinate range " +
                coordinateRangeText());
}

void requireFinite(const Vec3& value, const std::string& what) {
  if (!isFinite(value)) throw Error(what + " = " + toString(value) + " must be finite");
}

/// The box of a particle's bounding sphere, radius `radius` about its centre of mass at
/// `position`: it holds the particle's mesh wherever it turns.
Aabb sphereBox(const Vec3& position, double radius) noexcept {
  return Aabb{position, position}.grown(radius);
}

ContactLaw contactLawOf(const Parameters& parameters) {
  requirePositive(parameters.timeStep, "timeStep");
  requireContactDistance(parameters.epsilon, "epsilon");
  requireContactDistance(parameters.filterDistance, "filterDistance");
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
  const PartNesting& nesting = partNesting(mesh);
  if (!nesting.nested())
    throw Error(what + "the volume contact law needs a mesh that bounds a solid: " +
                describePartNesting(nesting));
}

/// The general case of rotatedApply, out of line: a sphere's steps, which never take it, stay
/// short enough to inline.
[[gnu::noinline]] Vec3 rotatedApplyTurning(const Quaternion& q, const Mat3& m,
                                           const Vec3& v) noexcept {
  return q.rotate(m * q.conjugate().rotate(v));
}

/// R·M·Rᵀ·v for the rotation q, without forming matrices; a·v where M = a·I (a sphere's inertia:
/// turning it changes nothing, and the two rotations were a fifth of a sphere step), which the
/// caller says (`isotropic`: a shape's isotropicInertia(), decided once, for its inverse inertia).
Vec3 rotatedApply(const Quaternion& q, const Mat3& m, bool isotropic, const Vec3& v) noexcept {
  if (isotropic) return v * m(0, 0);
  return rotatedApplyTurning(q, m, v);
}

/// cos h from h² (h ≤ 2⁻⁶), and sin(h)/h: Taylor series whose first terms left out are below
/// 10⁻¹⁹ of theirs, so within rounding without a call. For doubles and for two to a vector
/// (turnLanes), with the same arithmetic.
template <class T>
T cosineOfSquare(T h2) noexcept {
  return 1.0 - h2 * (1.0 / 2 - h2 * (1.0 / 24 - h2 * (1.0 / 720 - h2 * (1.0 / 40320))));
}
template <class T>
T sincOfSquare(T h2) noexcept {
  return 1.0 - h2 * (1.0 / 6 - h2 * (1.0 / 120 - h2 * (1.0 / 5040)));
}

/// The largest h² = (|ω|·dt/2)² the series take.
constexpr double kSeriesReach = 0x1p-12;

/// The rotation by the vector ω·dt (angle |ω|·dt about ω), composed before q: the quaternion
/// (cos h, ω·sin(h)/|ω|), h = |ω|·dt/2. A step turns a particle by little (h ≤ 2⁻⁶): there the
/// series above give them without a square root, a division or a call.
Quaternion turned(const Quaternion& q, const Vec3& angularVelocity, double timeStep) noexcept {
  const double rate2 = lengthSquared(angularVelocity);
  if (!(rate2 > 0.0)) return q;
  const double h2 = 0.25 * rate2 * timeStep * timeStep;
  if (h2 <= kSeriesReach) {
    const double cosine = cosineOfSquare(h2);
    const Vec3 axis = angularVelocity * (0.5 * timeStep * sincOfSquare(h2));
    return Quaternion{cosine, axis.x, axis.y, axis.z} * q;  // renormalises
  }
  const double rate = std::sqrt(rate2);
  const double half = 0.5 * rate * timeStep;
  const Vec3 axis = angularVelocity * (std::sin(half) / rate);
  return Quaternion{std::cos(half), axis.x, axis.y, axis.z} * q;
}

/// Turns in lanes: the bodies of isotropic inertia, kTurnLanes at a time, two to a vector.
constexpr std::size_t kTurnLanes = 8;

/// turned(q, ω, dt) for each of kTurnLanes particles, in place, with the same bits: the
/// small-angle series and the product with q (operator*, renormalised) on two particles to a
/// vector, each step for all of them before the next, so that their chains of some forty
/// dependent operations, a square root and a division run side by side (one after the other
/// they were about 8% of the 100-sphere pile's step). A batch with a particle at rest or
/// turning by more than the series covers takes turned() itself.
void turnLanes(Particle* const (&lanes)[kTurnLanes], double timeStep) noexcept {
  using delta::detail::splat;
  using delta::detail::Two;
  using delta::detail::Two3;
  constexpr std::size_t kHalves = kTurnLanes / 2;
  using Parts = delta::detail::QuaternionParts<Two>;
  Two3 rate[kHalves];
  Parts orientation[kHalves];
  Two h2[kHalves];
  bool series = true;
  for (std::size_t h = 0; h < kHalves; ++h) {
    const Particle& a = *lanes[2 * h];
    const Particle& b = *lanes[2 * h + 1];
    rate[h] = Two3::of(a.angularVelocity, b.angularVelocity);
    orientation[h] = {Two{a.orientation.w, b.orientation.w}, Two{a.orientation.x, b.orientation.x},
                      Two{a.orientation.y, b.orientation.y}, Two{a.orientation.z, b.orientation.z}};
    const Two rate2 = dot(rate[h], rate[h]);
    h2[h] = splat(0.25) * rate2 * splat(timeStep) * splat(timeStep);
    const auto covered = rate2 > Two{} && h2[h] <= splat(kSeriesReach);
    series = series && covered[0] && covered[1];
  }
  if (!series) {
    for (Particle* particle : lanes)
      particle->orientation = turned(particle->orientation, particle->angularVelocity, timeStep);
    return;
  }
  Parts turn[kHalves];
  Two norm[kHalves];
  for (std::size_t h = 0; h < kHalves; ++h) {
    const Two3 axis = rate[h] * (splat(0.5 * timeStep) * sincOfSquare(h2[h]));
    // Quaternion{cosine, axis} * q, before operator*'s renormalisation.
    turn[h] = delta::detail::product<Two>({cosineOfSquare(h2[h]), axis.x, axis.y, axis.z},
                                          orientation[h]);
    const auto& t = turn[h];
    norm[h] = delta::detail::squareRoot(t.w * t.w + t.x * t.x + t.y * t.y + t.z * t.z);
  }
  for (std::size_t h = 0; h < kHalves; ++h) {
    const Two qw = turn[h].w / norm[h], qx = turn[h].x / norm[h], qy = turn[h].y / norm[h],
              qz = turn[h].z / norm[h];
    for (std::size_t k = 0; k < 2; ++k)  // a unit factor's product is never zero or NaN
      lanes[2 * h + k]->orientation =
          norm[h][k] > 0.0 ? Quaternion{qw[k], qx[k], qy[k], qz[k]} : Quaternion{};
  }
}

bool isIdentity(const RigidTransform& motion) noexcept {
  const Quaternion& q = motion.rotation;
  return q.w == 1.0 && q.x == 0.0 && q.y == 0.0 && q.z == 0.0 && motion.translation == Vec3{};
}

using Springs = std::vector<std::pair<std::uint64_t, TangentialSpring>>;

/// The springs of a run of pairs in increasing key order, found by walking the sorted springs
/// alongside them (a binary search a pair missed the cache at each of its steps).
class SpringCursor {
 public:
  explicit SpringCursor(const Springs& springs) noexcept : springs_(springs) {}

  /// The spring kept for `key` (none: nullptr); keys must come in increasing order.
  const TangentialSpring* find(std::uint64_t key) noexcept {
    if (!started_) {
      next_ = std::lower_bound(
          springs_.begin(), springs_.end(), key,
          [](const Springs::value_type& entry, std::uint64_t k) { return entry.first < k; });
      started_ = true;
    }
    while (next_ != springs_.end() && next_->first < key)
      ++next_;
    return next_ != springs_.end() && next_->first == key ? &next_->second : nullptr;
  }

 private:
  const Springs& springs_;
  Springs::const_iterator next_;
  bool started_ = false;
};

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
  checkCoordinateRange(sphereBox(state.position, shapes_[shape].boundingRadius()),
                       what + "its bounding sphere");
  requireFinite(state.velocity, what + "velocity");
  requireFinite(state.angularVelocity, what + "angular velocity");
  const Quaternion& q = state.orientation;
  Particle particle;
  particle.shape = static_cast<std::uint32_t>(shape);
  particle.position = state.position;
  particle.orientation = Quaternion::fromComponents(q.w, q.x, q.y, q.z);  // throws if invalid
  particle.velocity = state.velocity;
  particle.angularVelocity = state.angularVelocity;
  particle.angularMomentum =
      angularMomentumOf(particle, particle.orientation, state.angularVelocity, what);
  ids_.reserve(ids_.size() + 1);  // nothing changes before both have room
  particles_.push_back(particle);
  ids_.push_back(static_cast<std::uint32_t>(particles_.size() - 1));
  owned_ = particles_.size();
  stateChanged();
  return particles_.size() - 1;
}

std::size_t World::addObstacle(const Mesh& mesh, const ObstacleMotion& motion) {
  const std::string what = "dem: addObstacle " + std::to_string(obstacles_.size()) + ": ";
  requireFinite(motion.velocity, what + "velocity");
  requireFinite(motion.angularVelocity, what + "angular velocity");
  requireFinite(motion.pivot, what + "pivot");
  QueryMesh prepared(mesh);
  checkCoordinateRange(prepared.bounds(), what + "its mesh");
  if (law_.model == ContactModel::volume) requireVolumeLawMesh(prepared, what);
  obstacles_.push_back(Obstacle{mesh, std::move(prepared), RigidTransform{}, motion});
  forcesCurrent_ = false;
  neighbours_.valid = false;
  return obstacles_.size() - 1;
}

Particle& World::particleAt(std::size_t index, const char* operation) {
  if (index >= owned_)
    throw Error(std::string("dem: ") + operation + ": particle " + std::to_string(index) +
                " does not exist (" + std::to_string(owned_) + " particles)");
  return particles_[index];
}

void World::stateChanged() noexcept {
  forcesCurrent_ = false;
  neighbours_.valid = false;
}

void World::setTimeStep(double timeStep) {
  requirePositive(timeStep, "timeStep");
  parameters_.timeStep = timeStep;
}

// Each setter checks everything before it changes anything: a refused value leaves the World as
// it was, the next step included (an audit: a zero orientation was refused after the particle
// had moved, and a refused velocity still made the next step evaluate its forces anew).

void World::setPose(std::size_t index, const Vec3& position, const Quaternion& orientation) {
  Particle& particle = particleAt(index, "setPose");
  requireFinite(position, "dem: setPose: position");
  checkCoordinateRange(sphereBox(position, shapes_[particle.shape].boundingRadius()),
                       "dem: setPose: particle " + std::to_string(index) + "'s bounding sphere");
  const Quaternion turned =
      Quaternion::fromComponents(orientation.w, orientation.x, orientation.y, orientation.z);
  // The body keeps turning at the same rate; its angular momentum follows the new orientation.
  const Vec3 momentum =
      angularMomentumOf(particle, turned, particle.angularVelocity, "dem: setPose: ");
  stateChanged();
  particle.position = position;
  particle.orientation = turned;
  particle.angularMomentum = momentum;
}

void World::setVelocity(std::size_t index, const Vec3& velocity) {
  Particle& particle = particleAt(index, "setVelocity");
  requireFinite(velocity, "dem: setVelocity: velocity");
  stateChanged();
  particle.velocity = velocity;
}

void World::setAngularVelocity(std::size_t index, const Vec3& angularVelocity) {
  Particle& particle = particleAt(index, "setAngularVelocity");
  requireFinite(angularVelocity, "dem: setAngularVelocity: angular velocity");
  const Vec3 momentum = angularMomentumOf(particle, particle.orientation, angularVelocity,
                                          "dem: setAngularVelocity: ");
  stateChanged();
  particle.angularVelocity = angularVelocity;
  particle.angularMomentum = momentum;
}

Vec3 World::angularMomentumOf(const Particle& particle, const Quaternion& orientation,
                              const Vec3& angularVelocity, const std::string& what) const {
  const Mat3& inertia = shapes_[particle.shape].inertia();
  const Vec3 momentum =
      rotatedApply(orientation, inertia, isMultipleOfIdentity(inertia), angularVelocity);
  requireFinite(momentum, what + "angular momentum");
  return momentum;
}

Vec3 World::angularVelocityOf(const Particle& particle,
                              const Quaternion& orientation) const noexcept {
  return angularVelocityOf(particle, orientation, particle.angularMomentum);
}

Vec3 World::angularVelocityOf(const Particle& particle, const Quaternion& orientation,
                              const Vec3& angularMomentum) const noexcept {
  const ParticleShape& shape = shapes_[particle.shape];
  return rotatedApply(orientation, shape.inverseInertia(), shape.isotropicInertia(),
                      angularMomentum);
}

void World::placeBodies() {
  const std::size_t count = particles_.size();  // ghosts included
  if (placed_.size() > count)
    placed_.erase(placed_.begin() + static_cast<std::ptrdiff_t>(count), placed_.end());
  for (std::size_t i = placed_.size(); i < count; ++i)
    placed_.push_back(shapes_[particles_[i].shape].queryMesh());
  spheres_.resize(count);
  parallelFor(0, count, kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Particle& particle = particles_[i];
      const ParticleShape& shape = shapes_[particle.shape];
      if (!shape.isSphere()) {  // a sphere's contacts never read its (display) mesh
        placed_[i] = shape.queryMesh();
        placed_[i].transform(particle.pose());
      }
      spheres_[i] = boundingSphere(particle);
    }
  });
  placedObstacles_.clear();
  for (const Obstacle& obstacle : obstacles_) {
    placedObstacles_.push_back(obstacle.queryMesh);
    if (!isIdentity(obstacle.pose)) placedObstacles_.back().transform(obstacle.pose);
  }
}

bool World::neighbourListHolds() noexcept {
  NeighbourList& list = neighbours_;
  if (!list.valid || list.positions.size() != particles_.size() ||
      list.obstaclePoses.size() != obstacles_.size())
    return false;
  list.moved.resize(particles_.size());
  double particleMove = 0.0;
  for (std::size_t i = 0; i < particles_.size(); ++i) {
    list.moved[i] = distance(particles_[i].position, list.positions[i]);
    particleMove = std::max(particleMove, list.moved[i]);
  }
  // A rigid motion moves the points of a box farthest at a corner (|(R − R₀)·p + t − t₀| is
  // convex in p), so the corners of the mesh's box bound how far its surface moved.
  list.obstacleMoved.assign(obstacles_.size(), 0.0);
  double obstacleMove = 0.0;
  for (std::size_t o = 0; o < obstacles_.size(); ++o) {
    const RigidTransform& now = obstacles_[o].pose;
    const RigidTransform& then = list.obstaclePoses[o];
    if (now.translation == then.translation && now.rotation.w == then.rotation.w &&
        now.rotation.x == then.rotation.x && now.rotation.y == then.rotation.y &&
        now.rotation.z == then.rotation.z)
      continue;
    const Aabb& box = obstacles_[o].queryMesh.bounds();
    for (int corner = 0; corner < 8; ++corner) {
      const Vec3 p = box.corner(corner);
      list.obstacleMoved[o] =
          std::max(list.obstacleMoved[o], distance(now.apply(p), then.apply(p)));
    }
    obstacleMove = std::max(obstacleMove, list.obstacleMoved[o]);
  }
  return 2.0 * particleMove <= list.budget && particleMove + obstacleMove <= list.budget;
}

void World::makeNeighbourList() {
  NeighbourList& list = neighbours_;
  const double reach = 2.0 * law_.epsilon;
  // The skin: a tenth of the smallest particle's bounding radius, less a rounding allowance of
  // 64 ulps of the largest coordinate or length met (tests that agree with the cell list's and
  // the wall search's to a few ulps).
  double smallest = std::numeric_limits<double>::infinity(), magnitude = reach;
  for (const Sphere& sphere : spheres_) {
    smallest = std::min(smallest, sphere.radius);
    magnitude = std::max(magnitude, maxAbs(sphere.center) + 2.0 * sphere.radius);
  }
  std::vector<Aabb> obstacleBoxes;
  for (const Obstacle& obstacle : obstacles_) {
    obstacleBoxes.push_back(movedBox(obstacle.queryMesh.bounds(), obstacle.pose));
    magnitude = std::max(magnitude, std::max(maxAbs(obstacleBoxes.back().lower),
                                             maxAbs(obstacleBoxes.back().upper)));
  }
  const double skin = spheres_.empty() ? 0.0 : 0.1 * smallest;
  list.allowance = 64.0 * std::numeric_limits<double>::epsilon() * (magnitude + skin);
  list.budget = skin - list.allowance;

  list.particlePairs.clear();
  // A pair is evaluated where its lower id is owned (the only rule, in one process or many);
  // pairs of two ghosts are some other process's. Summed in the order of their ids, forces
  // come out the same however the particles are split.
  for (CandidatePair pair : nearbyPairs(spheres_, reach + std::max(skin, 0.0))) {
    if (ids_[pair.second] < ids_[pair.first]) std::swap(pair.first, pair.second);
    if (pair.first >= owned_) continue;
    list.particlePairs.push_back({pair.first, pair.second, false,
                                  (std::uint64_t{ids_[pair.first]} << 32) | ids_[pair.second]});
  }
  std::sort(list.particlePairs.begin(), list.particlePairs.end(),
            [](const Interaction& a, const Interaction& b) { return a.key < b.key; });

  // Particle–obstacle pairs: the bounding sphere within 2ε + skin of the obstacle's box, then of
  // its surface (a nearest-triangle search stopped at r + 2ε + skin): a funnel's box holds every
  // particle inside it, its surface only those near the wall.
  const double unreached = std::numeric_limits<double>::infinity();
  std::vector<double> gaps(owned_ * obstacles_.size(), unreached);
  parallelFor(0, owned_, kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      for (std::size_t o = 0; o < obstacles_.size(); ++o) {
        const double limit = spheres_[i].radius + reach + std::max(skin, 0.0);
        if (!(distanceSquared(spheres_[i].center, obstacleBoxes[o]) < limit * limit)) continue;
        contactdetection::PointQuery query;
        query.epsilon = limit;
        const contactdetection::PointDistance found =
            contactdetection::distance(placedObstacles_[o], spheres_[i].center, query);
        if (found.found()) gaps[i * obstacles_.size() + o] = found.distance - spheres_[i].radius;
      }
  });
  list.obstaclePairs.clear();
  for (std::size_t i = 0; i < owned_; ++i)
    for (std::size_t o = 0; o < obstacles_.size(); ++o)
      if (gaps[i * obstacles_.size() + o] != unreached)
        list.obstaclePairs.push_back({{static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(o),
                                       true, (std::uint64_t{ids_[i]} << 32) | o},
                                      gaps[i * obstacles_.size() + o]});
  // By key: the order of the particles' ids (as the particles' own order in one process).
  std::sort(list.obstaclePairs.begin(), list.obstaclePairs.end(),
            [](const NeighbourList::ListedObstacle& a, const NeighbourList::ListedObstacle& b) {
              return a.pair.key < b.pair.key;
            });

  list.positions.resize(particles_.size());
  for (std::size_t i = 0; i < particles_.size(); ++i)
    list.positions[i] = particles_[i].position;
  list.obstaclePoses.clear();
  for (const Obstacle& obstacle : obstacles_)
    list.obstaclePoses.push_back(obstacle.pose);
  list.moved.assign(particles_.size(), 0.0);
  list.obstacleMoved.assign(obstacles_.size(), 0.0);
  list.valid = true;
}

const std::vector<World::Interaction>& World::findPairs(bool reuseList) {
  placeBodies();
  if (!reuseList || !neighbourListHolds()) makeNeighbourList();
  // Kept for the next evaluation only where nothing but the motion of the particles and the
  // obstacles can change the pairs (a World of one process).
  neighbours_.valid = reuseList;
  // The particle pairs within 2ε now: the same pairs, tested the same way, as the cell list
  // would find. The obstacle pairs whose gap when the list was made, less how far the two have
  // moved since, is below 2ε (and the rounding allowance): a wall search again would cost as
  // much as the narrow phase, which finds no contacts for the few of them farther than 2ε.
  const NeighbourList& list = neighbours_;
  const double reach = 2.0 * law_.epsilon;
  pairs_.clear();
  // Grown by 16 ulps of the pair's coordinates and radii: a placed vertex lies up to a few ulps
  // of them beyond its shape's bounding radius (the rotation's rounding), and two cubes corner
  // to corner, their corners 4.8e-16 within 2ε by the narrow phase, were no pair (an audit).
  // Per pair, so the same on any number of processes.
  constexpr double kPlacing = 16.0 * std::numeric_limits<double>::epsilon();
  for (const Interaction& pair : list.particlePairs) {
    const Sphere& one = spheres_[pair.first];
    const Sphere& other = spheres_[pair.second];
    const double radii = one.radius + other.radius;
    const double limit =
        radii + reach + kPlacing * (std::max(maxAbs(one.center), maxAbs(other.center)) + radii);
    if (distanceSquared(one.center, other.center) < limit * limit) pairs_.push_back(pair);
  }
  statistics_.particlePairsTested = pairs_.size();
  for (const NeighbourList::ListedObstacle& listed : list.obstaclePairs) {
    const Interaction& pair = listed.pair;
    if (listed.gap - list.moved[pair.first] - list.obstacleMoved[pair.second] <
        reach + list.allowance)
      pairs_.push_back(pair);
  }
  statistics_.obstaclePairsTested = pairs_.size() - statistics_.particlePairsTested;
  return pairs_;
}

Sphere World::boundingSphere(const Particle& particle) const noexcept {
  return {particle.position, shapes_[particle.shape].boundingRadius()};
}

void World::evaluateForces(bool halfStepVelocities, Exchange* exchange) {
  ++evaluations_;
  contactsLost_ = false;
  Clock::time_point start = Clock::now();
  // The neighbour list is kept between evaluations in a World of one process; a distributed
  // one's particles and ghosts change between them.
  const std::vector<Interaction>& pairs = findPairs(exchange == nullptr);
  statistics_.broadPhaseSeconds = secondsSince(start);

  start = Clock::now();
  predictMotions(halfStepVelocities);
  if (outcomes_.size() < pairs.size()) outcomes_.resize(pairs.size());
  const std::span<PairOutcome> outcomes(outcomes_.data(), pairs.size());
  detectContacts(pairs, outcomes);
  statistics_.contactDetectionSeconds = secondsSince(start);

  start = Clock::now();
  applyContactLaw(pairs, outcomes);
  const std::vector<GhostForce> imported =
      exchange ? exchangeGhostForces(pairs, outcomes, *exchange) : std::vector<GhostForce>{};
  sumForces(pairs, outcomes, imported);
  statistics_.forceSeconds = secondsSince(start) - statistics_.communicationSeconds;
  forcesCurrent_ = true;
}

namespace {

/// Carries the caches keyed like `caches` over to the pairs [begin, end) that `wanted` picks
/// (sorted by key; new ones made with `skin`, those of pairs gone dropped into `spare`, whose
/// capacity is kept), and points cacheOf[p] at pair p's; `pairOf` is scratch. The caches stay
/// where they are in memory: only their keys and pointers move (a flowing hopper's 2,700 caches
/// of 224 bytes, moved each step the pairs changed, took 110 µs a step on the calling thread).
template <class Caches, class Cache, class Pairs, class Wanted>
void routeCaches(const Pairs& pairs, std::size_t begin, std::size_t end, const Wanted& wanted,
                 double skin, Caches& caches, Caches& spare, std::vector<Cache*>& cacheOf,
                 std::vector<std::size_t>& pairOf) {
  using Held = typename Caches::value_type::second_type;  // World::Held<Cache>
  // Most steps meet the same pairs as the step before (the neighbour list holds, and the same
  // pairs come within 2ε): then every cache stays where it is.
  std::size_t kept = 0;
  bool same = true;
  for (std::size_t p = begin; p < end && same; ++p)
    if (wanted(pairs[p])) same = kept < caches.size() && caches[kept++].first == pairs[p].key;
  if (same && kept == caches.size()) {
    kept = 0;
    for (std::size_t p = begin; p < end; ++p)
      if (wanted(pairs[p])) cacheOf[p] = caches[kept++].second.get();
    return;
  }
  pairOf.clear();
  spare.clear();
  std::size_t old = 0;
  for (std::size_t p = begin; p < end; ++p) {
    const auto& pair = pairs[p];
    if (!wanted(pair)) continue;
    while (old < caches.size() && caches[old].first < pair.key)
      ++old;
    if (old < caches.size() && caches[old].first == pair.key)
      spare.emplace_back(pair.key, std::move(caches[old].second));
    else
      spare.emplace_back(pair.key, Held(skin));
    pairOf.push_back(p);
  }
  caches.swap(spare);
  for (std::size_t k = 0; k < pairOf.size(); ++k)
    cacheOf[pairOf[k]] = caches[k].second.get();
}

}  // namespace

void World::routeContactCaches(std::span<const Interaction> pairs) {
  cacheOf_.assign(pairs.size(), nullptr);
  sphereCacheOf_.assign(pairs.size(), nullptr);
  overlapCacheOf_.assign(pairs.size(), nullptr);
  // The skin: half of ε (measured: ε/4 to ε gave the same settled pile within 4%, and the
  // hopper's flow 3% to 4% slower at ε/4 and ε; the volume law's overlap caches within 7% at
  // ε/4 and ε, better on one state and worse on the other; docs/performance.md). A pair at rest
  // keeps its triangle pairs for good.
  const double skin = 0.5 * law_.epsilon;
  const std::size_t particlePairs = statistics_.particlePairsTested;
  std::vector<std::size_t> pairOf;  // one allocation for the three
  const auto every = [](const Interaction&) { return true; };
  if (law_.model == ContactModel::volume) {
    routeCaches(pairs, 0, particlePairs, every, skin, particleOverlapCaches_, spareOverlapCaches_,
                overlapCacheOf_, pairOf);
    routeCaches(pairs, particlePairs, pairs.size(), every, skin, obstacleOverlapCaches_,
                spareOverlapCaches_, overlapCacheOf_, pairOf);
    return;
  }
  const auto sphere = [&](std::uint32_t particle) {
    return shapes_[particles_[particle].shape].isSphere();
  };
  const auto meshes = [&](const Interaction& pair) {
    return !sphere(pair.first) && (pair.withObstacle || !sphere(pair.second));
  };
  routeCaches(pairs, 0, particlePairs, meshes, skin, particleCaches_, spareCaches_, cacheOf_,
              pairOf);
  routeCaches(pairs, particlePairs, pairs.size(), meshes, skin, obstacleCaches_, spareCaches_,
              cacheOf_, pairOf);
  routeCaches(
      pairs, particlePairs, pairs.size(),
      [&](const Interaction& pair) { return sphere(pair.first); }, skin, sphereObstacleCaches_,
      spareSphereCaches_, sphereCacheOf_, pairOf);
}

/// What detectPair needs of its caller's run of pairs: the law's ε and h, and scratch kept from
/// pair to pair; the mesh pairs whose step 1 went to the kernel batch, for finishBatchedPairs.
struct World::DetectionRun {
  double epsilon, filterDistance;
  bool volumeLaw;
  contactdetection::OverlapOptions overlapOptions;
  std::vector<ContactPoint> sphereFound;  ///< a sphere's contacts on an obstacle, raw
  PairContacts onObstacle;                ///< and finished
  contactdetection::ContactBatch& batch;
  std::vector<std::pair<std::size_t, std::size_t>>& batched;  ///< (pair, index in the batch)

  /// The calling thread's batch, kept with its memory from step to step.
  static contactdetection::ContactBatch& threadBatch() {
    thread_local contactdetection::ContactBatch batch;
    return batch;
  }
  static std::vector<std::pair<std::size_t, std::size_t>>& threadBatched() {
    thread_local std::vector<std::pair<std::size_t, std::size_t>> batched;
    return batched;
  }
};

void World::detectContacts(std::span<const Interaction> pairs, std::span<PairOutcome> outcomes) {
  routeContactCaches(pairs);
  const bool volumeLaw = law_.model == ContactModel::volume;
  routes_.resize(pairs.size());
  onePoints_.resize(pairs.size());
  // Pairs of two spheres have their own batched law (sphereSphereLaw); marked here.
  spherePairs_.clear();
  for (std::size_t p = 0; p < statistics_.particlePairsTested; ++p) {
    const Interaction& pair = pairs[p];
    if (!volumeLaw && shapes_[particles_[pair.first].shape].isSphere() &&
        shapes_[particles_[pair.second].shape].isSphere()) {
      spherePairs_.push_back(p);
      routes_[p].route = PairRoute::onePoint;
    } else {
      routes_[p].route = PairRoute::general;
    }
  }
  // In chunks of kDetectionGrain pairs; the mesh pairs of a chunk whose caches hold have their
  // kept triangle pairs through the kernels in one batch (a pair at rest keeps a few: alone,
  // they would leave most of a batch's lanes idle), finished after the chunk's other pairs.
  parallelFor(0, pairs.size(), kDetectionGrain, [&](std::size_t chunkBegin, std::size_t chunkEnd) {
    DetectionRun run{law_.epsilon,
                     parameters_.filterDistance,
                     volumeLaw,
                     {},
                     {},
                     {},
                     DetectionRun::threadBatch(),
                     DetectionRun::threadBatched()};
    run.overlapOptions.curves = false;
    run.batch.clear();  // a step that threw may have left pairs in it
    run.batched.clear();
    for (std::size_t begin = chunkBegin; begin < chunkEnd; begin += kDetectionGrain) {
      const std::size_t end = std::min(chunkEnd, begin + kDetectionGrain);
      for (std::size_t p = begin; p < end; ++p) {
        if (p + 1 < end && cacheOf_[p + 1]) cacheOf_[p + 1]->prefetch();
        if (p + 1 < end && overlapCacheOf_[p + 1]) overlapCacheOf_[p + 1]->prefetch();
        detectPair(pairs[p], p, outcomes[p], run);
      }
      if (!run.batched.empty()) finishBatchedPairs(pairs, outcomes, run);  // none: spheres
    }
  });
  sphereSphereLaw(pairs);
  onePointLaw(pairs);
}

void World::detectPair(const Interaction& pair, std::size_t p, PairOutcome& outcome,
                       DetectionRun& run) {
  RoutedPair& routed = routes_[p];
  if (routed.route == PairRoute::onePoint && !pair.withObstacle) return;  // two spheres
  const double epsilon = run.epsilon, filterDistance = run.filterDistance;
  const bool firstSphere = shapes_[particles_[pair.first].shape].isSphere();
  if (!run.volumeLaw && firstSphere && pair.withObstacle) {
    // Through the pair's cache, the sphere in the obstacle's prepared frame.
    const QueryMesh& obstacle = placedObstacles_[pair.second];
    Sphere sphere = spheres_[pair.first];
    if (obstacle.moved()) sphere.center = obstacle.inversePose().apply(sphere.center);
    contactdetection::sphereContacts(sphere, obstacle, epsilon, *sphereCacheOf_[p],
                                     run.sphereFound);
    routed.rawPoints = run.sphereFound.size();
    if (run.sphereFound.size() <= 1) {  // most: one point, its law in a batch below
      routed.route = run.sphereFound.empty() ? PairRoute::apart : PairRoute::onePoint;
      if (!run.sphereFound.empty())
        finishSphereMeshContact(run.sphereFound.front(), obstacle, onePoints_[p].point.point);
      return;
    }
    finishSphereMeshContacts(run.sphereFound, obstacle, filterDistance, run.onObstacle);
    if (run.onObstacle.points.size() <= 1) {  // the others dominated by the one
      routed.route = run.onObstacle.points.empty() ? PairRoute::apart : PairRoute::onePoint;
      if (!run.onObstacle.points.empty()) onePoints_[p].point.point = run.onObstacle.points.front();
      return;
    }
    routed.route = PairRoute::general;
    outcome.regions.clear();
    outcome.forces.points.clear();
    outcome.contacts.points.assign(run.onObstacle.points.begin(), run.onObstacle.points.end());
    return;
  }
  routed.route = PairRoute::general;
  outcome.regions.clear();
  outcome.forces.points.clear();
  const QueryMesh& other = pair.withObstacle ? placedObstacles_[pair.second] : placed_[pair.second];
  if (run.volumeLaw) {  // every shape and obstacle is a closed mesh (addShape, addObstacle)
    contactdetection::Overlap found = contactdetection::overlap(
        placed_[pair.first], other, run.overlapOptions, *overlapCacheOf_[p]);
    outcome.contacts.points.clear();
    routed.rawPoints = found.segments;
    outcome.regions = std::move(found.regions);
    return;
  }
  const bool secondSphere = !pair.withObstacle && shapes_[particles_[pair.second].shape].isSphere();
  PairContacts& found = outcome.contacts;
  if (firstSphere) {
    found =
        sphereMeshContacts(boundingSphere(particles_[pair.first]), other, epsilon, filterDistance);
  } else if (secondSphere) {
    found = meshSphereContacts(placed_[pair.first], boundingSphere(particles_[pair.second]),
                               epsilon, filterDistance);
  } else if (cacheOf_[p]) {  // step 1 in the run's kernel batch (finishBatchedPairs)
    run.batched.emplace_back(p, addPairContacts(run.batch, placed_[pair.first], other, epsilon,
                                                pair.withObstacle, *cacheOf_[p]));
    return;
  } else {
    found = pairContacts(placed_[pair.first], other, epsilon, filterDistance, pair.withObstacle);
  }
  routed.rawPoints = found.trianglePairs;
}

void World::finishBatchedPairs(std::span<const Interaction> pairs, std::span<PairOutcome> outcomes,
                               DetectionRun& run) {
  run.batch.run();
  for (const auto& [p, index] : run.batched) {
    const Interaction& pair = pairs[p];
    const QueryMesh& other =
        pair.withObstacle ? placedObstacles_[pair.second] : placed_[pair.second];
    PairContacts& found = outcomes[p].contacts;
    found = batchedPairContacts(run.batch, index, placed_[pair.first], other, run.epsilon,
                                run.filterDistance, pair.withObstacle);
    routes_[p].rawPoints = found.trianglePairs;
  }
  run.batch.clear();  // for the next run of pairs
  run.batched.clear();
}

/// What a run of the batched one-point law carries from pair to pair: the springs' cursor (the
/// pairs come in increasing key order), and the dashpots of the last pair of shapes met (a pile
/// of one or a few sphere shapes takes the square roots once).
struct World::LawRun {
  explicit LawRun(const Springs& kept) noexcept : springs(kept) {}
  SpringCursor springs;
  std::uint64_t dampedShapes = std::numeric_limits<std::uint64_t>::max();
  PairDamping damping;
};

namespace {

/// The pairs `indices` (increasing) in parallel runs, each in batches of up to kSphereGrain:
/// `element(p, run)` makes pair p's batch element, `law(batch, from)` runs a batch whose first
/// pair is indices[from].
template <class Element, class LawRun, class MakeElement, class Law>
void inBatches(std::span<const std::size_t> indices, const Springs& springs,
               const MakeElement& element, const Law& law) {
  parallelFor(0, indices.size(), kSphereGrain, [&](std::size_t begin, std::size_t end) {
    LawRun run(springs);
    Element batch[kSphereGrain];
    for (std::size_t from = begin; from < end; from += kSphereGrain) {
      const std::size_t count = std::min(kSphereGrain, end - from);
      for (std::size_t k = 0; k < count; ++k)
        batch[k] = element(indices[from + k], run);
      law(std::span<const Element>(batch, count), from);
    }
  });
}

}  // namespace

[[gnu::always_inline]] inline OnePointLaw World::pairLaw(const Interaction& pair, std::size_t p,
                                                         LawRun& run) noexcept {
  const std::uint64_t shapes = std::uint64_t{particles_[pair.first].shape} << 32 |
                               (pair.withObstacle ? std::numeric_limits<std::uint32_t>::max()
                                                  : particles_[pair.second].shape);
  if (shapes != run.dampedShapes) {
    run.damping = pairDamping(law_, effectiveMass(pair));
    run.dampedShapes = shapes;
  }
  return {&motions_[pair.first],
          pair.withObstacle ? &obstacleMotions_[pair.second] : &motions_[pair.second], run.damping,
          run.springs.find(pair.key), &onePoints_[p]};
}

void World::onePointLaw(std::span<const Interaction> pairs) {
  spherePairs_.clear();  // now the obstacle pairs of one point
  for (std::size_t p = statistics_.particlePairsTested; p < pairs.size(); ++p)
    if (routes_[p].route == PairRoute::onePoint) spherePairs_.push_back(p);
  inBatches<OnePointPair, LawRun>(
      spherePairs_, obstacleSprings_,
      [&](std::size_t p, LawRun& run) {
        return OnePointPair{&onePoints_[p].point.point, pairLaw(pairs[p], p, run)};
      },
      [&](std::span<const OnePointPair> batch, std::size_t) {
        onePointForces(batch, parameters_.timeStep, law_);
      });
}

void World::sphereSphereLaw(std::span<const Interaction> pairs) {
  inBatches<SpherePair, LawRun>(
      spherePairs_, particleSprings_,
      [&](std::size_t p, LawRun& run) {
        const Interaction& pair = pairs[p];
        return SpherePair{&spheres_[pair.first], &spheres_[pair.second], pairLaw(pair, p, run)};
      },
      [&](std::span<const SpherePair> batch, std::size_t from) {
        bool touching[kSphereGrain];
        sphereSphereForces(batch, parameters_.timeStep, law_,
                           std::span<bool>(touching, batch.size()));
        for (std::size_t k = 0; k < batch.size(); ++k)
          routes_[spherePairs_[from + k]] = {touching[k] ? PairRoute::onePoint : PairRoute::apart,
                                             touching[k] ? 1u : 0u};
      });
}

void World::predictMotions(bool halfStepVelocities) {
  // The dashpot and friction want the velocities at the time of the positions. Between the
  // kicks they are half a step behind: predict them with the previous forces (the first half
  // kick again), which keeps the velocity-dependent forces second order in dt.
  motions_.resize(particles_.size());
  const double predict = halfStepVelocities ? 0.5 * parameters_.timeStep : 0.0;
  parallelFor(0, particles_.size(), kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Particle& particle = particles_[i];
      const ParticleShape& shape = shapes_[particle.shape];
      const Vec3 momentum = particle.angularMomentum + particle.torque * predict;
      motions_[i] = {
          particle.position,
          particle.velocity + (particle.force / shape.mass() + parameters_.gravity) * predict,
          rotatedApply(particle.orientation, shape.inverseInertia(), shape.isotropicInertia(),
                       momentum)};
    }
  });
  obstacleMotions_.clear();
  for (const Obstacle& obstacle : obstacles_)
    obstacleMotions_.push_back({obstacle.pose.apply(obstacle.motion.pivot),
                                obstacle.motion.velocity, obstacle.motion.angularVelocity});
}

double World::effectiveMass(const Interaction& pair) const noexcept {
  const double mass = shapes_[particles_[pair.first].shape].mass();
  if (pair.withObstacle) return mass;
  const double otherMass = shapes_[particles_[pair.second].shape].mass();
  return mass * otherMass / (mass + otherMass);
}

void World::applyContactLaw(std::span<const Interaction> pairs, std::span<PairOutcome> outcomes) {
  const bool volumeLaw = law_.model == ContactModel::volume;
  const double dt = parameters_.timeStep;
  const std::vector<BodyMotion>& motions = motions_;
  // Only the pairs in contact on the general route, picked first: in a pile of spheres almost
  // every pair took the batched law, and chunks of pairs to skip cost two threads more than one.
  lawPairs_.clear();
  for (std::size_t p = 0; p < pairs.size(); ++p)
    if (routes_[p].route == PairRoute::general &&
        !(outcomes[p].contacts.points.empty() && outcomes[p].regions.empty()))
      lawPairs_.push_back(p);
  parallelFor(0, lawPairs_.size(), kLawGrain, [&](std::size_t begin, std::size_t end) {
    // The particle pairs, then the obstacle pairs, each run in increasing key order.
    SpringCursor particleSprings(particleSprings_), obstacleSprings(obstacleSprings_);
    for (std::size_t k = begin; k < end; ++k) {
      const std::size_t p = lawPairs_[k];
      const Interaction& pair = pairs[p];
      const Particle& one = particles_[pair.first];
      const BodyMotion& firstMotion = motions[pair.first];
      const BodyMotion& secondMotion =
          pair.withObstacle ? obstacleMotions_[pair.second] : motions[pair.second];
      const double mass = effectiveMass(pair);
      const TangentialSpring* spring =
          pair.withObstacle ? obstacleSprings.find(pair.key) : particleSprings.find(pair.key);
      if (volumeLaw) {
        double radius = equivalentRadius(shapes_[one.shape].volume());
        if (!pair.withObstacle)
          radius =
              std::min(radius, equivalentRadius(shapes_[particles_[pair.second].shape].volume()));
        outcomes[p].forces = volumePairForces(outcomes[p].regions, firstMotion, secondMotion, mass,
                                              volumeStiffness(law_.stiffness, radius),
                                              spring ? *spring : TangentialSpring{}, dt, law_);
        continue;
      }
      pairForces(outcomes[p].contacts.points, firstMotion, secondMotion, mass,
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
      for (const PointForce& point : pointForces(p, outcomes))
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
  records_.pending = true;  // the records wait for contacts()
  particleSprings_.clear();
  obstacleSprings_.clear();
  // Tallied in locals and stored once (as members, each pair's tallies were stored and loaded
  // again, with a division and a maximum in that chain). The largest depth is divided once: a
  // division by a positive number keeps the order, so the largest ratio is the same number.
  std::size_t pairsInContact = 0, rawPoints = 0, contactPoints = 0, overlapping = 0;
  double deepest = 0.0, elastic = 0.0;
  const bool friction = law_.friction > 0.0;
  for (std::size_t p = 0; p < pairs.size(); ++p) {
    const Interaction& pair = pairs[p];
    importBefore(pair.withObstacle ? std::numeric_limits<std::uint64_t>::max() : pair.key);
    const PairRoute route = routes_[p].route;
    rawPoints += routes_[p].rawPoints;
    if (route == PairRoute::apart) continue;
    const std::span<const PointForce> points = pointForces(p, outcomes);
    if (points.empty()) continue;
    const PairForceSummary& forces = route == PairRoute::onePoint
                                         ? static_cast<const PairForceSummary&>(onePoints_[p])
                                         : outcomes[p].forces;
    ++pairsInContact;
    deepest = std::max(deepest, forces.deepest);
    elastic += forces.springEnergy;
    if (friction)
      (pair.withObstacle ? obstacleSprings_ : particleSprings_)
          .push_back({pair.key, forces.spring});
    Particle& one = particles_[pair.first];
    Particle* other =
        pair.withObstacle || pair.second >= owned_ ? nullptr : &particles_[pair.second];
    for (const PointForce& point : points) {
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
      overlapping += point.point.overlap ? 1 : 0;
    }
    contactPoints += points.size();
  }
  statistics_.pairsInContact = pairsInContact;
  statistics_.rawContactPoints = rawPoints;
  statistics_.contactPoints = contactPoints;
  statistics_.overlappingContacts = overlapping;
  statistics_.deepestRatio = deepest / (2.0 * law_.epsilon);
  elasticEnergy_ = elastic;
  importBefore(std::numeric_limits<std::uint64_t>::max());
}

std::span<const Contact> World::contacts() const {
  const std::lock_guard<std::mutex> lock(records_.mutex);
  if (contactsLost_)
    throw Error(
        "dem: contacts: the records of the last force evaluation went with the step that "
        "failed after it (the World is as that evaluation left it); the next step makes "
        "them anew");
  if (records_.pending) {
    makeContacts();
    records_.pending = false;
  }
  return records_.contacts;
}

void World::makeContacts() const {
  records_.contacts.clear();
  const std::span<const PairOutcome> outcomes(outcomes_.data(), pairs_.size());
  for (std::size_t p = 0; p < pairs_.size(); ++p) {
    const Interaction& pair = pairs_[p];
    for (const PointForce& point : pointForces(p, outcomes)) {
      // Field by field into a value-initialised record: its padding bytes are zeros, so that
      // copies of the contacts (Python's arrays, checkpoints read back) compare byte for byte.
      Contact& contact = records_.contacts.emplace_back();
      contact.point = point.point;
      // The ids from the pair's key, made with the ids of its evaluation: a DistributedWorld
      // renumbers its particles at the start of the next step.
      contact.first = static_cast<std::uint32_t>(pair.key >> 32);
      contact.second = static_cast<std::uint32_t>(pair.key);
      contact.withObstacle = pair.withObstacle;
      contact.depth = point.depth;
      contact.force = point.force;
      contact.couple = point.couple;
      contact.volume = point.volume;
    }
  }
}

std::span<const PointForce> World::pointForces(std::size_t p,
                                               std::span<const PairOutcome> outcomes) const {
  switch (routes_[p].route) {
    case PairRoute::onePoint:
      return {&onePoints_[p].point, 1};
    case PairRoute::apart:
      return {};
    case PairRoute::general:
      break;
  }
  return outcomes[p].forces.points;
}

void World::halfKick() {
  const double half = 0.5 * parameters_.timeStep;
  parallelFor(0, owned_, kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i)
      kick(particles_[i], half);
  });
}

void World::kick(Particle& particle, double half) const noexcept {
  particle.velocity +=
      (particle.force / shapes_[particle.shape].mass() + parameters_.gravity) * half;
  particle.angularMomentum += particle.torque * half;
  particle.angularVelocity = angularVelocityOf(particle, particle.orientation);
}

void World::kickAndDrift(bool keepStart) {
  const double dt = parameters_.timeStep, half = 0.5 * dt;
  // With keepStart (a World of one process: no ghosts), the moved particles are written into
  // the kept buffer, which then changes place with particles_: the state at the step's start
  // stays whole for restoreStepStart, at no cost beyond the step's own pass.
  std::vector<Particle>& moved = keepStart ? stepStart_.particles : particles_;
  if (keepStart) moved.resize(particles_.size());
  // One parallel loop: each particle's half kick, then its drift (they read only its own
  // state), so that a short step wakes the pool's workers once.
  parallelFor(0, owned_, kParticleGrain, [&](std::size_t begin, std::size_t end) {
    Particle* lanes[kTurnLanes];
    std::size_t waiting = 0;
    for (std::size_t i = begin; i < end; ++i) {
      Particle& particle = moved[i];
      if (keepStart) particle = particles_[i];
      kick(particle, half);
      particle.position += particle.velocity * dt;
      // A body of isotropic inertia (a sphere's) turns at L/I whatever its orientation: the ω
      // the kick gave it; in lanes, kTurnLanes at a time.
      if (shapes_[particle.shape].isotropicInertia()) {
        lanes[waiting++] = &particle;
        if (waiting == kTurnLanes) {
          turnLanes(lanes, dt);
          waiting = 0;
        }
        continue;
      }
      // Otherwise the turn at the angular velocity of the half-turned body (midpoint rule): an
      // asymmetric body's ω changes as it turns at fixed L, and the start's ω made a free spin
      // gain energy at first order in dt (0.7% in 100,000 steps at 50 rad/s).
      const Vec3 midpointRate = angularVelocityOf(
          particle, turned(particle.orientation, particle.angularVelocity, 0.5 * dt));
      particle.orientation = turned(particle.orientation, midpointRate, dt);
      particle.angularVelocity = angularVelocityOf(particle, particle.orientation);
    }
    for (std::size_t k = 0; k < waiting; ++k)
      lanes[k]->orientation = turned(lanes[k]->orientation, lanes[k]->angularVelocity, dt);
  });
  if (keepStart) {
    particles_.swap(moved);
    stepStart_.particlesMoved = true;
  }
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
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t particle = kNone, spring = kNone;
  // Every field a checkpoint holds (and its reader checks): a World that stepped into a value
  // that is not finite anywhere would write a checkpoint that cannot be read back.
  for (std::size_t i = 0; i < owned_; ++i)
    if (!detail::holdsFiniteState(particles_[i])) particle = std::min(particle, ids_[i]);
  // And the friction springs, by their pair's lower id (a spring kept from a checkpoint longer
  // than its contact's forces could have made it turned into NaN at the Coulomb limit).
  for (const auto* springs : {&particleSprings_, &obstacleSprings_})
    for (const auto& [key, kept] : *springs)
      if (!detail::holdsFiniteState(kept))
        spring = std::min(spring, static_cast<std::uint32_t>(key >> 32));
  std::uint64_t failed = std::uint64_t{particle} << 32 | spring;
  if (exchange) failed = exchange->firstNonFinite(failed);
  particle = static_cast<std::uint32_t>(failed >> 32);
  spring = static_cast<std::uint32_t>(failed);
  // The time, the same on every process (no agreement needed).
  if (!std::isfinite(time_ + parameters_.timeStep))
    throw Error("dem: the time is no longer finite at step " + std::to_string(stepCount_ + 1));
  if (particle == kNone && spring == kNone) return;
  throw Error("dem: " +
              (particle != kNone
                   ? "particle " + std::to_string(particle)
                   : "the friction spring of a contact of particle " + std::to_string(spring)) +
              " is no longer finite at step " + std::to_string(stepCount_ + 1) + " (time step " +
              toString(parameters_.timeStep) + " too large for stiffness " +
              toString(parameters_.stiffness) + "? the suggested one is " +
              toString(suggestedTimeStep()) + ")");
}

void World::requireBodiesInRange(Exchange* exchange) const {
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::uint32_t particle = kNone;
  std::size_t local = owned_;  // its index here, where it is here
  for (std::size_t i = 0; i < owned_; ++i) {
    const Particle& p = particles_[i];
    if (!boxInCoordinateRange(sphereBox(p.position, shapes_[p.shape].boundingRadius())) &&
        ids_[i] < particle) {
      particle = ids_[i];
      local = i;
    }
  }
  if (exchange) {
    const auto first = static_cast<std::uint32_t>(
        exchange->firstNonFinite(std::uint64_t{particle} << 32 | kNone) >> 32);
    if (first != particle) local = owned_;
    particle = first;
  }
  const std::string step = " at step " + std::to_string(stepCount_ + 1);
  if (particle != kNone) {
    const std::string what = "dem: particle " + std::to_string(particle);
    if (local < owned_) {
      const Particle& p = particles_[local];
      checkCoordinateRange(sphereBox(p.position, shapes_[p.shape].boundingRadius()),
                           what + "'s bounding sphere" + step);
    }
    throw Error(what + " (on another process) leaves the coordinate range " +
                coordinateRangeText() + step + ", within which Δ answers exactly");
  }
  // The obstacles, the same on every process; those at rest were checked when added.
  for (std::size_t k = 0; k < obstacles_.size(); ++k)
    if (!isIdentity(obstacles_[k].pose))
      checkCoordinateRange(movedBox(obstacles_[k].queryMesh.bounds(), obstacles_[k].pose),
                           "dem: obstacle " + std::to_string(k) + step);
}

void World::advance(Exchange* exchange) {
  // A DistributedWorld's ranks would all have to undo their parts, and agree that one failed;
  // they stop instead.
  if (exchange) {
    advanceOnce(exchange);
    return;
  }
  keepStepStart();
  try {
    advanceOnce(nullptr);
  } catch (...) {
    restoreStepStart();
    throw;
  }
}

void World::keepStartForces() {
  stepStart_.forces.resize(particles_.size());
  for (std::size_t i = 0; i < particles_.size(); ++i)
    stepStart_.forces[i] = {particles_[i].force, particles_[i].torque};
  stepStart_.forcesKept = true;
}

void World::keepStepStart() {
  // The particles are kept by kickAndDrift (it writes the moved ones elsewhere); the rest is
  // copied into the kept buffers (their capacity stays).
  stepStart_.particlesMoved = false;
  stepStart_.forcesKept = false;
  stepStart_.particleSprings = particleSprings_;
  stepStart_.obstacleSprings = obstacleSprings_;
  stepStart_.obstaclePoses.resize(obstacles_.size());
  for (std::size_t k = 0; k < obstacles_.size(); ++k)
    stepStart_.obstaclePoses[k] = obstacles_[k].pose;
  stepStart_.statistics = statistics_;
  stepStart_.elasticEnergy = elasticEnergy_;
  stepStart_.evaluations = evaluations_;
  stepStart_.forcesCurrent = forcesCurrent_;
  stepStart_.contactsPending = records_.pending;
  stepStart_.contactsLost = contactsLost_;
}

void World::restoreStepStart() noexcept {
  // Swapped back (no allocation where memory may have run out); the kept buffers are refilled
  // at the next step's start. Before kickAndDrift moved them, a step changes only the
  // particles' forces and torques, by a first evaluation: put back as they were (a checkpoint
  // or digest taken after the failed step is the one before it; an audit found 13 of 30
  // particles' forces changed).
  if (stepStart_.particlesMoved) {
    particles_.swap(stepStart_.particles);
  } else if (stepStart_.forcesKept) {
    for (std::size_t i = 0; i < stepStart_.forces.size(); ++i)
      std::tie(particles_[i].force, particles_[i].torque) = stepStart_.forces[i];
  }
  particleSprings_.swap(stepStart_.particleSprings);
  obstacleSprings_.swap(stepStart_.obstacleSprings);
  for (std::size_t k = 0; k < obstacles_.size(); ++k)
    obstacles_[k].pose = stepStart_.obstaclePoses[k];
  statistics_ = stepStart_.statistics;
  elasticEnergy_ = stepStart_.elasticEnergy;
  forcesCurrent_ = stepStart_.forcesCurrent;
  // The records of the last evaluation: kept where contacts() had made them, or where this step
  // failed before its evaluation began; otherwise its pairs and outcomes overwrote them.
  // (Lost at the start, by a step that failed before, they stay lost.)
  contactsLost_ = stepStart_.contactsLost ||
                  (stepStart_.contactsPending && evaluations_ != stepStart_.evaluations);
  records_.pending = stepStart_.contactsPending && !contactsLost_;
  // The neighbour list and the pairs' caches were made for the moved bodies: the list is made
  // anew; the caches hold for any pose (they bound the move since they were made).
  neighbours_.valid = false;
}

void World::advanceOnce(Exchange* exchange) {
  // Threads under load (world.h): threaded steps whose calling thread ran for less than 60% of
  // them, the rest put aside by the operating system or waiting for workers that were, were
  // held up by other processes on every core; the next steps run on the calling thread alone,
  // a few on the threads now and then to see whether the cores are free again. One process only
  // (a DistributedWorld's steps wait for other ranks).
  std::optional<delta::detail::SerialLoops> alone;
  if (serialSteps_ > 0) {
    alone.emplace();
    --serialSteps_;
  }
  const bool judging = !alone && exchange == nullptr && threadCount() > 1;
  if (judging && !loadWindow_.open)
    loadWindow_ = {true, Clock::now(), delta::detail::threadWorkSeconds()};
  const Clock::time_point start = Clock::now();
  double communication = 0.0;
  const auto refreshGhosts = [&] {
    if (!exchange) return;
    const Clock::time_point begin = Clock::now();
    exchange->refreshGhosts(*this);
    communication += secondsSince(begin);
  };
  if (!forcesCurrent_) {
    if (!exchange) keepStartForces();
    refreshGhosts();
    statistics_.communicationSeconds = 0.0;
    evaluateForces(false, exchange);
    communication += statistics_.communicationSeconds;
  }
  Clock::time_point phase = Clock::now();
  // One process only: a DistributedWorld would need every rank to agree to stop (dem/mpi).
  if (!exchange) requireCatchableMotion();
  kickAndDrift(exchange == nullptr);
  requireFiniteParticles(exchange);  // before the broad phase meets it
  requireBodiesInRange(exchange);    // before a pair's query does
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
  if (!judging) return;
  const double wall = secondsSince(loadWindow_.start);
  if (wall < kJudgedWall) return;
  loadWindow_.open = false;
  if (delta::detail::threadWorkSeconds() - loadWindow_.cpuStart >= 0.6 * wall) {
    loadedWindows_ = 0;
    serialPeriod_ = kSerialSteps;
  } else if (++loadedWindows_ == 2) {
    loadedWindows_ = 0;
    serialSteps_ = serialPeriod_;
    serialPeriod_ = std::min(2 * serialPeriod_, kLongestSerial);
  }
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
