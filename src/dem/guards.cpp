// World's guard against bodies passing through each other within one step (world.h, "No
// pass-through"): the rule and its message, apart from the stepping it guards.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/core/error.h"
#include "delta/core/format.h"
#include "delta/core/parallel.h"
#include "delta/core/rotation.h"
#include "delta/dem/world.h"

namespace delta::dem {
namespace {

/// Particles per parallel chunk: a bound costs about as much as a half kick.
constexpr std::size_t kParticleGrain = 128;

/// The farthest a point of `box` lies from `pivot`: the farthest corner (a box is convex).
double reachFrom(const Aabb& box, const Vec3& pivot) noexcept {
  double farthest = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 x = box.corner(corner);
    farthest = std::max(farthest, length(x - pivot));
  }
  return farthest;
}

/// The exponent of the power of two that brings `largest` (finite, positive) near 1: a scaling
/// (by ldexp, which also takes subnormal values up) that rounds nothing, so that squares of finite
/// values beyond 1e154 do not overflow.
int unitExponent(double largest) noexcept {
  return -std::ilogb(largest);
}

/// |v|, also where |v|² would overflow (a velocity beyond 1e154 is finite, and must not be
/// taken for one that is not: the guard would leave its particle out); NaN or +∞ for a vector
/// that is not finite.
double magnitude(const Vec3& v) noexcept {
  const double largest = maxAbs(v);
  if (!isFinite(v) || largest == 0.0) return length(v);
  const int exponent = unitExponent(largest);
  return std::ldexp(length(ldexp(v, exponent)), -exponent);
}

/// The least distance from the origin to the segment from `a` to `a + d`, scaled so that no
/// square overflows: the fraction t of the way from `a` and `d` brought near 1 together, the
/// distance by magnitude(). (From +∞ in dot(d, d), t was 0 and the distance |a|: a pass-through
/// unseen. Scaled together, a's squares may underflow against a large d, and its distance is
/// its own.)
double closestApproach(const Vec3& a, const Vec3& d) noexcept {
  const double largest = std::max(maxAbs(a), maxAbs(d));
  if (!(largest > 0.0) || !std::isfinite(largest)) return magnitude(a);
  const int exponent = unitExponent(largest);
  const Vec3 as = ldexp(a, exponent), ds = ldexp(d, exponent);
  const double dd = dot(ds, ds);
  const double t = dd > 0.0 ? std::clamp(-dot(as, ds) / dd, 0.0, 1.0) : 0.0;
  return magnitude(a + d * t);
}

/// The obstacles' boxes where they are, and how fast their farthest points move (0 at rest).
struct ObstacleMotions {
  std::vector<Aabb> box;
  std::vector<double> speed;
  double fastest = 0.0;
};

ObstacleMotions obstacleMotions(const std::vector<Obstacle>& obstacles) {
  ObstacleMotions motions{std::vector<Aabb>(obstacles.size()),
                          std::vector<double>(obstacles.size(), 0.0)};
  for (std::size_t o = 0; o < obstacles.size(); ++o) {
    const Obstacle& wall = obstacles[o];
    const ObstacleMotion& motion = wall.motion;
    motions.box[o] = movedBox(wall.queryMesh.bounds(), wall.pose);
    if (motion.velocity == Vec3{} && motion.angularVelocity == Vec3{}) continue;
    motions.speed[o] =
        length(motion.velocity) +
        length(motion.angularVelocity) * reachFrom(motions.box[o], wall.pose.apply(motion.pivot));
    motions.fastest = std::max(motions.fastest, motions.speed[o]);
  }
  return motions;
}

/// The fastest two bodies could approach: the two fastest particles' speeds summed, or the
/// fastest particle's and the fastest obstacle's. Speeds that are not finite are left out (the
/// step goes on and requireFiniteParticles names the particle after it).
double fastestPairSpeed(const std::vector<double>& speeds, double fastestObstacle) noexcept {
  double first = 0.0, second = 0.0;
  for (const double speed : speeds) {
    if (!std::isfinite(speed)) continue;
    if (speed > first) {
      second = first;
      first = speed;
    } else if (speed > second) {
      second = speed;
    }
  }
  return first + std::max(second, fastestObstacle);
}

}  // namespace

