#include "delta/dem/scenarios.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/mesh/primitives.h"

namespace delta::dem {
namespace {

constexpr double kGrainRadius = 0.01;   ///< r: the largest semi-axis of a granulate (m)
constexpr double kDensity = 2500.0;     ///< glass or rock (kg/m³)
constexpr double kGravity = 9.81;       ///< m/s²
constexpr int kGranulatePoints = 42;    ///< 80 triangles (primitives::granulate)
constexpr std::size_t kShapePool = 16;  ///< distinct granulates a scenario draws from
constexpr std::size_t kFrames = 100;    ///< output frames a run is meant to give

/// Random numbers from raw mt19937_64 output (no standard distribution: the same on every
/// standard library, like primitives::granulate).
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(engine_() >> 11) * 0x1p-53; }
  double uniform(double low, double high) { return low + (high - low) * uniform(); }
  /// A uniformly distributed rotation (Shoemake, "Uniform random rotations", Graphics Gems III).
  Quaternion rotation() {
    const double u = uniform(), a = 2.0 * std::numbers::pi * uniform(),
                 b = 2.0 * std::numbers::pi * uniform();
    return Quaternion::fromComponents(std::sqrt(1.0 - u) * std::sin(a),
                                      std::sqrt(1.0 - u) * std::cos(a), std::sqrt(u) * std::sin(b),
                                      std::sqrt(u) * std::cos(b));
  }
  std::uint64_t next() { return engine_(); }

 private:
  std::mt19937_64 engine_;
};

/// The parameters every granular scenario shares; granularWorld sets the stiffness and time step.
Parameters granularParameters(double restitution, double friction, ContactModel model) {
  Parameters parameters;
  parameters.contactModel = model;
  parameters.epsilon = kGrainRadius / 20.0;
  parameters.filterDistance = kGrainRadius / 4.0;
  parameters.restitution = restitution;
  parameters.friction = friction;
  parameters.gravity = {0.0, 0.0, -kGravity};
  parameters.stiffness = 1.0;  // valid stand-ins: granularWorld sets both from the masses
  parameters.timeStep = 1.0;
  return parameters;
}

/// The shared granulate shapes of a scenario: semi-axes r·(1, a, b), a, b in [0.6, 1].
std::vector<ParticleShape> granulateShapes(std::size_t count, Random& random) {
  std::vector<ParticleShape> shapes;
  for (std::size_t s = 0; s < std::min(count, kShapePool); ++s) {
    const Vec3 semiAxes{kGrainRadius, kGrainRadius * random.uniform(0.6, 1.0),
                        kGrainRadius * random.uniform(0.6, 1.0)};
    shapes.emplace_back(primitives::granulate(random.next(), semiAxes, kGranulatePoints), kDensity);
  }
  return shapes;
}

/// The largest bounding radius and mass of the shapes.
std::pair<double, double> largestRadiusAndMass(const std::vector<ParticleShape>& shapes) {
  double radius = 0.0, mass = 0.0;
  for (const ParticleShape& shape : shapes) {
    radius = std::max(radius, shape.boundingRadius());
    mass = std::max(mass, shape.mass());
  }
  return {radius, mass};
}

/// Lattice positions: `columns` × `columns` in x and y, centred on the z axis, layers up from
/// `bottom`, `spacing` apart, the first `count` of them.
std::vector<Vec3> lattice(std::size_t count, std::size_t columns, double spacing, double bottom) {
  std::vector<Vec3> positions;
  const double offset = 0.5 * static_cast<double>(columns - 1) * spacing;
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t layer = i / (columns * columns), inLayer = i % (columns * columns);
    positions.push_back({static_cast<double>(inLayer % columns) * spacing - offset,
                         static_cast<double>(inLayer / columns) * spacing - offset,
                         bottom + static_cast<double>(layer) * spacing});
  }
  return positions;
}

std::size_t framesInterval(std::size_t steps) {
  return std::max<std::size_t>(1, steps / kFrames);
}

