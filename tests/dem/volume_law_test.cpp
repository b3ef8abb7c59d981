// The volume contact law (contact_model.h, ContactModel::volume): its forces are the derivatives
// of its energy, do not depend on the triangulation, give the asked restitution, conserve the
// energy of an elastic settle, and run in a World as the point law does.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "delta/core/error.h"
#include "delta/dem/checkpoint.h"
#include "delta/dem/contact_model.h"
#include "delta/dem/scenarios.h"
#include "delta/dem/world.h"
#include "delta/mesh/primitives.h"
#include "delta/query/overlap.h"

#include "kernels/triangle_pairs.h"

namespace delta::dem {
namespace {

using contactdetection::Overlap;
using contactdetection::OverlapOptions;
using delta::test::kSlowBuild;

constexpr double kDensity = 2500.0;

/// An axis-aligned cube of edge `edge` about `center`, each face split into n × n squares of two
/// triangles (12·n² triangles), vertices shared along the edges so that it is closed.
Mesh gridCube(int n, double edge, const Vec3& center = {}) {
  std::map<std::array<int, 3>, std::uint32_t> index;
  std::vector<Vec3> vertices;
  const auto vertex = [&](std::array<int, 3> grid) {
    const auto [found, added] =
        index.try_emplace(grid, static_cast<std::uint32_t>(vertices.size()));
    if (added)
      vertices.push_back(center + Vec3{grid[0] * edge / n - 0.5 * edge,
                                       grid[1] * edge / n - 0.5 * edge,
                                       grid[2] * edge / n - 0.5 * edge});
    return found->second;
  };
  std::vector<TriangleIndices> triangles;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // e_u × e_v = e_axis
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          const auto corner = [&](int di, int dj) {
            std::array<int, 3> grid{};
            grid[axis] = side * n;
            grid[u] = i + di;
            grid[v] = j + dj;
            return vertex(grid);
          };
          const std::uint32_t a = corner(0, 0), b = corner(1, 0), c = corner(1, 1),
                              d = corner(0, 1);
          if (side == 1) {  // normal +e_axis
            triangles.push_back({a, b, c});
            triangles.push_back({a, c, d});
          } else {
            triangles.push_back({a, c, b});
            triangles.push_back({a, d, c});
          }
        }
    }
  return Mesh(std::move(vertices), std::move(triangles));
}

/// A law for unit tests: k, ζ from e, μ.
ContactLaw lawOf(double stiffness, double restitution, double friction) {
  ContactLaw law;
  law.epsilon = 1e-3;
  law.stiffness = stiffness;
  law.dampingRatio = dampingRatio(restitution);
  law.friction = friction;
  law.tangentialStiffness = 2.0 / 7.0 * stiffness;
  law.model = ContactModel::volume;
  return law;
}

/// The wrench on the second body of a pair (force, torque about `centre`) from the forces on the
/// first.
struct Wrench {
  Vec3 force;
  Vec3 torque;
};
Wrench onSecond(const PairForces& forces, const Vec3& centre) {
  Wrench wrench;
  for (const PointForce& point : forces.points) {
    wrench.force -= point.force;
    wrench.torque -= cross(point.point.x - centre, point.force) + point.couple;
  }
  return wrench;
}

double elasticEnergy(const QueryMesh& first, const QueryMesh& second, double kappa) {
  double energy = 0.0;
  for (const auto& region : contactdetection::overlap(first, second, OverlapOptions{false}).regions)
    energy += 0.5 * kappa * region.volume * region.volume;
  return energy;
}

