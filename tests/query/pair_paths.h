#pragma once

// The paths the mesh-pair cache tests (contact_cache_test.cpp, overlap_cache_test.cpp) walk: a
// pair of meshes, the second moved against the first by small steps (a cache answers most
// calls) and by jumps (it must be made anew), on random and adversarial pairs: granulates,
// icospheres, a box face on a box face (coplanar, touching), a cylinder on or in a box a million
// units from the origin, a tiny pair.

#include <cstddef>
#include <random>
#include <vector>

#include "delta/core/rotation.h"
#include "delta/mesh/mesh.h"
#include "delta/mesh/primitives.h"
#include "delta/query/query_mesh.h"

namespace delta::test {

struct PairScene {
  const char* name;
  Mesh first, second;
  double epsilon;  ///< the scene's ε (the caches' skin is half of it)
  double step;     ///< the path's step, against the scene's size
};

/// The scenes, the pairs near one another (`interpenetrating` false: the contact query's, at
/// most touching) or sunk into each other (true: the overlap query's).
inline std::vector<PairScene> pairScenes(bool interpenetrating) {
  std::vector<PairScene> all;
  const double sink = interpenetrating ? 1.0 : 0.0;
  Mesh a = primitives::granulate(3);
  Mesh b = primitives::granulate(4);
  b.translate({1.75 - 0.15 * sink, 0.1, 0.0});
  all.push_back({"granulates", a, b, 0.05, 0.004});
  Mesh c = primitives::icosphere(3);
  Mesh d = primitives::icosphere(3);
  d.rotate({1, 0, 0}, 0.3).translate({1.8, 0.3, 0});
  all.push_back({"icospheres", c, d, 0.01, 0.002});
  all.push_back({"box face on box face", primitives::box({1, 1, 1}),
                 primitives::box({1, 1, 1}, {0.2, 0.1, 1.0}), 0.01, 0.001});
  all.push_back({"cylinder on a box far from the origin", primitives::box({2, 2, 0.5}, {1e6, 0, 0}),
                 primitives::cylinder(0.5, 1, 24, {1e6 + 0.3, 0.2, 0.751 - 0.011 * sink}), 0.002,
                 2e-4});
  Mesh e = primitives::granulate(5, {1e-6, 1e-6, 1e-6});
  Mesh f = primitives::granulate(6, {1e-6, 1e-6, 1e-6});
  f.translate({1.8e-6 - 0.2e-6 * sink, 0.0, 0.0});
  all.push_back({"tiny granulates", e, f, 5e-8, 4e-9});
  return all;
}

/// Walks `scene`'s path of `steps` steps, calling `visit(s, a, b)` with both meshes placed at
/// step s: each step a drift and a turn of about the scene's step (the second turned about its
/// centre, so that it rolls on or in the first), with a jump every 37 steps (40 steps at once)
/// that no skin covers; the first drifted half as far when `moveFirst`.
template <class Visit>
void walkPath(const PairScene& scene, bool moveFirst, int steps, const Visit& visit) {
  const QueryMesh first(scene.first), second(scene.second);
  std::mt19937_64 random(7);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1p-53 - 0.5; };
  RigidTransform secondPose, firstPose;
  for (int s = 0; s < steps; ++s) {
    const double jump = s % 37 == 36 ? 40.0 : 1.0;
    const Vec3 axis{0.3 + uniform(), 0.5, 1.0};
    const RigidTransform step{Quaternion::fromAxisAngle(axis, 0.5 * scene.step),
                              Vec3{uniform(), uniform(), uniform()} * (jump * scene.step)};
    const Vec3 centre = secondPose.apply(scene.second.bounds().center());
    secondPose = RigidTransform::translationBy(step.translation) *
                 RigidTransform::rotationAbout(step.rotation, centre) * secondPose;
    if (moveFirst) firstPose = RigidTransform::translationBy(step.translation * 0.5) * firstPose;
    QueryMesh a = first, b = second;
    a.setPose(firstPose);
    b.setPose(secondPose);
    visit(s, a, b);
  }
}

}  // namespace delta::test
