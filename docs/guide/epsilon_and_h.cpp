// The guide's "Choosing ε and h" (docs/guide.md): DEM parameters derived from the particles by
// the built-in scenarios' rules, and what filter(h) keeps of one contact.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <vector>

#include "delta/delta.h"

namespace {

// [guide:begin parameters]
// The scenarios' rules: ε and h from the particle size, the stiffness that stops the fastest
// expected impact within ε (half the shell), and a time step of a thirtieth of a contact.
delta::dem::Parameters parametersFor(const delta::dem::ParticleShape& lightest,
                                     double fastestImpact) {
  namespace dem = delta::dem;
  const double r = lightest.boundingRadius();
  dem::Parameters parameters;
  parameters.epsilon = r / 20;
  parameters.filterDistance = r / 4;
  parameters.stiffness = dem::stiffnessForImpact(lightest.mass(), fastestImpact, r / 20);
  parameters.timeStep = dem::suggestedTimeStep(parameters.stiffness, lightest.mass());
  return parameters;
}
// [guide:end parameters]

}  // namespace

int main() try {
  namespace cd = delta::contactdetection;
  const double r = 0.01, speed = 1.0;
  const delta::dem::ParticleShape rock(delta::primitives::granulate(3, {r, r, r}), 2500.0);
  const delta::dem::Parameters p = parametersFor(rock, speed);
  std::printf("ε = %g m, h = %g m, k = %g N/m, dt = %g s\n", p.epsilon, p.filterDistance,
              p.stiffness, p.timeStep);

  // dt = π/(30√2)·ε/v: a particle at the impact speed moves 0.074 ε a step, and a contact
  // lasts about thirty steps.
  const double travel = speed * p.timeStep / p.epsilon;
  const double steps = delta::dem::contactDuration(p.stiffness, rock.mass() / 2) / p.timeStep;
  if (std::abs(travel - std::numbers::pi / (30 * std::sqrt(2.0))) > 1e-12 ||
      std::abs(steps - 30) > 1e-9) {
    std::fprintf(stderr, "travel %g ε a step, %g steps a contact\n", travel, steps);
    return 1;
  }

  // Two particles ε apart (moved along the line of their closest points): every triangle pair
  // closer than 2ε is a contact point.
  const delta::QueryMesh a = rock.queryMesh();
  delta::QueryMesh b = a;
  b.transform(delta::RigidTransform{delta::Quaternion::fromAxisAngle({0, 0, 1}, 3.1), {}});
  b.transform(delta::RigidTransform::translationBy({2 * r, 0, 0}));
  const cd::MinimumDistance gap = cd::minimumDistance(a, b);
  const delta::Vec3 towardA = delta::normalized(gap.p - gap.q);
  b.transform(delta::RigidTransform::translationBy(towardA * (gap.distance - p.epsilon)));

  // [guide:begin filter]
  const std::vector<delta::ContactPoint> raw = cd::contacts(a, b, p.epsilon);
  for (const double h : {r / 40, r / 4, 2 * r})
    std::printf("h = %.2g r: %zu of %zu contact points kept\n", h / r, cd::filter(raw, h).size(),
                raw.size());
  // [guide:end filter]

  // filter(h) keeps the deepest point, and fewer points as h grows.
  std::size_t previous = raw.size() + 1;
  for (const double h : {r / 40, r / 4, 2 * r}) {
    const std::vector<delta::ContactPoint> kept = cd::filter(raw, h);
    double deepestRaw = 2 * p.epsilon, deepestKept = 2 * p.epsilon;
    for (const delta::ContactPoint& point : raw)
      deepestRaw = std::min(deepestRaw, point.distance);
    for (const delta::ContactPoint& point : kept)
      deepestKept = std::min(deepestKept, point.distance);
    if (raw.empty() || kept.size() > previous || deepestKept != deepestRaw) {
      std::fprintf(stderr, "filter(%g): %zu points kept\n", h, kept.size());
      return 1;
    }
    previous = kept.size();
  }

  // The table of the guide: for gaps of ε (mid-shell), the triangle pairs closer than 2ε and the
  // points filter(h) keeps, over 20 pairs of granulates of 80 triangles (radius 1).
  std::printf("ε/r    triangle pairs    after filter(r/16)    filter(r/4)    filter(r)\n");
  for (const double fraction : {0.01, 0.025, 0.05, 0.1, 0.2}) {
    double pairs = 0, fine = 0, scenario = 0, coarse = 0;
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      const delta::QueryMesh first(delta::primitives::granulate(seed));
      delta::QueryMesh second(delta::primitives::granulate(seed + 100));
      second.transform(delta::RigidTransform::translationBy({2.5, 0, 0}));
      const cd::MinimumDistance apart = cd::minimumDistance(first, second);
      second.transform(delta::RigidTransform::translationBy(delta::normalized(apart.p - apart.q) *
                                                            (apart.distance - fraction)));
      const std::vector<delta::ContactPoint> found = cd::contacts(first, second, fraction);
      pairs += static_cast<double>(found.size()) / 20;
      fine += static_cast<double>(cd::filter(found, 1.0 / 16).size()) / 20;
      scenario += static_cast<double>(cd::filter(found, 1.0 / 4).size()) / 20;
      coarse += static_cast<double>(cd::filter(found, 1.0).size()) / 20;
    }
    std::printf("%-6g %-17.1f %-21.1f %-14.1f %.1f\n", fraction, pairs, fine, scenario, coarse);
  }
  return 0;
} catch (const delta::Error& error) {
  std::fprintf(stderr, "epsilon_and_h: %s\n", error.what());
  return 1;
}
