// The batched one-point law of a World's spheres (contact_model.h: sphereSphereForces and
// onePointForces) against the general law (pairForces of the same point) and against itself
// in other batches.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "delta/dem/contact_model.h"
#include "delta/dem/narrow_phase.h"

namespace delta::dem {
namespace {

/// Uniform doubles from std::mt19937_64's raw output: the same cases on every machine.
class Random {
 public:
  explicit Random(std::uint64_t seed) : engine_(seed) {}
  double uniform(double low, double high) {
    return low + (high - low) * (static_cast<double>(engine_() >> 11) * 0x1p-53);
  }
  Vec3 inBox(double half) {
    return {uniform(-half, half), uniform(-half, half), uniform(-half, half)};
  }
  Vec3 unit() {
    for (;;) {
      const Vec3 v = inBox(1.0);
      const double n = length(v);
      if (n > 0.1 && n < 1.0) return v / n;
    }
  }

 private:
  std::mt19937_64 engine_;
};

ContactLaw lawWith(double friction) {
  ContactLaw law;
  law.epsilon = 1e-3;
  law.stiffness = 2e4;
  law.dampingRatio = dampingRatio(0.4);
  law.friction = friction;
  law.tangentialStiffness = 2.0 / 7.0 * law.stiffness;
  return law;
}

/// One random pair of spheres with its motions and spring: gaps from overlapping by 2ε to 3ε
/// apart (about one in six apart), centres `offset` from the origin.
struct SphereCase {
  Sphere first, second;
  BodyMotion firstMotion, secondMotion;
  TangentialSpring spring;
  bool newContact = false;
  double effectiveMass = 0.0;
};

SphereCase randomSphereCase(Random& random, const ContactLaw& law, const Vec3& offset) {
  SphereCase c;
  const double epsilon = law.epsilon;
  c.first.radius = random.uniform(0.005, 0.02);
  c.second.radius = random.uniform(0.005, 0.02);
  const double gap = random.uniform(-2.0 * epsilon, 3.0 * epsilon);
  c.first.center = offset + random.inBox(0.1);
  c.second.center = c.first.center - random.unit() * (c.first.radius + c.second.radius + gap);
  c.firstMotion = {c.first.center, random.inBox(0.5), random.inBox(50.0)};
  c.secondMotion = {c.second.center, random.inBox(0.5), random.inBox(50.0)};
  // Springs in and out of the tangent plane, small (sticking) and large (sliding).
  c.spring.displacement = random.inBox(random.uniform(0.0, 1.0) < 0.5 ? 1e-6 : 1e-3);
  c.newContact = random.uniform(0.0, 1.0) < 0.2;
  c.effectiveMass = random.uniform(1e-3, 1e-1);
  return c;
}

/// How far apart two results may be: the rounding of the two ways of computing the point (a
/// few ulps of the coordinates and the gap) carried through the law.
void expectClose(const OnePointForces& actual, const PairForces& expected, double scale,
                 const std::string& label) {
  ASSERT_EQ(expected.points.size(), 1u) << label;
  const PointForce& a = actual.point;
  const PointForce& e = expected.points.front();
  const double near = 1e-12 * scale;
  EXPECT_LE(distance(a.point.x, e.point.x), near) << label;
  EXPECT_LE(distance(a.point.normal, e.point.normal), near) << label;
  EXPECT_LE(distance(a.point.direction, e.point.direction), 1e-12) << label;
  EXPECT_NEAR(a.point.distance, e.point.distance, near) << label;
  EXPECT_EQ(a.point.overlap, e.point.overlap) << label;
  EXPECT_EQ(a.point.first, e.point.first) << label;
  EXPECT_EQ(a.point.second, e.point.second) << label;
  EXPECT_TRUE(a.point.converged) << label;
  EXPECT_NEAR(a.depth, e.depth, near) << label;
  const double force = 1e-8 * (length(e.force) + 1.0);
  EXPECT_LE(distance(a.force, e.force), force) << label;
  EXPECT_EQ(a.couple, Vec3{}) << label;
  EXPECT_EQ(a.volume, 0.0) << label;
  EXPECT_NEAR(actual.normalForce, expected.normalForce, force) << label;
  EXPECT_NEAR(actual.deepest, expected.deepest, near) << label;
  EXPECT_NEAR(actual.springEnergy, expected.springEnergy, 1e-8 * (expected.springEnergy + 1e-12))
      << label;
  EXPECT_LE(distance(actual.spring.displacement, expected.spring.displacement),
            1e-8 * (length(expected.spring.displacement) + 1e-12))
      << label;
  EXPECT_EQ(actual.spring.twist, 0.0) << label;
  EXPECT_EQ(actual.sliding, expected.sliding) << label;
}

/// Every field of two results, bit for bit.
void expectSame(const OnePointForces& a, const OnePointForces& b, const std::string& label) {
  EXPECT_EQ(a.point.point.x, b.point.point.x) << label;
  EXPECT_EQ(a.point.point.normal, b.point.point.normal) << label;
  EXPECT_EQ(a.point.point.direction, b.point.point.direction) << label;
  EXPECT_EQ(a.point.point.distance, b.point.point.distance) << label;
  EXPECT_EQ(a.point.point.overlap, b.point.point.overlap) << label;
  EXPECT_EQ(a.point.depth, b.point.depth) << label;
  EXPECT_EQ(a.point.force, b.point.force) << label;
  EXPECT_EQ(a.normalForce, b.normalForce) << label;
  EXPECT_EQ(a.deepest, b.deepest) << label;
  EXPECT_EQ(a.springEnergy, b.springEnergy) << label;
  EXPECT_EQ(a.spring.displacement, b.spring.displacement) << label;
  EXPECT_EQ(a.sliding, b.sliding) << label;
}

std::vector<SpherePair> spherePairs(const std::vector<SphereCase>& cases, const ContactLaw& law,
                                    std::vector<OnePointForces>& results) {
  std::vector<SpherePair> pairs;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const SphereCase& c = cases[i];
    pairs.push_back({&c.first,
                     &c.second,
                     {&c.firstMotion, &c.secondMotion, pairDamping(law, c.effectiveMass),
                      c.newContact ? nullptr : &c.spring, &results[i]}});
  }
  return pairs;
}

TEST(DemOnePointLaw, SpherePairsAgreeWithTheGeneralLawToRounding) {
  for (const double friction : {0.0, 0.5, 0.02}) {
    const ContactLaw law = lawWith(friction);
    for (const Vec3 offset : {Vec3{}, Vec3{1e3, -2e3, 5e2}}) {
      Random random(7);
      std::vector<SphereCase> cases;
      for (int i = 0; i < 2000; ++i)
        cases.push_back(randomSphereCase(random, law, offset));
      std::vector<OnePointForces> results(cases.size());
      const std::vector<SpherePair> pairs = spherePairs(cases, law, results);
      std::unique_ptr<bool[]> flags(new bool[cases.size()]);
      sphereSphereForces(pairs, 1e-4, law, std::span<bool>(flags.get(), cases.size()));
      std::size_t apart = 0, overlapping = 0, sliding = 0;
      for (std::size_t i = 0; i < cases.size(); ++i) {
        const SphereCase& c = cases[i];
        const std::string label = "friction " + std::to_string(friction) + " offset " +
                                  std::to_string(offset.x) + " case " + std::to_string(i);
        const PairContacts contacts = sphereSphereContacts(c.first, c.second, law.epsilon);
        // Gaps within rounding of 2ε are not drawn (one in 10⁹): the two ways agree on which
        // side of the shell a pair is.
        ASSERT_EQ(flags[i], !contacts.points.empty()) << label;
        if (!flags[i]) {
          ++apart;
          continue;
        }
        const PairForces expected =
            pairForces(contacts.points, c.firstMotion, c.secondMotion, c.effectiveMass,
                       c.newContact ? TangentialSpring{} : c.spring, 1e-4, law);
        expectClose(results[i], expected, maxAbs(c.first.center) + c.first.radius, label);
        overlapping += results[i].point.point.overlap ? 1 : 0;
        sliding += results[i].sliding ? 1 : 0;
      }
      // The draw reached every branch.
      EXPECT_GT(apart, 100u);
      EXPECT_GT(overlapping, 100u);
      if (friction > 0.0) {
        EXPECT_GT(sliding, 10u);
      }
    }
  }
}

TEST(DemOnePointLaw, ConcentricAndTouchingSpheres) {
  const ContactLaw law = lawWith(0.5);
  BodyMotion still;
  Sphere a{{1, 2, 3}, 0.01}, b{{1, 2, 3}, 0.02};
  OnePointForces result;
  SpherePair pair{&a, &b, {&still, &still, pairDamping(law, 0.01), nullptr, &result}};
  bool touching = false;
  sphereSphereForces(std::span<const SpherePair>(&pair, 1), 1e-4, law,
                     std::span<bool>(&touching, 1));
  ASSERT_TRUE(touching);
  EXPECT_EQ(result.point.point.direction, (Vec3{1, 0, 0}));  // as sphereSphereContacts
  EXPECT_TRUE(result.point.point.overlap);
  EXPECT_DOUBLE_EQ(result.point.point.distance, 0.03);
  EXPECT_DOUBLE_EQ(result.point.depth, 2 * law.epsilon + 0.03);
  // Exactly 2ε apart: no contact (strictly below 2ε, as everywhere).
  Sphere c{{0, 0, 0}, 0.5}, d{{0, 0, -1.0 - 2 * law.epsilon}, 0.5};
  result = OnePointForces{};
  result.deepest = 42.0;
  pair = {&c, &d, {&still, &still, pairDamping(law, 0.01), nullptr, &result}};
  sphereSphereForces(std::span<const SpherePair>(&pair, 1), 1e-4, law,
                     std::span<bool>(&touching, 1));
  EXPECT_EQ(touching, !sphereSphereContacts(c, d, law.epsilon).points.empty());
  if (!touching) {
    EXPECT_EQ(result.deepest, 42.0);  // untouched
  }
}

TEST(DemOnePointLaw, APairsAnswerDoesNotDependOnItsBatch) {
  const ContactLaw law = lawWith(0.3);
  Random random(11);
  std::vector<SphereCase> cases;
  for (int i = 0; i < 203; ++i)  // not a multiple of the lanes
    cases.push_back(randomSphereCase(random, law, {}));
  std::vector<OnePointForces> all(cases.size()), alone(cases.size());
  const std::vector<SpherePair> pairs = spherePairs(cases, law, all);
  const std::vector<SpherePair> single = spherePairs(cases, law, alone);
  std::unique_ptr<bool[]> together(new bool[cases.size()]);
  sphereSphereForces(pairs, 1e-4, law, std::span<bool>(together.get(), cases.size()));
  for (std::size_t i = 0; i < cases.size(); ++i) {
    bool touching = false;
    sphereSphereForces(std::span<const SpherePair>(&single[i], 1), 1e-4, law,
                       std::span<bool>(&touching, 1));
    ASSERT_EQ(touching, together[i]) << i;
    if (touching) expectSame(alone[i], all[i], "sphere pair " + std::to_string(i));
  }

  // The same for the law of given points, each result also holding its own point.
  std::vector<ContactPoint> points;
  for (std::size_t i = 0; i < cases.size(); ++i)
    if (together[i]) points.push_back(all[i].point.point);
  std::vector<OnePointForces> batched(points.size()), oneByOne(points.size());
  std::vector<OnePointPair> batch, each;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const SphereCase& c = cases[i];
    batched[i].point.point = points[i];
    const PairDamping damping = pairDamping(law, c.effectiveMass);
    batch.push_back({&batched[i].point.point,
                     {&c.firstMotion, &c.secondMotion, damping, &c.spring, &batched[i]}});
    each.push_back(
        {&points[i], {&c.firstMotion, &c.secondMotion, damping, &c.spring, &oneByOne[i]}});
  }
  onePointForces(batch, 1e-4, law);
  for (std::size_t i = 0; i < points.size(); ++i) {
    onePointForces(std::span<const OnePointPair>(&each[i], 1), 1e-4, law);
    expectSame(oneByOne[i], batched[i], "point " + std::to_string(i));
  }
}

