// The hopper's free fall taken in long steps, for the benchmarks that time its flow: until the
// first contact nothing but gravity acts, so velocity Verlet with any step is exact there.
#pragma once

#include <cstddef>

#include "delta/dem/world.h"

namespace delta::bench {

/// One step of `world` with `timeStep`; false (and `world` unchanged) when it would find a contact.
inline bool freeFallStep(dem::World& world, double timeStep) {
  dem::World trial = world;
  trial.setTimeStep(timeStep);
  trial.step();
  if (trial.statistics().rawContactPoints > 0) return false;
  trial.setTimeStep(world.parameters().timeStep);
  world = std::move(trial);
  return true;
}

/// Steps of `stride` times the world's time step until the next would find a contact; returns
/// how many.
inline std::size_t fallFreely(dem::World& world, double stride) {
  const double timeStep = stride * world.parameters().timeStep;
  std::size_t steps = 0;
  while (freeFallStep(world, timeStep))
    ++steps;
  return steps;
}

}  // namespace delta::bench
