// The guide's "DEM with triangulated particles" (docs/guide.md): four granulates of about a
// centimetre dropped into an open box, stepped until they come to rest, and their contacts read.
#include <cmath>
#include <cstdio>

#include "delta/delta.h"

int main() try {
  // [guide:begin world]
  namespace dem = delta::dem;
  const double r = 0.01;  // particles of about 1 cm, in SI units
  const dem::ParticleShape rock(delta::primitives::granulate(7, {r, 0.8 * r, 0.7 * r}), 2500.0);

  dem::Parameters parameters;
  parameters.epsilon = r / 20;        // surfaces closer than 2ε are in contact
  parameters.filterDistance = r / 4;  // h: a pair's contact points closer than h merge
  parameters.restitution = 0.5;
  parameters.friction = 0.5;
  parameters.stiffness = dem::stiffnessForImpact(rock.mass(), 1.0, parameters.epsilon);
  parameters.timeStep = dem::suggestedTimeStep(parameters.stiffness, rock.mass());

  dem::World world(parameters);
  const std::size_t shape = world.addShape(rock);     // prepared once, shared by its particles
  world.addObstacle(dem::openBox(0.05, 0.05, 0.03));  // a floor at z = 0 and four walls
  for (int i = 0; i < 4; ++i) {
    dem::ParticleState state;  // at rest unless a velocity is given
    state.position = {0.025 * (i % 2) - 0.0125, 0.025 * (i / 2) - 0.0125, 0.01 + 0.002 * i};
    state.orientation = delta::Quaternion::fromAxisAngle({1, 2, 3}, i);
    world.addParticle(shape, state);
  }
  // [guide:end world]

  // [guide:begin run]
  world.run(3000);  // 3000 steps of 37 µs: 0.11 s
  for (const dem::Contact& contact : world.contacts())
    std::printf("particle %u, %s %u: force (%.3g, %.3g, %.3g) N\n", contact.first,
                contact.withObstacle ? "wall" : "particle", contact.second, contact.force.x,
                contact.force.y, contact.force.z);
  for (const dem::Particle& particle : world.particles())
    std::printf("at (%.4f, %.4f, %.4f) m, moving at %.2g m/s\n", particle.position.x,
                particle.position.y, particle.position.z, delta::length(particle.velocity));
  std::printf("%zu contact points of %zu pairs; %.0f%% of the last step in contact detection\n",
              world.statistics().contactPoints, world.statistics().pairsInContact,
              100 * world.statistics().contactDetectionSeconds / world.statistics().totalSeconds);
  // [guide:end run]

  // They fell into the box and came nearly to rest, on its floor.
  bool onFloor = false;
  for (const dem::Contact& contact : world.contacts())
    onFloor = onFloor || contact.withObstacle;
  for (const dem::Particle& particle : world.particles()) {
    const delta::Vec3 x = particle.position;
    if (!(std::abs(x.x) < 0.025 && std::abs(x.y) < 0.025 && x.z > 0.0 && x.z < 2 * r &&
          delta::length(particle.velocity) < 0.1)) {
      std::fprintf(stderr, "a particle left the box or is still fast\n");
      return 1;
    }
  }
  return onFloor ? 0 : 1;
} catch (const delta::Error& error) {
  std::fprintf(stderr, "dem_particles: %s\n", error.what());
  return 1;
}
