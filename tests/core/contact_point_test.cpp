#include "delta/core/contact_point.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "delta/kernels/pair_results.h"
#include "delta/kernels/penalty.h"
#include "delta/mesh/primitives.h"
#include "delta/mesh/triangle_soa.h"
#include "delta/query/contacts.h"
#include "delta/query/query_mesh.h"

namespace delta {
namespace {

/// Two spheres pushed into each other: crossing pairs, some of which the penalty solver does not
/// certify.
struct CrossingSpheres {
  Mesh a = primitives::icosphere(2);
  Mesh b = moved(primitives::icosphere(2));
  static Mesh moved(Mesh mesh) {
    mesh.translate({1.0, 0.1, 0.0});
    return mesh;
  }
};

TEST(ContactPoint, ConvergedIsThePenaltySolversFlagPairByPair) {
  const CrossingSpheres scene;
  const std::vector<ContactPoint> found = contactdetection::contacts(
      QueryMesh(scene.a), QueryMesh(scene.b), 0.05, kernels::Solver::Penalty);
  ASSERT_FALSE(found.empty());
  const TriangleSoA a(scene.a), b(scene.b);
  kernels::PairResults results(1);
  std::size_t unconverged = 0;
  for (const ContactPoint& contact : found) {
    kernels::penaltyDistances(a.triangle(contact.first), b, contact.second, contact.second + 1,
                              results);
    ASSERT_EQ(results.size(), 1u);
    EXPECT_EQ(contact.converged, results.converged(0))
        << "pair " << contact.first << ", " << contact.second;
    unconverged += !contact.converged;
  }
  EXPECT_GT(unconverged, 0u) << "the scene shows no unconverged pair";
  EXPECT_LT(unconverged, found.size());
}

TEST(ContactPoint, ExactSolversAndValuesMadeByHandAreConverged) {
  EXPECT_TRUE(ContactPoint{}.converged);
  const CrossingSpheres scene;
  for (const kernels::Solver solver : {kernels::Solver::Hybrid, kernels::Solver::BruteForce}) {
    const std::vector<ContactPoint> found =
        contactdetection::contacts(QueryMesh(scene.a), QueryMesh(scene.b), 0.05, solver);
    ASSERT_FALSE(found.empty());
    EXPECT_TRUE(
        std::all_of(found.begin(), found.end(), [](const ContactPoint& c) { return c.converged; }));
  }
}

}  // namespace
}  // namespace delta