/// A World of `count` granulates on the lattice (its first layer `bottomGap` above `bottom`),
/// each turned at random and nudged sideways by up to a tenth of r; the stiffness and time step
/// set for a fall to z = 0 from the top layer, or from the first layer where `impactFromTop` is
/// false (in a hopper the layers above land on the ones below, not on the floor).
struct GranularSetup {
  World world;
  double spacing;
  double top;  ///< the highest centre
};

/// The sphere with the mean volume of `shapes`.
ParticleShape meanSphere(const std::vector<ParticleShape>& shapes) {
  double volume = 0.0;
  for (const ParticleShape& shape : shapes)
    volume += shape.volume();
  volume /= static_cast<double>(shapes.size());
  return ParticleShape::sphere(std::cbrt(0.75 * volume / std::numbers::pi), kDensity);
}

GranularSetup granularWorld(std::size_t count, std::uint64_t seed, double restitution,
                            double friction, std::size_t columns, double bottomGap, double bottom,
                            bool impactFromTop, ParticleKind kind, ContactModel model) {
  Random random(seed);
  std::vector<ParticleShape> shapes = granulateShapes(count, random);
  // The lattice is the granulates' whatever the kind, so both kinds start in the same places.
  const double radius = largestRadiusAndMass(shapes).first;
  if (kind == ParticleKind::Sphere) shapes = {meanSphere(shapes)};
  const double heaviest = largestRadiusAndMass(shapes).second;
  Parameters parameters = granularParameters(restitution, friction, model);
  const double spacing = 2.0 * radius + 2.0 * parameters.epsilon + 0.3 * kGrainRadius;
  const double firstLayer = bottom + radius + bottomGap;
  const double top = firstLayer + static_cast<double>((count - 1) / (columns * columns)) * spacing;
  const double speed = std::sqrt(2.0 * kGravity * (impactFromTop ? top : firstLayer));
  parameters.stiffness = stiffnessForImpact(heaviest, speed, parameters.epsilon);
  World world(parameters);
  for (const ParticleShape& shape : shapes)
    world.addShape(shape);
  const double jitter = 0.1 * kGrainRadius;
  for (const Vec3& site : lattice(count, columns, spacing, firstLayer)) {
    ParticleState state;
    state.position =
        site + Vec3{random.uniform(-jitter, jitter), random.uniform(-jitter, jitter), 0};
    state.orientation = random.rotation();
    world.addParticle(static_cast<std::size_t>(random.next() % shapes.size()), state);
  }
  world.setTimeStep(world.suggestedTimeStep());
  return {std::move(world), spacing, top};
}

void requireCount(std::size_t count, const char* scenario) {
  if (count == 0) throw Error(std::string("dem scenario ") + scenario + ": count must be positive");
}

}  // namespace

Mesh openBox(double width, double depth, double height, double floor) {
  for (const auto& [value, name] :
       {std::pair{width, "width"}, std::pair{depth, "depth"}, std::pair{height, "height"}})
    if (!std::isfinite(value) || !(value > 0.0))
      throw Error(std::string("openBox: ") + name + " = " + toString(value) +
                  " must be finite and positive");
  if (!std::isfinite(floor)) throw Error("openBox: floor = " + toString(floor) + " must be finite");
  const double x = 0.5 * width, y = 0.5 * depth, top = floor + height;
  std::vector<Vec3> vertices = {{-x, -y, floor}, {x, -y, floor}, {x, y, floor}, {-x, y, floor},
                                {-x, -y, top},   {x, -y, top},   {x, y, top},   {-x, y, top}};
  // Normals inward: up from the floor, toward the middle from the walls.
  std::vector<TriangleIndices> triangles = {{0, 1, 2}, {0, 2, 3},   // floor
                                            {0, 4, 5}, {0, 5, 1},   // y = −y wall
                                            {1, 5, 6}, {1, 6, 2},   // x = +x
                                            {2, 6, 7}, {2, 7, 3},   // y = +y
                                            {3, 7, 4}, {3, 4, 0}};  // x = −x
  return Mesh(std::move(vertices), std::move(triangles));
}