TEST(DemVolumeLaw, ForceAndTorqueAreMinusTheGradientOfTheEnergy) {
  // Two granulates, the second turned and pushed into the first: the law's force and torque on
  // the second are −∂w/∂x and −∂w/∂θ (central differences of w(V) under its rigid motions).
  const QueryMesh first(primitives::granulate(3, {0.01, 0.008, 0.007}));
  QueryMesh second(primitives::granulate(4, {0.01, 0.009, 0.006}));
  const RigidTransform pose{Quaternion::fromAxisAngle({0.3, -0.5, 1.0}, 0.7),
                            Vec3{0.0155, 0.003, -0.002}};
  second.setPose(pose);
  const double kappa = volumeStiffness(1e4, 0.008);
  const Overlap overlap = contactdetection::overlap(first, second, OverlapOptions{false});
  ASSERT_TRUE(overlap.any());
  const ContactLaw law = lawOf(1e4, 1.0, 0.0);
  const PairForces forces =
      volumePairForces(overlap.regions, {}, {pose.translation, {}, {}}, 1e-3, kappa, {}, 1e-5, law);
  const Wrench wrench = onSecond(forces, pose.translation);
  EXPECT_GT(length(wrench.force), 0.0);
  const double h = 1e-7;  // 1e-5 of the size: V is smooth there, and rounding stays small
  for (int axis = 0; axis < 3; ++axis) {
    Vec3 step;
    step[static_cast<std::size_t>(axis)] = h;
    QueryMesh moved = second;
    moved.setPose({pose.rotation, pose.translation + step});
    const double ahead = elasticEnergy(first, moved, kappa);
    moved.setPose({pose.rotation, pose.translation - step});
    const double behind = elasticEnergy(first, moved, kappa);
    const double force = -(ahead - behind) / (2.0 * h);
    EXPECT_NEAR(force, wrench.force[static_cast<std::size_t>(axis)], 1e-5 * length(wrench.force))
        << "axis " << axis;
    // A turn by ±h about the axis through the second body's centre.
    const double angle = h / 0.01;
    moved.setPose(
        RigidTransform::rotationAbout(Quaternion::fromAxisAngle(step, angle), pose.translation) *
        pose);
    const double turnedAhead = elasticEnergy(first, moved, kappa);
    moved.setPose(
        RigidTransform::rotationAbout(Quaternion::fromAxisAngle(step, -angle), pose.translation) *
        pose);
    const double turnedBehind = elasticEnergy(first, moved, kappa);
    const double torque = -(turnedAhead - turnedBehind) / (2.0 * angle);
    EXPECT_NEAR(torque, wrench.torque[static_cast<std::size_t>(axis)],
                1e-5 * length(wrench.torque) + 1e-6 * length(wrench.force) * 0.01)
        << "axis " << axis;
  }
  EXPECT_DOUBLE_EQ(forces.springEnergy, elasticEnergy(first, second, kappa));
}

TEST(DemVolumeLaw, DampingOpposesTheNormalVelocityAndNeverPulls) {
  // A smaller cube 0.5 mm into a larger one's +x face (no faces in a common plane).
  const QueryMesh first(gridCube(1, 0.02));
  QueryMesh second(gridCube(1, 0.016));
  second.setPose({Quaternion{}, {0.0175, 0.0, 0.0}});
  const Overlap overlap = contactdetection::overlap(first, second, OverlapOptions{false});
  ASSERT_EQ(overlap.regions.size(), 1u);
  const double kappa = volumeStiffness(1e4, 0.01), mass = 1e-2;
  const ContactLaw law = lawOf(1e4, 0.5, 0.0);
  const double spring = kappa * overlap.regions[0].volume * length(overlap.regions[0].areaVector);
  const auto pushOnSecond = [&](double speed) {  // the second moving along +x at `speed`
    const PairForces forces = volumePairForces(
        overlap.regions, {}, {{0.0175, 0, 0}, {speed, 0, 0}, {}}, mass, kappa, {}, 1e-5, law);
    return -forces.points.at(0).force.x;
  };
  EXPECT_NEAR(pushOnSecond(0.0), spring, 1e-12 * spring);
  EXPECT_GT(pushOnSecond(-0.1), spring);  // approaching: more
  EXPECT_LT(pushOnSecond(0.1), spring);   // parting: less
  EXPECT_EQ(pushOnSecond(1e6), 0.0);      // never pulls
  const double c =
      2.0 * law.dampingRatio * std::sqrt(mass * kappa) * length(overlap.regions[0].areaVector);
  EXPECT_NEAR(pushOnSecond(-0.1) - spring, 0.1 * c, 1e-9 * spring);
}

