// World parameters by the built-in scenarios' rules, for DEM tests that build their own worlds.
#pragma once

#include "delta/core/vec3.h"
#include "delta/dem/contact_model.h"
#include "delta/dem/world.h"

namespace delta::dem::test {

/// Particles of radius about r = 1 cm (scenarios.h): ε = r/20, h = r/4, the stiffness that stops
/// a body of `mass` arriving at `speed` within the shell, and the suggested time step.
inline Parameters centimetreParameters(double mass, double speed, double restitution,
                                       double friction, const Vec3& gravity) {
  constexpr double kRadius = 0.01;
  Parameters parameters;
  parameters.epsilon = kRadius / 20.0;
  parameters.filterDistance = kRadius / 4.0;
  parameters.restitution = restitution;
  parameters.friction = friction;
  parameters.gravity = gravity;
  parameters.stiffness = stiffnessForImpact(mass, speed, parameters.epsilon);
  parameters.timeStep = suggestedTimeStep(parameters.stiffness, mass);
  return parameters;
}

}  // namespace delta::dem::test