Mesh funnel(double outletRadius, double topRadius, double outletHeight, double topHeight,
            int segments, int rows) {
  if (!std::isfinite(outletRadius) || !(outletRadius > 0.0) || !std::isfinite(topRadius) ||
      !(topRadius > 0.0))
    throw Error("funnel: radii " + toString(outletRadius) + " and " + toString(topRadius) +
                " must be finite and positive");
  if (!std::isfinite(outletHeight) || !std::isfinite(topHeight) || !(topHeight > outletHeight))
    throw Error("funnel: topHeight = " + toString(topHeight) +
                " must exceed outletHeight = " + toString(outletHeight));
  if (segments < 3) throw Error("funnel: segments = " + std::to_string(segments) + " must be ≥ 3");
  if (rows < 1) throw Error("funnel: rows = " + std::to_string(rows) + " must be ≥ 1");
  std::vector<Vec3> vertices;
  for (int row = 0; row <= rows; ++row) {
    const double along = static_cast<double>(row) / rows;
    const double radius = outletRadius + along * (topRadius - outletRadius);
    const double height = outletHeight + along * (topHeight - outletHeight);
    for (int s = 0; s < segments; ++s) {
      const double angle = 2.0 * std::numbers::pi * s / segments;
      vertices.push_back({radius * std::cos(angle), radius * std::sin(angle), height});
    }
  }
  std::vector<TriangleIndices> triangles;
  const auto around = static_cast<std::uint32_t>(segments);
  for (std::uint32_t row = 0; row < static_cast<std::uint32_t>(rows); ++row)
    for (std::uint32_t s = 0; s < around; ++s) {
      const std::uint32_t next = (s + 1) % around;
      const std::uint32_t low = row * around, high = (row + 1) * around;
      // Normals toward the axis (the side the particles are on).
      triangles.push_back({low + s, high + s, low + next});
      triangles.push_back({low + next, high + s, high + next});
    }
  return Mesh(std::move(vertices), std::move(triangles));
}

namespace {

/// A convex hexahedron from its corners, indexed like a box's: bit 0 the first direction, bit 1
/// the second, bit 2 the third (a right-handed triple), each face two triangles, normals out.
Mesh hexahedron(const std::array<Vec3, 8>& corners) {
  std::vector<Vec3> vertices(corners.begin(), corners.end());
  std::vector<TriangleIndices> triangles = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5},
                                            {0, 1, 5}, {0, 5, 4}, {2, 6, 7}, {2, 7, 3},
                                            {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
  return Mesh(std::move(vertices), std::move(triangles));
}

void requireThickness(double thickness, const char* function) {
  if (!std::isfinite(thickness) || !(thickness > 0.0))
    throw Error(std::string(function) + ": thickness = " + toString(thickness) +
                " must be finite and positive");
}

}  // namespace

std::vector<Mesh> openBoxWalls(double width, double depth, double height, double floor,
                               double thickness) {
  requireThickness(thickness, "openBoxWalls");
  openBox(width, depth, height, floor);  // throws as openBox does for the other arguments
  const double x = 0.5 * width, y = 0.5 * depth, t = thickness, middle = floor + 0.5 * height;
  return {primitives::box({width + 2.0 * t, depth + 2.0 * t, t}, {0.0, 0.0, floor - 0.5 * t}),
          primitives::box({t, depth + 2.0 * t, height}, {-x - 0.5 * t, 0.0, middle}),
          primitives::box({t, depth + 2.0 * t, height}, {x + 0.5 * t, 0.0, middle}),
          primitives::box({width, t, height}, {0.0, -y - 0.5 * t, middle}),
          primitives::box({width, t, height}, {0.0, y + 0.5 * t, middle})};
}