/// The force and torque (about the cube's centre) of a cube of n × n squares a face resting,
/// tilted and slightly sunk, on a floor box.
Wrench cubeOnFloor(int n) {
  const double edge = 0.02;
  const QueryMesh floor(primitives::box({0.1, 0.1, 0.01}, {0.0, 0.0, -0.005}));
  QueryMesh cube(gridCube(n, edge));
  const Vec3 centre{0.001, -0.002, 0.5 * edge - 0.0004};
  const RigidTransform pose{Quaternion::fromAxisAngle({1.0, 0.4, 0.0}, 0.03), centre};
  cube.setPose(pose);
  const Overlap overlap = contactdetection::overlap(cube, floor, OverlapOptions{false});
  const double kappa = volumeStiffness(1e4, equivalentRadius(edge * edge * edge));
  const PairForces forces = volumePairForces(overlap.regions, {centre, {}, {}}, {}, 1e-2, kappa, {},
                                             1e-5, lawOf(1e4, 1.0, 0.0));
  Wrench onCube;
  for (const PointForce& point : forces.points) {
    onCube.force += point.force;
    onCube.torque += cross(point.point.x - centre, point.force) + point.couple;
  }
  return onCube;
}

TEST(DemVolumeLaw, ACubeOf12And768TrianglesFeelsTheSameForce) {
  const Wrench coarse = cubeOnFloor(1), fine = cubeOnFloor(8);
  EXPECT_EQ(gridCube(8, 1.0).triangleCount(), 768u);
  ASSERT_GT(coarse.force.z, 0.0);
  ASSERT_GT(length(coarse.torque), 0.0);  // tilted: the deeper edge pushes harder
  const double forceScale = length(coarse.force), torqueScale = length(coarse.torque);
  std::printf("cube 12 vs 768: force %.17g vs %.17g (relative %.3g), torque relative %.3g\n",
              coarse.force.z, fine.force.z, length(coarse.force - fine.force) / forceScale,
              length(coarse.torque - fine.torque) / torqueScale);
  EXPECT_LE(length(coarse.force - fine.force), 1e-9 * forceScale);
  EXPECT_LE(length(coarse.torque - fine.torque), 1e-9 * torqueScale);
}

TEST(DemVolumeLaw, TwoIcospheresPushAsTheSphericalLensWithinTheirDiscretisation) {
  // Two spheres of radius R, centres d apart: the lens V = π(4R + d)(2R − d)²/12 and the disc
  // |S| = πa², a² = R² − d²/4. The icospheres (5,120 triangles) are inscribed; their own volume
  // falls short of the sphere's by a fraction δ, and the lens, thin, by a few times δ·R/h
  // (h = R − d/2 its half-thickness): the polyhedron lies inside the sphere by δ·R/3 on the
  // mean, which thins the lens by that on either side; V ∝ h² and |S| ∝ h then fall short by
  // about (2/3 + 1/3)·δ·R/h.
  const double radius = 0.01;
  const Mesh sphere = primitives::icosphere(4, radius);
  ASSERT_EQ(sphere.triangleCount(), 5120u);
  const QueryMesh first(sphere);
  const double sphereVolume = 4.0 / 3.0 * std::numbers::pi * radius * radius * radius;
  const ParticleShape shape(sphere, kDensity);
  const double deficit = 1.0 - shape.volume() / sphereVolume;
  EXPECT_GT(deficit, 0.0);
  for (const double d : {1.9 * radius, 1.7 * radius, 1.4 * radius}) {
    QueryMesh second(sphere);
    second.setPose({Quaternion::fromAxisAngle({0.2, 0.7, 0.1}, 0.4), {d, 0.0, 0.0}});
    const Overlap overlap = contactdetection::overlap(first, second, OverlapOptions{false});
    ASSERT_EQ(overlap.regions.size(), 1u);
    const double lensVolume =
        std::numbers::pi * (4.0 * radius + d) * (2.0 * radius - d) * (2.0 * radius - d) / 12.0;
    const double discArea = std::numbers::pi * (radius * radius - 0.25 * d * d);
    const double kappa = volumeStiffness(1e4, radius);
    const double force = kappa * overlap.regions[0].volume * length(overlap.regions[0].areaVector);
    const double analytic = kappa * lensVolume * discArea;
    const double error = std::fabs(force / analytic - 1.0);
    const double allowed = 1.5 * deficit * radius / (radius - 0.5 * d);
    std::printf(
        "lens d = %.2f R: force %.6g N, analytic %.6g N, error %.3g%% (mesh volume deficit "
        "%.3g%%, allowed %.3g%%)\n",
        d / radius, force, analytic, 100.0 * error, 100.0 * deficit, 100.0 * allowed);
    EXPECT_LT(error, allowed) << "d = " << d / radius << " R";
    // Along the line of centres, but for the facets (the second icosphere is turned).
    EXPECT_LT(length(cross(overlap.regions[0].areaVector, Vec3{1, 0, 0})),
              deficit * length(overlap.regions[0].areaVector));
  }
}

