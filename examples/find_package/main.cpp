// Builds two granulate particles, moves them, and asks Δ where they touch and how far two points
// are from the first: the README's "Using the library" lines, compiled against an installed Δ.
#include <cstdio>
#include <vector>

#include "delta/delta.h"

int main() {
  delta::Mesh particle = delta::primitives::granulate(/*seed=*/42);
  particle.rotate({0, 0, 1}, 0.5).translate({1, 2, 3});
  const delta::TriangleSoA flat = delta::flatten(particle);
  const delta::MassProperties mass = delta::massProperties(particle, /*density=*/2500.0);

  namespace cd = delta::contactdetection;
  delta::QueryMesh a(particle), b(delta::primitives::granulate(8).translate({2.8, 2, 3}));
  const std::vector<delta::ContactPoint> touching = cd::contacts(a, b, 0.01);
  const std::vector<delta::Vec3> points = {{1, 2, 3}, {5, 5, 5}};
  const std::vector<cd::PointDistance> d = cd::distances(a, points, {.signedDistance = true});

  std::printf("delta %s (%s): %zu triangles flattened into %zu lanes, volume %.6f, mass %.3f\n",
              delta::version(), delta::gitCommit(), flat.size(), flat.paddedSize(), mass.volume,
              mass.mass);
  std::printf("%zu contact points; the centre is %.3f inside, (5, 5, 5) %.3f outside\n",
              touching.size(), d[0].distance, d[1].distance);
  // The particles are 0.017 apart, closer than 2ε: they touch without overlapping.
  const bool touch = !touching.empty() && !touching.front().overlap;
  const bool sane = flat.size() == particle.triangleCount() && mass.volume > 0.0 && touch &&
                    d[0].inside && !d[1].inside;
  return sane ? 0 : 1;
}