std::vector<Mesh> funnelWalls(double outletRadius, double topRadius, double outletHeight,
                              double topHeight, int segments, double thickness) {
  requireThickness(thickness, "funnelWalls");
  funnel(outletRadius, topRadius, outletHeight, topHeight, segments, 1);  // throws as funnel does
  std::vector<Mesh> pieces;
  for (int s = 0; s < segments; ++s) {
    std::array<Vec3, 8> corners;
    for (int corner = 0; corner < 8; ++corner) {
      // Bit 0: inner or outer face (radially out), bit 1: the segment's first or second side
      // (around the axis), bit 2: outlet or top (up): a right-handed triple.
      const bool outer = corner & 1, second = corner & 2, top = corner & 4;
      const double angle = 2.0 * std::numbers::pi * (s + (second ? 1 : 0)) / segments;
      const double radius = (top ? topRadius : outletRadius) + (outer ? thickness : 0.0);
      corners[static_cast<std::size_t>(corner)] = {
          radius * std::cos(angle), radius * std::sin(angle), top ? topHeight : outletHeight};
    }
    pieces.push_back(hexahedron(corners));
  }
  return pieces;
}

Scenario twoParticles(double restitution, double offsetFraction, double friction,
                      ContactModel model) {
  if (!std::isfinite(offsetFraction) || offsetFraction < 0.0 || offsetFraction >= 1.0)
    throw Error("twoParticles: offsetFraction = " + toString(offsetFraction) +
                " must lie in [0, 1)");
  const double radius = kGrainRadius, approachSpeed = 1.0;
  const ParticleShape sphere(primitives::icosphere(3, radius), kDensity);
  Parameters parameters;
  parameters.epsilon = radius / 20.0;
  parameters.filterDistance = radius / 4.0;
  parameters.restitution = restitution;
  parameters.friction = friction;
  parameters.gravity = {};
  parameters.contactModel = model;
  // Head-on, the pair (effective mass m/2) stops at depth ε undamped.
  parameters.stiffness = stiffnessForImpact(0.5 * sphere.mass(), approachSpeed, parameters.epsilon);
  parameters.timeStep = dem::suggestedTimeStep(parameters.stiffness, sphere.mass());
  World world(parameters);  // validates restitution and friction
  world.addShape(sphere);
  const double gap = 2.0 * parameters.epsilon + 0.1 * radius;  // surface to surface
  const double centres = 2.0 * radius + gap;
  ParticleState left, right;
  left.position = {-0.5 * centres, 0.0, 0.0};
  left.velocity = {0.5 * approachSpeed, 0.0, 0.0};
  right.position = {0.5 * centres, offsetFraction * 2.0 * radius, 0.0};
  right.velocity = {-0.5 * approachSpeed, 0.0, 0.0};
  world.addParticle(0, left);
  world.addParticle(0, right);
  // The volume law is softer: head-on, two spheres a depth δ into each other hold w = k·δ⁴/(8r²)
  // (the lens, V ≈ πrδ²/2 and |S| ≈ πrδ, with κ = k/(πr²)²), a quartic well that stops them at
  // δ = √(2rε) after 1.31·δ/v, and sends them back as long again.
  const double contact =
      model == ContactModel::volume
          ? 2.0 * 1.3110287771461 * std::sqrt(2.0 * radius * parameters.epsilon) / approachSpeed
          : contactDuration(parameters.stiffness, 0.5 * sphere.mass());
  const double duration = 0.1 * radius / approachSpeed + 3.0 * contact;
  const auto steps = static_cast<std::size_t>(std::ceil(duration / parameters.timeStep));
  return {"two-particles", std::move(world), steps, framesInterval(steps)};
}

Scenario settle(std::size_t count, std::uint64_t seed, ParticleKind kind, ContactModel model) {
  requireCount(count, "settle");
  const auto columns = static_cast<std::size_t>(std::ceil(std::cbrt(static_cast<double>(count))));
  GranularSetup setup =
      granularWorld(count, seed, 0.5, 0.5, columns, 0.5 * kGrainRadius, 0.0, true, kind, model);
  const double width = static_cast<double>(columns) * setup.spacing + kGrainRadius;
  const double height = setup.top + 2.0 * kGrainRadius;
  if (model == ContactModel::volume)  // closed convex pieces, a grain thick (scenarios.h)
    for (const Mesh& wall : openBoxWalls(width, width, height, 0.0, kGrainRadius))
      setup.world.addObstacle(wall);
  else
    setup.world.addObstacle(openBox(width, width, height));
  const double duration = 2.0 * std::sqrt(2.0 * setup.top / kGravity) + 0.1;
  const auto steps =
      static_cast<std::size_t>(std::ceil(duration / setup.world.parameters().timeStep));
  return {"settle", std::move(setup.world), steps, framesInterval(steps)};
}