/// `old`'s shapes, particles (as they are) and obstacles in a new World with `parameters`.
World remade(const World& old, const Parameters& parameters) {
  World world(parameters);
  for (const ParticleShape& shape : old.shapes())
    world.addShape(shape);
  for (const Particle& particle : old.particles())
    world.addParticle(particle.shape, {particle.position, particle.orientation, particle.velocity,
                                       particle.angularVelocity});
  for (const Obstacle& obstacle : old.obstacles())
    world.addObstacle(obstacle.mesh, obstacle.motion);
  return world;
}

/// The largest |E − E₀| / E₀ over `steps` steps of an elastic, frictionless settle of 27
/// granulates with `model` (the first `steps` of the run: the fall and the first impacts).
double elasticSettleDrift(ContactModel model, std::size_t steps, std::size_t* contactSteps) {
  const Scenario scenario = settle(27, 3, ParticleKind::Mesh, model);
  Parameters parameters = scenario.world.parameters();
  parameters.restitution = 1.0;
  parameters.friction = 0.0;
  World world = remade(scenario.world, parameters);
  const double start = world.energies().total();
  double drift = 0.0;
  *contactSteps = 0;
  for (std::size_t s = 0; s < steps; ++s) {
    world.step();
    *contactSteps += world.contacts().empty() ? 0 : 1;
    drift = std::max(drift, std::fabs(world.energies().total() - start) / std::fabs(start));
  }
  return drift;
}

TEST(DemVolumeLaw, AnElasticFrictionlessSettleKeepsItsEnergy) {
  // The first layer lands after about 1,100 steps; then the granulates bounce on the floor and
  // on each other.
  const std::size_t steps = kSlowBuild ? 1500 : 3000;
  std::size_t volumeContacts = 0, pointContacts = 0;
  const double volume = elasticSettleDrift(ContactModel::volume, steps, &volumeContacts);
  const double point = elasticSettleDrift(ContactModel::point, steps, &pointContacts);
  std::printf(
      "elastic settle of 27 over %zu steps: energy drift %.3g%% (volume law, %zu steps "
      "with contacts), %.3g%% (point law, %zu)\n",
      steps, 100.0 * volume, volumeContacts, 100.0 * point, pointContacts);
  EXPECT_GT(volumeContacts, steps / 10);  // the test looks at contacts, not at a free fall
  EXPECT_LT(volume, 1e-3);
  EXPECT_GT(point, volume);
}

TEST(DemVolumeLaw, TwoParticlesReboundWithTheAskedRestitution) {
  for (const double e : {0.5, 0.9}) {
    Scenario scenario = twoParticles(e, 0.0, 0.0, ContactModel::volume);
    RestitutionMeter meter(scenario.world);
    for (std::size_t s = 0; s < scenario.steps; ++s) {  // the scenario's run sees them part
      scenario.world.step();
      meter.observe(scenario.world);
    }
    ASSERT_TRUE(meter.separated()) << "e = " << e;
    std::printf("two-particles, volume law: restitution %.4f (asked %.2f)\n", meter.restitution(),
                e);
    EXPECT_NEAR(meter.restitution(), e, 0.02 * e);
  }
}

