// World parameters by the built-in scenarios' rules, and a closed system of converging
// particles, for DEM tests that build their own worlds.
#pragma once

#include <cstddef>
#include <cstdint>
#include <random>
#include <span>

#include "delta/core/rotation.h"
#include "delta/core/vec3.h"
#include "delta/dem/contact_model.h"
#include "delta/dem/world.h"

namespace delta::test {

/// Particles of radius about r = 1 cm (scenarios.h): ε = r/20, h = r/4, the stiffness that stops
/// a body of `mass` arriving at `speed` within the shell, and the suggested time step.
inline dem::Parameters centimetreParameters(double mass, double speed, double restitution,
                                            double friction, const Vec3& gravity) {
  constexpr double kRadius = 0.01;
  dem::Parameters parameters;
  parameters.epsilon = kRadius / 20.0;
  parameters.filterDistance = kRadius / 4.0;
  parameters.restitution = restitution;
  parameters.friction = friction;
  parameters.gravity = gravity;
  parameters.stiffness = dem::stiffnessForImpact(mass, speed, parameters.epsilon);
  parameters.timeStep = dem::suggestedTimeStep(parameters.stiffness, mass);
  return parameters;
}

/// A closed system for the conservation tests: six particles of radius about r = 1 cm flying at
/// each other from ±x, ±y, ±z (2.6 r out, off-centre), spinning, drawn from `seed`; particle i
/// has shape shapes[i].
inline void addConvergingParticles(dem::World& world, std::uint64_t seed,
                                   std::span<const std::uint32_t, 6> shapes) {
  constexpr double kRadius = 0.01;
  std::mt19937_64 random(seed);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53 - 0.5; };
  const Vec3 directions[] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  for (std::size_t i = 0; i < 6; ++i) {
    dem::ParticleState state;
    const Vec3 offset{uniform() * kRadius, uniform() * kRadius, uniform() * kRadius};
    state.position = directions[i] * (2.6 * kRadius) + offset * 0.6;
    state.velocity = directions[i] * -0.5 + Vec3{uniform(), uniform(), uniform()} * 0.1;
    state.orientation = Quaternion::fromAxisAngle({uniform(), uniform(), 1.0}, 6.0 * uniform());
    state.angularVelocity = Vec3{uniform(), uniform(), uniform()} * 20.0;
    world.addParticle(shapes[i], state);
  }
}

}  // namespace delta::test