Scenario hopper(std::size_t count, std::uint64_t seed, ParticleKind kind, ContactModel model) {
  requireCount(count, "hopper");
  const double r = kGrainRadius;
  const auto columns = static_cast<std::size_t>(std::ceil(std::cbrt(static_cast<double>(count))));
  // The funnel: its top wide enough for the lattice's corners, walls at 60° to the horizontal.
  const double spacingEstimate = 2.0 * r + 0.1 * r + 0.3 * r;
  const double outletRadius = 4.5 * r, outletHeight = 10.0 * r;
  // At least a grain wider than the outlet: a lattice of one or two columns (up to 8 particles)
  // is narrower than the outlet, and the funnel had no height.
  const double topRadius =
      std::max(std::numbers::sqrt2 * 0.5 * static_cast<double>(columns) * spacingEstimate + r,
               outletRadius + r);
  const double topHeight =
      outletHeight + (topRadius - outletRadius) * std::tan(std::numbers::pi / 3);
  GranularSetup setup =
      granularWorld(count, seed, 0.5, 0.3, columns, r, topHeight, false, kind, model);
  const double floorSize = 2.0 * (topRadius + 20.0 * r);
  if (model == ContactModel::volume) {  // closed convex pieces, a grain thick (scenarios.h)
    for (const Mesh& wall : funnelWalls(outletRadius, topRadius, outletHeight, topHeight, 48, r))
      setup.world.addObstacle(wall);
    setup.world.addObstacle(primitives::box({floorSize, floorSize, r}, {0, 0, -0.5 * r}));
  } else {
    setup.world.addObstacle(funnel(outletRadius, topRadius, outletHeight, topHeight));
    setup.world.addObstacle(primitives::quad(floorSize, floorSize, {0, 0, 0}));
  }
  const double duration = 0.5;  // the lattice falls into the funnel and flows out onto the floor
  const auto steps =
      static_cast<std::size_t>(std::ceil(duration / setup.world.parameters().timeStep));
  return {"hopper", std::move(setup.world), steps, framesInterval(steps)};
}

RestitutionMeter::RestitutionMeter(const World& world, std::size_t first, std::size_t second)
    : RestitutionMeter(world.particles(), first, second) {}

RestitutionMeter::RestitutionMeter(std::span<const Particle> particles, std::size_t first,
                                   std::size_t second)
    : first_(first), second_(second) {
  if (first >= particles.size() || second >= particles.size() || first == second)
    throw Error("RestitutionMeter: particles " + std::to_string(first) + " and " +
                std::to_string(second) + " must be two of the world's " +
                std::to_string(particles.size()));
  before_ = particles[first].velocity - particles[second].velocity;
}

void RestitutionMeter::observe(const World& world) {
  observe(world.particles(), world.contacts());
}

void RestitutionMeter::observe(std::span<const Particle> particles,
                               std::span<const Contact> contacts) {
  const auto low = static_cast<std::uint32_t>(std::min(first_, second_));
  const auto high = static_cast<std::uint32_t>(std::max(first_, second_));
  bool touching = false;
  for (const Contact& contact : contacts)
    touching =
        touching || (!contact.withObstacle && contact.first == low && contact.second == high);
  const Particle& one = particles[first_];
  const Particle& other = particles[second_];
  if (touching && !collided_) {
    collided_ = true;
    lineOfCentres_ = normalized(other.position - one.position);
  }
  if (collided_ && !touching) {
    separated_ = true;
    after_ = one.velocity - other.velocity;
  }
}

double RestitutionMeter::restitution() const noexcept {
  if (!separated_) return std::numeric_limits<double>::quiet_NaN();
  return std::fabs(dot(after_, lineOfCentres_)) / std::fabs(dot(before_, lineOfCentres_));
}

}  // namespace delta::dem