TEST(DemVolumeLaw, AlignedCubesMeetingHeadOnLeaveHeadOn) {
  // Two cubes 2 cm across, aligned, meeting face to face along z: their side faces lie in one
  // plane. The overlap's area vector was the one-sided derivative the displacement (+x first)
  // takes, and the pair left with a sideways kick of 9% and 1.9% of the energy in spin.
  const ParticleShape cube(gridCube(1, 0.02), kDensity);
  Parameters parameters;
  parameters.epsilon = 0.0005;
  parameters.filterDistance = 0.0025;
  parameters.restitution = 0.5;
  parameters.gravity = {};
  parameters.stiffness = stiffnessForImpact(cube.mass(), 1.0, parameters.epsilon);
  parameters.timeStep = suggestedTimeStep(parameters.stiffness, cube.mass());
  parameters.contactModel = ContactModel::volume;
  World world(parameters);
  world.addShape(cube);
  ParticleState state;
  state.position = {0.0, 0.0, -0.0105};
  state.velocity = {0.0, 0.0, 0.5};
  world.addParticle(0, state);
  state.position = {0.0, 0.0, 0.0105};
  state.velocity = {0.0, 0.0, -0.5};
  world.addParticle(0, state);
  std::size_t contactSteps = 0;
  for (std::size_t s = 0; s < 2000 && (contactSteps == 0 || !world.contacts().empty()); ++s) {
    world.step();
    contactSteps += world.contacts().empty() ? 0 : 1;
  }
  ASSERT_GT(contactSteps, 10u);
  ASSERT_TRUE(world.contacts().empty()) << "they part";
  double sideways = 0.0, spin = 0.0, along = 0.0;
  for (const Particle& particle : world.particles()) {
    sideways = std::max(sideways, std::hypot(particle.velocity.x, particle.velocity.y));
    spin = std::max(spin, length(particle.angularVelocity));
    along = std::max(along, std::abs(particle.velocity.z));
  }
  std::printf("aligned cubes head on: leave at %.4g m/s along z, %.3g sideways, spin %.3g rad/s\n",
              along, sideways, spin);
  EXPECT_NEAR(along, 0.25, 0.02);  // e = 0.5
  EXPECT_LT(sideways, 1e-12);
  EXPECT_LT(spin, 1e-9);
}

/// How far a 1 cm cube resting on a floor slab slides along an incline of 15° (gravity tilted)
/// in `steps` steps after `settling` steps, with Coulomb coefficient `friction`; `timeStep` is
/// set to the step used.
double slideOnAnIncline(double friction, std::size_t settling, std::size_t steps,
                        double& timeStep) {
  const double slope = 15.0 * std::numbers::pi / 180.0, g = 9.81;
  const ParticleShape cube(gridCube(1, 0.01), kDensity);
  Parameters parameters;
  parameters.epsilon = 0.0005;
  parameters.filterDistance = 0.0025;
  parameters.restitution = 0.5;
  parameters.friction = friction;
  parameters.gravity = {g * std::sin(slope), 0.0, -g * std::cos(slope)};
  parameters.stiffness = stiffnessForImpact(cube.mass(), 0.3, parameters.epsilon);
  parameters.timeStep = suggestedTimeStep(parameters.stiffness, cube.mass());
  timeStep = parameters.timeStep;
  parameters.contactModel = ContactModel::volume;
  World world(parameters);
  world.addShape(cube);
  world.addObstacle(primitives::box({2.0, 0.1, 0.01}, {0.0, 0.0, -0.005}));
  ParticleState state;
  state.position = {-0.9, 0.0, 0.005};  // resting on the floor, corners on its top face
  world.addParticle(0, state);
  world.run(settling);
  const double start = world.particles()[0].position.x;
  world.run(steps);
  return world.particles()[0].position.x - start;
}