TEST(DemOnePointLaw, GivenPointsAgreeWithTheGeneralLawToRounding) {
  for (const double friction : {0.0, 0.5, 0.02}) {
    const ContactLaw law = lawWith(friction);
    Random random(5);
    std::vector<ContactPoint> points(1500);
    std::vector<BodyMotion> first(points.size()), second(points.size());
    std::vector<TangentialSpring> springs(points.size());
    std::vector<OnePointForces> results(points.size());
    std::vector<OnePointPair> pairs;
    for (std::size_t i = 0; i < points.size(); ++i) {
      ContactPoint& point = points[i];
      // A sphere's contact on a wall: a unit direction, a gap below 2ε (overlapping or not),
      // a triangle id.
      const double gap = random.uniform(-law.epsilon, 1.999 * law.epsilon);
      point.direction = random.unit();
      point.distance = std::fabs(gap);
      point.overlap = gap < 0.0;
      point.normal = point.direction * (0.5 * gap);
      point.x = random.inBox(0.2);
      point.second = static_cast<std::uint32_t>(i);
      first[i] = {point.x + point.direction * 0.01, random.inBox(0.5), random.inBox(50.0)};
      second[i] = {random.inBox(1.0), random.inBox(0.1), random.inBox(1.0)};
      springs[i].displacement = random.inBox(random.uniform(0.0, 1.0) < 0.5 ? 1e-6 : 1e-3);
      pairs.push_back(
          {&points[i], {&first[i], &second[i], pairDamping(law, 0.02), &springs[i], &results[i]}});
    }
    onePointForces(pairs, 1e-4, law);
    std::size_t sliding = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const PairForces expected = pairForces(std::span<const ContactPoint>(&points[i], 1), first[i],
                                             second[i], 0.02, springs[i], 1e-4, law);
      expectClose(results[i], expected, 1.0,
                  "friction " + std::to_string(friction) + " point " + std::to_string(i));
      EXPECT_EQ(results[i].point.point.second, points[i].second);
      sliding += results[i].sliding ? 1 : 0;
    }
    if (friction > 0.0) {
      EXPECT_GT(sliding, 10u);
    }
  }
}

}  // namespace
}  // namespace delta::dem
