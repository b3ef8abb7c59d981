// Builds a granulate particle, moves it, flattens it, and prints what Δ measures.
#include <cstdio>

#include "delta/delta.h"

int main() {
  delta::Mesh particle = delta::primitives::granulate(/*seed=*/42);
  particle.rotate({0, 0, 1}, 0.5).translate({1, 2, 3});
  const delta::TriangleSoA flat = delta::flatten(particle);
  const delta::MassProperties mass = delta::massProperties(particle, /*density=*/2500.0);
  std::printf("delta %s (%s): %zu triangles flattened into %zu lanes, volume %.6f, mass %.3f\n",
              delta::version(), delta::gitCommit(), flat.size(), flat.paddedSize(), mass.volume,
              mass.mass);
  return flat.size() == particle.triangleCount() && mass.volume > 0.0 ? 0 : 1;
}