void World::requireCatchableMotion() const {
  const double dt = parameters_.timeStep, half = 0.5 * dt;
  const double shell = 2.0 * law_.epsilon;
  // Each particle's motion in the coming step, with the velocities the half kick will give it
  // (computed as halfKick() does: World::step in world.h), and how far its surface may move
  // about its centre by turning (|ω|·r·dt).
  struct Motion {
    Vec3 velocity;
    double angular;  ///< |ω|
  };
  const auto motionOf = [&](std::size_t i) {
    const Particle& particle = particles_[i];
    const ParticleShape& shape = shapes_[particle.shape];
    return Motion{particle.velocity + (particle.force / shape.mass() + parameters_.gravity) * half,
                  magnitude(angularVelocityOf(particle, particle.orientation,
                                              particle.angularMomentum + particle.torque * half))};
  };
  const auto radius = [&](std::size_t i) { return shapes_[particles_[i].shape].boundingRadius(); };
  // 1. Each particle's speed bound, |v| + |ω|·r.
  std::vector<double> speeds(owned_);
  parallelFor(0, owned_, kParticleGrain, [&](std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      const Motion motion = motionOf(i);
      speeds[i] = magnitude(motion.velocity) + motion.angular * radius(i);
    }
  });
  // 2. Each obstacle's box and speed.
  const ObstacleMotions obstacles = obstacleMotions(obstacles_);
  // 3. The cheap bound: no two bodies can approach by 2ε.
  if (fastestPairSpeed(speeds, obstacles.fastest) * dt < shell) return;
  // 4. Some two could: the pairs that could, where one moves by ε or more. A pair is unsafe when
  // its bounding spheres (grown by their turning and the shell) can meet along the straight
  // drift of their centres, or a particle's swept box can meet an obstacle's box (grown by the
  // obstacle's motion), and their motions sum to 2ε or more.
  std::vector<Vec3> drift(owned_);
  std::vector<double> turn(owned_);
  for (std::size_t i = 0; i < owned_; ++i) {
    const Motion motion = motionOf(i);
    drift[i] = motion.velocity * dt;
    turn[i] = motion.angular * radius(i) * dt;
  }
  const auto fail = [&](std::size_t i, const std::string& other, double otherSpeed) {
    const Particle& particle = particles_[i];
    const double safe = shell / (speeds[i] + otherSpeed);
    throw Error("dem: particle " + std::to_string(ids_[i]) + " (speed " +
                toString(magnitude(particle.velocity)) + ", angular speed " +
                toString(magnitude(particle.angularVelocity)) + ") would move " +
                toString(speeds[i] * dt) + " in step " + std::to_string(stepCount_ + 1) +
                " within reach of " + other + ": together they could approach by " +
                toString((speeds[i] + otherSpeed) * dt) +
                ", more than the contact shell 2ε = " + toString(shell) +
                " catches, and pass through each other unseen; the largest safe time step is "
                "about " +
                toString(safe) + " (now " + toString(dt) + ")");
  };
  const double epsilon = law_.epsilon;
  for (std::size_t i = 0; i < owned_; ++i) {
    const double mi = speeds[i] * dt;
    if (!std::isfinite(mi)) continue;
    const Vec3& a = particles_[i].position;
    for (std::size_t j = 0; j < owned_; ++j) {
      const double mj = speeds[j] * dt;
      if (j == i || !std::isfinite(mj) || std::max(mi, mj) < epsilon || mi + mj < shell) continue;
      if (mj > mi || (mj == mi && j < i)) continue;  // each pair once, from its faster body
      const double reach = radius(i) + radius(j) + turn[i] + turn[j] + shell;
      if (closestApproach(particles_[j].position - a, drift[j] - drift[i]) <= reach)
        fail(i, "particle " + std::to_string(ids_[j]), speeds[j]);
    }
    for (std::size_t o = 0; o < obstacles_.size(); ++o) {
      const double mo = obstacles.speed[o] * dt;
      if (std::max(mi, mo) < epsilon || mi + mo < shell) continue;
      Aabb swept;
      swept.extend(a);
      swept.extend(a + drift[i]);
      const double grow = radius(i) + turn[i] + shell + mo;
      if (distanceSquared(swept, obstacles.box[o]) <= grow * grow)
        fail(i, "obstacle " + std::to_string(o), obstacles.speed[o]);
    }
  }
}

}  // namespace delta::dem