TEST(DemVolumeLaw, FrictionHoldsBelowTheCoulombLimitAndLetsGoAbove) {
  // tan 15° = 0.27: μ = 0.5 holds the cube (once its tangential spring has settled), μ = 0.1
  // lets it slide at a = g·(sin 15° − 0.1·cos 15°) from the start.
  const std::size_t settling = 6000, steps = 2000;
  double dt = 0.0;
  const double held = slideOnAnIncline(0.5, settling, steps, dt);
  const double slid = slideOnAnIncline(0.1, settling, steps, dt);
  const double slope = 15.0 * std::numbers::pi / 180.0;
  const double a = 9.81 * (std::sin(slope) - 0.1 * std::cos(slope));
  const double before = static_cast<double>(settling) * dt,
               during = static_cast<double>(steps) * dt;
  const double expected = a * before * during + 0.5 * a * during * during;
  std::printf("incline: %.3g m held (mu 0.5), %.4g m slid (mu 0.1; Coulomb: %.4g m)\n", held, slid,
              expected);
  EXPECT_LT(std::fabs(held), 1e-6);
  EXPECT_NEAR(slid, expected, 0.01 * expected);
}

TEST(DemVolumeLaw, WorldsRefuseWhatTheLawCannotUse) {
  Parameters parameters = twoParticles(0.5).world.parameters();
  parameters.contactModel = ContactModel::volume;
  World world(parameters);
  const auto errorOf = [](const auto& action) -> std::string {
    try {
      action();
    } catch (const Error& error) {
      return error.what();
    }
    return "";
  };
  EXPECT_NE(errorOf([&] { world.addObstacle(primitives::quad(1.0, 1.0)); }).find("closed"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { world.addObstacle(openBox(1.0, 1.0, 1.0)); }).find("volume"),
            std::string::npos);
  EXPECT_NE(errorOf([&] { world.addShape(ParticleShape::sphere(0.01, kDensity)); }).find("sphere"),
            std::string::npos);
  // A box with a second box of the same orientation inside it: closed, crossing nowhere, and
  // bounding no solid (its inner part is misoriented).
  const Mesh outer = primitives::box({1, 1, 1}), inner = primitives::box({0.5, 0.5, 0.5});
  std::vector<Vec3> vertices(outer.vertices().begin(), outer.vertices().end());
  vertices.insert(vertices.end(), inner.vertices().begin(), inner.vertices().end());
  std::vector<TriangleIndices> triangles(outer.triangles().begin(), outer.triangles().end());
  const auto offset = static_cast<std::uint32_t>(outer.vertexCount());
  for (const TriangleIndices& t : inner.triangles())
    triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
  const Mesh shells(vertices, triangles);
  EXPECT_NE(errorOf([&] { world.addObstacle(shells); }).find("oriented against"),
            std::string::npos);
  EXPECT_EQ(world.obstacles().size(), 0u);
  EXPECT_EQ(world.shapes().size(), 0u);
  for (const Mesh& wall : openBoxWalls(1.0, 1.0, 1.0, 0.0, 0.1))
    EXPECT_NO_THROW(world.addObstacle(wall));
  for (const Mesh& wall : funnelWalls(0.045, 0.2, 0.1, 0.3, 48, 0.01))
    EXPECT_NO_THROW(world.addObstacle(wall));
  EXPECT_EQ(world.obstacles().size(), 5u + 48u);
  EXPECT_NO_THROW(world.addShape(primitives::granulate(1, {0.01, 0.01, 0.01}), kDensity));
  EXPECT_EQ(contactModelNamed("volume"), ContactModel::volume);
  EXPECT_STREQ(contactModelName(ContactModel::point), "point");
  EXPECT_THROW(contactModelNamed("points"), Error);
  for (const ContactModel model : {ContactModel::point, ContactModel::volume})
    EXPECT_EQ(parseContactModel(contactModelName(model)), model);
  EXPECT_FALSE(parseContactModel("Volume"));
  EXPECT_FALSE(parseContactModel(""));
}

