// contacts(first, second, ε, cache) against contacts(first, second, ε): the same contacts, bit
// for bit, at every pose of a pair moved along a path, whether the cache answered or was made
// anew, and with the inside test left for later (markInside). The paths move the second mesh
// against the first by small steps (the cache answers most calls) and by jumps (it must be made
// anew), both meshes moved or only one, on the scenes of pair_paths.h: granulates, icospheres, a
// box face on a box face (coplanar, touching), a cylinder resting on a box a million units from
// the origin, a tiny pair. ContactBatch: the same, every path's pair in one kernel batch.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <utility>
#include <vector>

#include "delta/core/error.h"
#include "delta/core/rotation.h"
#include "delta/mesh/primitives.h"
#include "delta/query/contacts.h"
#include "delta/query/query_mesh.h"

#include "pair_paths.h"

namespace delta::contactdetection {
namespace {

bool sameContacts(const std::vector<ContactPoint>& a, const std::vector<ContactPoint>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const ContactPoint &x = a[i], &y = b[i];
    const bool same = std::memcmp(&x.x, &y.x, sizeof(Vec3)) == 0 &&
                      std::memcmp(&x.normal, &y.normal, sizeof(Vec3)) == 0 &&
                      std::memcmp(&x.direction, &y.direction, sizeof(Vec3)) == 0 &&
                      std::memcmp(&x.distance, &y.distance, sizeof(double)) == 0 &&
                      x.overlap == y.overlap && x.converged == y.converged && x.first == y.first &&
                      x.second == y.second;
    if (!same) return false;
  }
  return true;
}

TEST(ContactCache, SameContactsAsAFreshQueryAlongAPath) {
  std::size_t insideMarks = 0;  // contacts marked by the inside test alone
  for (const test::PairScene& scene : test::pairScenes(false)) {
    SCOPED_TRACE(scene.name);
    for (const bool moveFirst : {false, true}) {
      ContactCache cache(0.5 * scene.epsilon), laterCache(0.5 * scene.epsilon);
      std::size_t withContacts = 0;
      test::walkPath(scene, moveFirst, 150, [&](int s, const QueryMesh& a, const QueryMesh& b) {
        const std::vector<ContactPoint> fresh = contacts(a, b, scene.epsilon);
        const std::vector<ContactPoint> cached = contacts(a, b, scene.epsilon, cache);
        ASSERT_TRUE(sameContacts(cached, fresh))
            << "step " << s << ": " << cached.size() << " against " << fresh.size();
        // The inside test left for later, then made on every contact: the same marks.
        std::vector<ContactPoint> later =
            contacts(a, b, scene.epsilon, laterCache, kernels::Solver::Hybrid, InsideTest::later);
        for (std::size_t i = 0; i < std::min(later.size(), fresh.size()); ++i)
          insideMarks += fresh[i].overlap && !later[i].overlap ? 1 : 0;
        markInside(a, b, scene.epsilon, later);
        ASSERT_TRUE(sameContacts(later, fresh)) << "step " << s << ", the inside test later";
        withContacts += fresh.empty() ? 0 : 1;
      });
      // Both ways of answering were taken, on a path that touched most of the time.
      EXPECT_GT(cache.reused(), 75u);
      EXPECT_GT(cache.made(), 4u);
      EXPECT_GT(withContacts, 75u);
    }
  }
  EXPECT_GT(insideMarks, 100u);
}

TEST(ContactCache, OtherMeshesEpsilonOrSolverMakeItAnew) {
  const QueryMesh a(primitives::granulate(3));
  QueryMesh b(primitives::granulate(4));
  b.setPose(RigidTransform::translationBy({1.7, 0.1, 0.0}));
  QueryMesh c(primitives::icosphere(2));
  c.setPose(RigidTransform::translationBy({1.9, 0.0, 0.0}));
  ContactCache cache(0.02);
  EXPECT_TRUE(sameContacts(contacts(a, b, 0.05, cache), contacts(a, b, 0.05)));
  EXPECT_TRUE(sameContacts(contacts(a, b, 0.05, cache), contacts(a, b, 0.05)));
  EXPECT_EQ(cache.made(), 1u);
  EXPECT_EQ(cache.reused(), 1u);
  EXPECT_TRUE(sameContacts(contacts(a, c, 0.05, cache), contacts(a, c, 0.05)));  // another mesh
  EXPECT_TRUE(sameContacts(contacts(c, b, 0.05, cache), contacts(c, b, 0.05)));  // swapped roles
  EXPECT_TRUE(sameContacts(contacts(c, b, 0.1, cache), contacts(c, b, 0.1)));    // another ε
  EXPECT_TRUE(sameContacts(contacts(c, b, 0.1, cache, kernels::Solver::BruteForce),
                           contacts(c, b, 0.1, kernels::Solver::BruteForce)));
  EXPECT_EQ(cache.made(), 5u);
  cache.clear();
  EXPECT_TRUE(sameContacts(contacts(c, b, 0.1, cache), contacts(c, b, 0.1)));
  EXPECT_EQ(cache.made(), 6u);
}

TEST(ContactCache, NoSkinAskedIsAFreshQueryEachCall) {
  const QueryMesh a(primitives::granulate(3));
  QueryMesh b(primitives::granulate(4));
  b.setPose(RigidTransform::translationBy({1.7, 0.1, 0.0}));
  for (const double skin : {0.0, -1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    ContactCache cache(skin);
    for (int call = 0; call < 3; ++call)
      EXPECT_TRUE(sameContacts(contacts(a, b, 0.05, cache), contacts(a, b, 0.05)));
    EXPECT_EQ(cache.reused(), 0u) << skin;
    EXPECT_EQ(cache.size(), 0u) << skin;
  }
}

TEST(ContactCache, BadInputThrowsAsTheQueryDoes) {
  const QueryMesh a(primitives::granulate(3)), b(primitives::granulate(4));
  ContactCache cache(0.01);
  for (const double epsilon : {0.0, -1.0, std::nan("")})
    EXPECT_THROW(contacts(a, b, epsilon, cache), Error) << epsilon;
  EXPECT_EQ(cache.made(), 0u);
}

// Every scene's paths (both meshes moved or one) at once, a batch a step: each pair's contacts
// are its fresh query's, bit for bit, whichever pairs share the kernels' batch with it.
// A path of a pair of meshes: its ε, the inside test asked, and the poses, a step each.
struct Path {
  double epsilon;
  InsideTest inside;
  std::vector<std::pair<QueryMesh, QueryMesh>> poses;
};

// Every scene's paths (both meshes moved or one), `steps` long.
std::vector<Path> everyScenesPaths(int steps) {
  std::vector<Path> paths;
  for (const test::PairScene& scene : test::pairScenes(false))
    for (const bool moveFirst : {false, true}) {
      Path& path = paths.emplace_back(
          Path{scene.epsilon, moveFirst ? InsideTest::later : InsideTest::now, {}});
      test::walkPath(scene, moveFirst, steps, [&](int, const QueryMesh& a, const QueryMesh& b) {
        path.poses.emplace_back(a, b);
      });
    }
  return paths;
}

// All the paths at once, a batch a step: each pair's contacts are its fresh query's, bit for
// bit, whichever pairs share the kernels' batch with it.
void expectFreshContactsInBatches(kernels::Solver solver, int steps) {
  SCOPED_TRACE(kernels::name(solver));
  const std::vector<Path> paths = everyScenesPaths(steps);
  std::vector<ContactCache> caches;
  for (const Path& path : paths)
    caches.emplace_back(0.5 * path.epsilon);
  ContactBatch batch(solver);
  std::size_t gathered = 0, withContacts = 0;
  for (int s = 0; s < steps; ++s) {
    batch.clear();
    std::vector<std::size_t> index;
    for (std::size_t k = 0; k < paths.size(); ++k) {
      const auto& [a, b] = paths[k].poses[static_cast<std::size_t>(s)];
      const std::size_t reusedBefore = caches[k].reused();
      index.push_back(batch.add(a, b, paths[k].epsilon, caches[k], paths[k].inside));
      gathered += caches[k].reused() - reusedBefore;
    }
    ASSERT_EQ(batch.size(), paths.size());
    batch.run();
    for (std::size_t k = 0; k < paths.size(); ++k) {
      const auto& [a, b] = paths[k].poses[static_cast<std::size_t>(s)];
      const std::vector<ContactPoint> fresh = contacts(a, b, paths[k].epsilon, solver);
      std::vector<ContactPoint>& batched = batch.contacts(index[k]);
      if (paths[k].inside == InsideTest::later) markInside(a, b, paths[k].epsilon, batched);
      ASSERT_TRUE(sameContacts(batched, fresh)) << "path " << k << ", step " << s << ": "
                                                << batched.size() << " against " << fresh.size();
      withContacts += fresh.empty() ? 0 : 1;
    }
  }
  // Most pairs went through the batch's kernels, most of them touching.
  const auto calls = paths.size() * static_cast<std::size_t>(steps);
  EXPECT_GT(gathered, calls / 2);
  EXPECT_GT(withContacts, calls / 2);
}

TEST(ContactBatch, EachPairGetsItsFreshQuerysContacts) {
  expectFreshContactsInBatches(kernels::Solver::Hybrid, 120);
}

// The other solvers' pairs do not depend on their batch either (the penalty solver's lanes run a
// fixed schedule each; brute force runs pair by pair).
TEST(ContactBatch, EachPairGetsItsFreshQuerysContactsWithTheOtherSolvers) {
  expectFreshContactsInBatches(kernels::Solver::Penalty, 40);
  expectFreshContactsInBatches(kernels::Solver::BruteForce, 40);
}

TEST(ContactBatch, BadInputThrowsAndLeavesTheBatchUsable) {
  const QueryMesh a(primitives::granulate(3));
  QueryMesh b(primitives::granulate(4));
  b.setPose(RigidTransform::translationBy({1.7, 0.1, 0.0}));
  ContactCache cache(0.02), other(0.02);
  ContactBatch batch;
  EXPECT_EQ(batch.add(a, b, 0.05, cache), 0u);
  EXPECT_THROW(batch.add(a, b, -1.0, other), Error);
  EXPECT_THROW(batch.add(a, b, std::nan(""), other), Error);
  EXPECT_EQ(batch.add(a, b, 0.05, other), 1u);
  batch.run();
  EXPECT_EQ(batch.size(), 2u);
  EXPECT_TRUE(sameContacts(batch.contacts(0), contacts(a, b, 0.05)));
  EXPECT_TRUE(sameContacts(batch.contacts(1), contacts(a, b, 0.05)));
  EXPECT_FALSE(batch.contacts(0).empty());
  // Answered from the caches the second time, through the kernels in one batch.
  batch.clear();
  EXPECT_EQ(batch.add(a, b, 0.05, cache), 0u);
  EXPECT_EQ(batch.add(a, b, 0.05, other), 1u);
  EXPECT_THROW(batch.contacts(0), Error);  // before run()
  batch.run();
  EXPECT_EQ(cache.reused(), 1u);
  EXPECT_EQ(other.reused(), 1u);
  EXPECT_TRUE(sameContacts(batch.contacts(1), contacts(a, b, 0.05)));
  EXPECT_THROW(batch.contacts(2), Error);
  // Run again, and with a pair added after a run: each pair's contacts once, as a fresh query's.
  batch.run();
  EXPECT_TRUE(sameContacts(batch.contacts(0), contacts(a, b, 0.05)));
  ContactCache third(0.02);
  EXPECT_EQ(batch.add(a, b, 0.05, third), 2u);
  batch.run();
  EXPECT_TRUE(sameContacts(batch.contacts(0), contacts(a, b, 0.05)));
  EXPECT_TRUE(sameContacts(batch.contacts(2), contacts(a, b, 0.05)));
  batch.clear();
  EXPECT_EQ(batch.size(), 0u);
  EXPECT_THROW(batch.contacts(0), Error);
}

}  // namespace
}  // namespace delta::contactdetection