TEST(DemVolumeLaw, TheScenariosSolidWallsAreClosedConvexPiecesBehindTheOpenOnes) {
  // A probe cube pushed into each piece's inner face from inside the container overlaps it with
  // a positive volume (the pieces are outward-oriented), and a convex body's overlap with a
  // convex piece is one region.
  const std::vector<Mesh> box = openBoxWalls(0.2, 0.1, 0.1, 0.0, 0.01);
  ASSERT_EQ(box.size(), 5u);
  const std::vector<Mesh> cone = funnelWalls(0.045, 0.2, 0.1, 0.3, 48, 0.01);
  ASSERT_EQ(cone.size(), 48u);
  std::size_t probed = 0;
  for (const std::vector<Mesh>* pieces : {&box, &cone})
    for (const Mesh& piece : *pieces) {
      const QueryMesh wall(piece);
      EXPECT_TRUE(wall.closed());
      EXPECT_EQ(piece.triangleCount(), 12u);
      // Where the open obstacle's face is: the piece's inner face, probed from the middle.
      const bool isFunnel = pieces == &cone;
      const Vec3 centre = (wall.bounds().lower + wall.bounds().upper) * 0.5;
      const Vec3 inward =
          isFunnel                      ? normalized(Vec3{-centre.x, -centre.y, 0.0})
          : std::fabs(centre.x) > 0.099 ? Vec3{-centre.x / std::fabs(centre.x), 0, 0}
          : std::fabs(centre.y) > 0.049 ? Vec3{0, -centre.y / std::fabs(centre.y), 0}
                                        : Vec3{0, 0, 1};
      QueryMesh probe(gridCube(1, 0.004));
      // Start well inside the container, then sink the probe 1 mm into the piece.
      Vec3 at = centre + inward * 0.02;
      for (int s = 0; s < 400 && !contactdetection::overlap(probe.setPose({Quaternion{}, at}), wall,
                                                            OverlapOptions{false})
                                      .any();
           ++s)
        at = at - inward * 0.0001;
      at = at - inward * 0.001;
      probe.setPose({Quaternion{}, at});
      const Overlap overlap = contactdetection::overlap(probe, wall, OverlapOptions{false});
      ASSERT_EQ(overlap.regions.size(), 1u);
      EXPECT_GT(overlap.regions[0].volume, 0.0);
      EXPECT_GT(dot(overlap.regions[0].areaVector, -inward), 0.0);  // pushes the probe back in
      ++probed;
    }
  EXPECT_EQ(probed, 53u);
  // The point law's obstacles are as they were.
  EXPECT_EQ(openBox(1.0, 1.0, 1.0).triangleCount(), 10u);
  EXPECT_EQ(funnel(0.045, 0.2, 0.1, 0.3).triangleCount(), 2u * 48u * 12u);
  EXPECT_THROW(openBoxWalls(1.0, 1.0, 1.0, 0.0, 0.0), Error);
  EXPECT_THROW(funnelWalls(0.045, 0.2, 0.3, 0.1, 48, 0.01), Error);
}

TEST(DemVolumeLaw, SettleAndHopperRunWithTheVolumeLaw) {
  Scenario settled = settle(8, 5, ParticleKind::Mesh, ContactModel::volume);
  settled.world.run(1500);  // until the first particles land (8 are quick to step in any build)
  EXPECT_GT(settled.world.contacts().size(), 0u);
  for (const Particle& particle : settled.world.particles())
    EXPECT_GT(particle.position.z, 0.0);  // on the floor, not through it
  EXPECT_EQ(settled.world.obstacles().size(), 5u);
  Scenario hopperRun = hopper(40, 2, ParticleKind::Mesh, ContactModel::volume);
  EXPECT_EQ(hopperRun.world.obstacles().size(), 49u);
  hopperRun.world.run(50);
  EXPECT_THROW(settle(8, 5, ParticleKind::Sphere, ContactModel::volume), Error);
}

}  // namespace
}  // namespace delta::dem
