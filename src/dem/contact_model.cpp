#include "delta/dem/contact_model.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "delta/core/error.h"
#include "delta/core/format.h"

#include "detail/two_lanes.h"

namespace delta::dem {
namespace {

using delta::detail::splat;
using delta::detail::Two;
using delta::detail::Two3;
using delta::detail::TwoMask;

/// The largest damping ratio dampingRatio() searches (restitution ≈ 1e-4 there).
constexpr double kLargestDampingRatio = 50.0;

/// The depth of a contact point into the ε-shell; past the shell it keeps growing with the
/// distance between the (interpenetrating) triangles, see the law in the header.
double depthOf(const ContactPoint& point, double shell) noexcept {
  if (point.overlap) return shell + point.distance;
  return std::max(0.0, shell - point.distance);
}

/// How much of the dashpot to charge at the first evaluation of a contact. Velocity Verlet
/// applies a force for the step centred on its evaluation; the dashpot, unlike the spring, is at
/// full strength the moment the surfaces cross the shell, so charging it from the first
/// evaluation in contact on made the restitution depend on where the crossing fell between two
/// evaluations (±1.7% at e = 0.5 and thirty steps a contact). The crossing happened δ/|v_n|
/// before this evaluation (the deepest point's depth and approach speed): when that is less than
/// one step, this evaluation is the contact's first and its share is 0.5 + δ/(|v_n|·dt), between
/// ½ (the crossing just now: half the step ahead is in contact) and 3/2 (the crossing a step
/// ago: half of the step before, charged nothing, was in contact too). Otherwise 1.
[[gnu::always_inline]] inline double onsetFactor(const PointForce& deepest, const BodyMotion& first,
                                                 const BodyMotion& second,
                                                 double timeStep) noexcept {
  const Vec3 relative = first.velocityAt(deepest.point.x) - second.velocityAt(deepest.point.x);
  const double approach = -dot(relative, deepest.point.direction) * timeStep;  // per step
  if (!(approach > 0.0) || deepest.depth >= approach) return 1.0;
  return 0.5 + deepest.depth / approach;
}

/// What friction puts at a contact's centre: a tangential force and a torque about the normal.
struct Friction {
  Vec3 force;
  double torque = 0.0;
  TangentialSpring spring;
  bool sliding = false;
};

/// The tangential and torsion springs at `centre` with unit `normal` (the header's "Friction"),
/// limited by μ·normalForce and μ·normalForce·meanArm; `polarMoment` is Σwᵢ|rᵢ|², the torsion
/// spring's stiffness per k_t (0: no twist).
[[gnu::always_inline]] inline Friction frictionAt(const Vec3& centre, const Vec3& normal,
                                                  double normalForce, double polarMoment,
                                                  double meanArm, const BodyMotion& first,
                                                  const BodyMotion& second, double effectiveMass,
                                                  const TangentialSpring& previous, double timeStep,
                                                  const ContactLaw& law) noexcept {
  Friction result;
  const double tangentialDamping =
      2.0 * law.dampingRatio * std::sqrt(law.tangentialStiffness * effectiveMass);

  // Sliding: the spring at the contact centre, turned into the current tangent plane at its
  // length, stretched by the tangential relative velocity there.
  const Vec3 relative = first.velocityAt(centre) - second.velocityAt(centre);
  const Vec3 slidingVelocity = relative - normal * dot(relative, normal);
  const double previousLength = length(previous.displacement);
  Vec3 displacement = previous.displacement - normal * dot(previous.displacement, normal);
  const double projectedLength = length(displacement);
  displacement = projectedLength > 0.0 ? displacement * (previousLength / projectedLength) : Vec3{};
  displacement += slidingVelocity * timeStep;
  Vec3 tangential = displacement * -law.tangentialStiffness - slidingVelocity * tangentialDamping;
  const double limit = law.friction * normalForce;
  const double magnitude = length(tangential);
  if (magnitude > limit) {
    tangential = magnitude > 0.0 ? tangential * (limit / magnitude) : Vec3{};
    displacement = tangential * (-1.0 / law.tangentialStiffness);
    result.sliding = true;
  }
  result.force = tangential;
  result.spring.displacement = displacement;

  // Twisting: a torsion spring of stiffness k_t·polarMoment, cut at the Coulomb limit
  // μ·F·meanArm. One point, or points on a line through the centre along which the body turns,
  // have no arm and no twist.
  if (polarMoment > 0.0) {
    const double spin = dot(first.angularVelocity - second.angularVelocity, normal);
    double twist = previous.twist + spin * timeStep;
    const double torsionStiffness = law.tangentialStiffness * polarMoment;
    double torque = -torsionStiffness * twist - tangentialDamping * polarMoment * spin;
    const double torqueLimit = law.friction * normalForce * meanArm;
    if (std::fabs(torque) > torqueLimit) {
      torque = std::copysign(torqueLimit, torque);
      twist = -torque / torsionStiffness;
      result.sliding = true;
    }
    result.torque = torque;
    result.spring.twist = twist;
  }
  return result;
}

/// pairForces of one point: the general law's arithmetic with its sums of one term written out
/// (a weight d/d is 1, x·1 and x/1 are x), so the same bits without its loops; a mesh pair's
/// lone contact. No twist: one point has no arm.
void onePointForces(const ContactPoint& point, const BodyMotion& first, const BodyMotion& second,
                    double effectiveMass, const TangentialSpring& previous, double timeStep,
                    const ContactLaw& law, OnePointForces& result) noexcept {
  result = OnePointForces{};
  PointForce& out = result.point;
  out.point = point;
  out.depth = depthOf(point, 2.0 * law.epsilon);
  if (out.depth > 0.0) result.deepest = out.depth;
  // The general law's overlap directions change nothing here: a lone overlapping point has no
  // clear points to take a direction from.
  result.springEnergy = 0.5 * law.stiffness * result.deepest * result.deepest;
  if (!(out.depth > 0.0)) return;  // exactly on the shell: no force yet

  const double damping = 2.0 * law.dampingRatio * std::sqrt(law.stiffness * effectiveMass) *
                         onsetFactor(out, first, second, timeStep);
  const double spring = law.stiffness * result.deepest;
  const Vec3& n = out.point.direction;
  const Vec3 relative = first.velocityAt(out.point.x) - second.velocityAt(out.point.x);
  const double normalForce = std::max(0.0, spring - damping * dot(relative, n));
  out.force = n * normalForce;
  result.normalForce = normalForce;
  const Vec3 centre = Vec3{} + out.point.x;  // as the general sum from zero: −0 becomes +0
  const Vec3 meanDirection = normalized(Vec3{} + n);
  if (!(law.friction > 0.0) || !(law.tangentialStiffness > 0.0) ||
      !(lengthSquared(meanDirection) > 0.5))
    return;
  const Friction friction = frictionAt(centre, meanDirection, result.normalForce, 0.0, 0.0, first,
                                       second, effectiveMass, previous, timeStep, law);
  result.spring = friction.spring;
  result.sliding = friction.sliding;
  out.force += friction.force;
}

}  // namespace

PairDamping pairDamping(const ContactLaw& law, double effectiveMass) noexcept {
  return {2.0 * law.dampingRatio * std::sqrt(law.stiffness * effectiveMass),
          2.0 * law.dampingRatio * std::sqrt(law.tangentialStiffness * effectiveMass)};
}

namespace {

/// Pairs side by side in one batch of the one-point law: every step of the law on two pairs at
/// once (two lanes of a vector register: SSE2 on x86-64, Advanced SIMD on AArch64), and on four
/// such pairs of lanes before the next step, so that the pairs' chains of square roots and
/// divisions overlap instead of waiting one after the other (a pair alone is a chain of four of
/// each). Each lane's arithmetic is the scalar law's, operation for operation: the same bits.
constexpr std::size_t kLanes = 8;
constexpr std::size_t kHalves = kLanes / 2;

/// A body's BodyMotion in two lanes.
struct MotionTwo {
  Two3 centre, velocity, spin;

  /// velocityAt: velocity + ω × (x − centre).
  Two3 velocityAt(const Two3& x) const noexcept { return velocity + cross(spin, x - centre); }
};

/// What the one-point law reads of two lanes' pairs, and what it gives.
struct LawTwo {
  Two3 x;  ///< the contact point
  Two3 n;  ///< its unit direction, from the second body toward the first
  Two gap;
  MotionTwo first, second;
  Two normalDamping, tangentialDamping;
  Two3 previous;  ///< the sliding spring of the step before

  Two depth;
  Two normalForce;
  Two3 force;
  Two3 displacement;  ///< the sliding spring to keep
  TwoMask sliding;
};

/// The point law of one point (onePointForces' arithmetic, without its sums of one term) on
/// every lane of `lanes`: each step for all of them before the next, so that their chains of
/// square roots and divisions (four of each, one after the other) run side by side.
[[gnu::always_inline]] inline void pointLaw(LawTwo (&lanes)[kHalves], double timeStep,
                                            const ContactLaw& law) noexcept {
  const Two zero{};
  Two3 relative[kHalves];
  Two normalVelocity[kHalves];
  for (std::size_t h = 0; h < kHalves; ++h) {
    LawTwo& two = lanes[h];
    two.depth = splat(2.0 * law.epsilon) - two.gap;  // 2ε − gap, overlapping or not (depthOf)
    relative[h] = two.first.velocityAt(two.x) - two.second.velocityAt(two.x);
    normalVelocity[h] = dot(relative[h], two.n);
  }
  // The normal law, its dashpot charged from the onset (onsetFactor).
  for (std::size_t h = 0; h < kHalves; ++h) {
    LawTwo& two = lanes[h];
    const Two approach = -normalVelocity[h] * splat(timeStep);
    const Two share = splat(0.5) + two.depth / approach;  // taken only where approach > 0
    const Two onset = approach > zero && two.depth < approach ? share : splat(1.0);
    const Two normal =
        splat(law.stiffness) * two.depth - two.normalDamping * onset * normalVelocity[h];
    two.normalForce = zero < normal ? normal : zero;  // std::max(0.0, normal)
    two.force = two.n * two.normalForce;
    two.displacement = Two3{};
    two.sliding = TwoMask{};
  }
  if (!(law.friction > 0.0 && law.tangentialStiffness > 0.0)) return;
  // The sliding spring turned into the tangent plane at its length, stretched (frictionAt).
  Two3 slidingVelocity[kHalves], displacement[kHalves], tangential[kHalves];
  Two previousLength[kHalves], projectedLength[kHalves], magnitude[kHalves];
  for (std::size_t h = 0; h < kHalves; ++h) {
    const LawTwo& two = lanes[h];
    slidingVelocity[h] = relative[h] - two.n * normalVelocity[h];
    previousLength[h] = length(two.previous);
    displacement[h] = two.previous - two.n * dot(two.previous, two.n);
    projectedLength[h] = length(displacement[h]);
  }
  for (std::size_t h = 0; h < kHalves; ++h) {
    const Two ratio = previousLength[h] / projectedLength[h];  // taken only where it is > 0
    displacement[h] = select(projectedLength[h] > zero, displacement[h] * ratio, Two3{}) +
                      slidingVelocity[h] * splat(timeStep);
    tangential[h] = displacement[h] * splat(-law.tangentialStiffness) -
                    slidingVelocity[h] * lanes[h].tangentialDamping;
    magnitude[h] = length(tangential[h]);
  }
  for (std::size_t h = 0; h < kHalves; ++h) {
    LawTwo& two = lanes[h];
    const Two limit = splat(law.friction) * two.normalForce;
    const TwoMask slides = magnitude[h] > limit;
    const Two cut = limit / magnitude[h];  // taken only where the magnitude is > 0
    const Two3 cutBack = select(magnitude[h] > zero, tangential[h] * cut, Two3{});
    tangential[h] = select(slides, cutBack, tangential[h]);
    two.displacement =
        select(slides, tangential[h] * splat(-1.0 / law.tangentialStiffness), displacement[h]);
    two.sliding = slides;
    two.force = two.force + tangential[h];
  }
}

/// The motions, dashpots and springs of `a` (lane 0) and `b` (lane 1).
void takeLaws(LawTwo& lanes, const OnePointLaw& a, const OnePointLaw& b) noexcept {
  const auto motion = [](const BodyMotion& one, const BodyMotion& two) {
    return MotionTwo{Two3::of(one.centre, two.centre), Two3::of(one.velocity, two.velocity),
                     Two3::of(one.angularVelocity, two.angularVelocity)};
  };
  lanes.first = motion(*a.firstMotion, *b.firstMotion);
  lanes.second = motion(*a.secondMotion, *b.secondMotion);
  lanes.normalDamping = Two{a.damping.normal, b.damping.normal};
  lanes.tangentialDamping = Two{a.damping.tangential, b.damping.tangential};
  lanes.previous = Two3::of(a.previous ? a.previous->displacement : Vec3{},
                            b.previous ? b.previous->displacement : Vec3{});
}

/// Lane k's forces into `result` (its point set by the caller).
void laneForces(const LawTwo& lanes, std::size_t k, const ContactLaw& law,
                OnePointForces& result) noexcept {
  PointForce& out = result.point;
  const double depth = lanes.depth[k];
  out.depth = depth;
  out.force = lanes.force.lane(k);
  out.couple = Vec3{};
  out.volume = 0.0;
  result.deepest = depth;
  result.springEnergy = 0.5 * law.stiffness * depth * depth;
  result.normalForce = lanes.normalForce[k];
  result.spring = {lanes.displacement.lane(k), 0.0};
  result.sliding = lanes.sliding[k] != 0;
}

}  // namespace

void sphereSphereForces(std::span<const SpherePair> pairs, double timeStep, const ContactLaw& law,
                        std::span<bool> touching) noexcept {
  const double shell = 2.0 * law.epsilon;
  for (std::size_t base = 0; base < pairs.size(); base += kLanes) {
    // A short last batch repeats its first pair.
    const std::size_t count = std::min(kLanes, pairs.size() - base);
    const SpherePair* lane[kLanes];
    for (std::size_t k = 0; k < kLanes; ++k)
      lane[k] = &pairs[base + (k < count ? k : 0)];
    LawTwo lanes[kHalves];
    Two3 first[kHalves], difference[kHalves], half[kHalves];
    Two firstRadius[kHalves], secondRadius[kHalves], centres[kHalves];
    for (std::size_t h = 0; h < kHalves; ++h) {
      const SpherePair& a = *lane[2 * h];
      const SpherePair& b = *lane[2 * h + 1];
      first[h] = Two3::of(a.first->center, b.first->center);
      firstRadius[h] = Two{a.first->radius, b.first->radius};
      secondRadius[h] = Two{a.second->radius, b.second->radius};
      takeLaws(lanes[h], a.law, b.law);
      difference[h] = first[h] - Two3::of(a.second->center, b.second->center);
      centres[h] = length(difference[h]);
    }
    for (std::size_t h = 0; h < kHalves; ++h) {
      LawTwo& two = lanes[h];
      const Two gap = centres[h] - firstRadius[h] - secondRadius[h];
      const Two3 n = select(centres[h] > Two{}, difference[h] * (splat(1.0) / centres[h]),
                            Two3{splat(1.0), Two{}, Two{}});
      // Halfway between the surfaces' closest points c₁ − r₁n and c₂ + r₂n; P − x is half the
      // gap.
      half[h] = n * (splat(0.5) * gap);
      two.x = first[h] - n * firstRadius[h] - half[h];
      two.n = n;
      two.gap = gap;
    }
    pointLaw(lanes, timeStep, law);
    for (std::size_t k = 0; k < count; ++k) {
      const LawTwo& two = lanes[k / 2];
      const double gap = two.gap[k % 2];
      touching[base + k] = gap < shell;
      if (!touching[base + k]) continue;
      OnePointForces& result = *lane[k]->law.result;
      ContactPoint& point = result.point.point;
      point.x = two.x.lane(k % 2);
      point.normal = half[k / 2].lane(k % 2);
      point.direction = two.n.lane(k % 2);
      point.distance = std::fabs(gap);
      point.overlap = gap < 0.0;
      point.converged = true;
      point.first = point.second = 0;
      laneForces(two, k % 2, law, result);
    }
  }
}

void onePointForces(std::span<const OnePointPair> pairs, double timeStep,
                    const ContactLaw& law) noexcept {
  for (std::size_t base = 0; base < pairs.size(); base += kLanes) {
    const std::size_t count = std::min(kLanes, pairs.size() - base);
    const OnePointPair* lane[kLanes];
    for (std::size_t k = 0; k < kLanes; ++k)
      lane[k] = &pairs[base + (k < count ? k : 0)];
    LawTwo lanes[kHalves];
    for (std::size_t h = 0; h < kHalves; ++h) {
      const OnePointPair& a = *lane[2 * h];
      const OnePointPair& b = *lane[2 * h + 1];
      LawTwo& two = lanes[h];
      two.x = Two3::of(a.point->x, b.point->x);
      two.n = Two3::of(a.point->direction, b.point->direction);
      const auto gap = [](const ContactPoint& point) {
        return point.overlap ? -point.distance : point.distance;
      };
      two.gap = Two{gap(*a.point), gap(*b.point)};
      takeLaws(two, a.law, b.law);
    }
    pointLaw(lanes, timeStep, law);
    for (std::size_t k = 0; k < count; ++k) {
      ContactPoint& point = lane[k]->law.result->point.point;
      if (&point != lane[k]->point) point = *lane[k]->point;
      laneForces(lanes[k / 2], k % 2, law, *lane[k]->law.result);
    }
  }
}

PairForces pairForces(std::span<const ContactPoint> points, const BodyMotion& first,
                      const BodyMotion& second, double effectiveMass,
                      const TangentialSpring& previous, double timeStep, const ContactLaw& law) {
  PairForces result;
  pairForces(points, first, second, effectiveMass, previous, timeStep, law, result);
  return result;
}

void pairForces(std::span<const ContactPoint> points, const BodyMotion& first,
                const BodyMotion& second, double effectiveMass, const TangentialSpring& previous,
                double timeStep, const ContactLaw& law, PairForces& result) {
  std::vector<PointForce> buffer = std::move(result.points);
  result = PairForces{};
  result.points = std::move(buffer);
  result.points.assign(points.size(), PointForce{});
  if (points.empty()) return;
  if (points.size() == 1) {
    OnePointForces one;
    onePointForces(points.front(), first, second, effectiveMass, previous, timeStep, law, one);
    static_cast<PairForceSummary&>(result) = one;
    result.points.front() = one.point;
    return;
  }
  const double shell = 2.0 * law.epsilon;
  double depthSum = 0.0;
  std::size_t deepestIndex = 0, pressed = 0;
  Vec3 clearDirection;  // depth-weighted mean direction of the points that do not overlap
  for (std::size_t i = 0; i < points.size(); ++i) {
    PointForce& out = result.points[i];
    out.point = points[i];
    out.depth = depthOf(points[i], shell);
    depthSum += out.depth;
    pressed += out.depth > 0.0 ? 1 : 0;
    if (out.depth > result.deepest) {
      result.deepest = out.depth;
      deepestIndex = i;
    }
    if (!points[i].overlap) clearDirection += points[i].direction * out.depth;
  }
  clearDirection = normalized(clearDirection);
  if (lengthSquared(clearDirection) > 0.5)
    for (PointForce& out : result.points)
      if (out.point.overlap) out.point.direction = clearDirection;
  result.springEnergy = 0.5 * law.stiffness * result.deepest * result.deepest;
  if (!(depthSum > 0.0)) return;  // every point exactly on the shell: no force yet

  const double damping = 2.0 * law.dampingRatio * std::sqrt(law.stiffness * effectiveMass) *
                         onsetFactor(result.points[deepestIndex], first, second, timeStep);
  const double pointDamping = damping / static_cast<double>(pressed);
  const double spring = law.stiffness * result.deepest;
  // Point i's share wᵢ·k·δ_max − (c/m)·v_n,ᵢ. Where some are negative (shallow points while the
  // bodies separate) they are not pulled: each point takes its positive share, scaled by
  // (Σ of all shares) / (Σ of the positive ones), so that the pair's total stays
  // max(0, k·δ_max − c·v̄_n) (v̄_n the points' mean) and its restitution e. (Cut at zero point
  // by point, the dropped negative shares left the pair under-damped: an icosphere dropped on a
  // floor came back at 1.23 for e = 0.1, an audit found.) Where none is negative the scale is
  // exactly 1.
  const auto share = [&](const PointForce& out) {
    const Vec3 relative = first.velocityAt(out.point.x) - second.velocityAt(out.point.x);
    return out.depth / depthSum * spring - pointDamping * dot(relative, out.point.direction);
  };
  double total = 0.0, positive = 0.0;
  for (const PointForce& out : result.points) {
    if (!(out.depth > 0.0)) continue;
    const double f = share(out);
    total += f;
    positive += std::max(0.0, f);
  }
  const double scale = total > 0.0 ? total / positive : 0.0;
  Vec3 centre, meanDirection;
  for (PointForce& out : result.points) {
    if (!(out.depth > 0.0)) continue;
    const double weight = out.depth / depthSum;
    const Vec3& n = out.point.direction;
    const double normalForce = std::max(0.0, share(out)) * scale;
    out.force = n * normalForce;
    result.normalForce += normalForce;
    centre += out.point.x * weight;
    meanDirection += n * weight;
  }

  meanDirection = normalized(meanDirection);
  if (!(law.friction > 0.0) || !(law.tangentialStiffness > 0.0) ||
      !(lengthSquared(meanDirection) > 0.5))
    return;
  // The torsion spring's stiffness per k_t and arm: rᵢ the points' offsets in the tangent plane.
  double polarMoment = 0.0, meanArm = 0.0;
  for (PointForce& out : result.points) {
    if (!(out.depth > 0.0)) continue;
    const double weight = out.depth / depthSum;
    const Vec3 arm = out.point.x - centre;
    const Vec3 planar = arm - meanDirection * dot(arm, meanDirection);
    polarMoment += weight * lengthSquared(planar);
    meanArm += weight * length(planar);
  }
  const Friction friction =
      frictionAt(centre, meanDirection, result.normalForce, polarMoment, meanArm, first, second,
                 effectiveMass, previous, timeStep, law);
  const Vec3 tangential = friction.force;
  const double torque = friction.torque;
  result.spring = friction.spring;
  result.sliding = friction.sliding;

  // Shared by the points: the sliding force by depth, the twisting torque as forces along
  // n × rᵢ whose sum is zero (Σwᵢrᵢ = 0 about the weighted centre) and whose moment is the torque.
  for (PointForce& out : result.points) {
    if (!(out.depth > 0.0)) continue;
    const double weight = out.depth / depthSum;
    out.force += tangential * weight;
    if (polarMoment > 0.0)
      out.force += cross(meanDirection, out.point.x - centre) * (weight * torque / polarMoment);
  }
}

PairForces volumePairForces(std::span<const contactdetection::OverlapRegion> regions,
                            const BodyMotion& first, const BodyMotion& second, double effectiveMass,
                            double volumeStiffness, const TangentialSpring& previous,
                            double timeStep, const ContactLaw& law) {
  PairForces result;
  const double kappa = volumeStiffness;
  const double dampingPerArea = 2.0 * law.dampingRatio * std::sqrt(effectiveMass * kappa);
  std::size_t largest = 0;
  for (const contactdetection::OverlapRegion& region : regions) {
    const double area = length(region.areaVector);
    if (!(area > 0.0) || !(region.volume > 0.0)) continue;
    const Vec3 n = region.areaVector / area;      // from the first body into the second
    const double spring = kappa * region.volume;  // w′(V)
    // The relative velocity of the second body with respect to the first, along n: negative
    // while they approach. The dashpot acts at the centroid, never pulling (it may cancel the
    // spring's force, not reverse it).
    const double normalVelocity =
        dot(second.velocityAt(region.centroid) - first.velocityAt(region.centroid), n);
    const double springForce = spring * area;
    const double damping = std::max(-springForce, -dampingPerArea * area * normalVelocity);
    PointForce out;
    out.point.x = region.centroid;
    out.point.direction = -n;
    out.point.normal = Vec3{};
    out.point.distance = region.volume / area;
    out.point.overlap = true;
    out.point.converged = true;
    out.depth = region.volume / area;
    out.volume = region.volume;
    // On the first body: the opposites of the second's κV·S + damping·n (= (κV|S| + damping)·n,
    // never negative) at the centroid and of its couple κV·M.
    out.force = n * -(springForce + damping);
    out.couple = region.moment * -spring;
    result.normalForce += springForce + damping;
    result.springEnergy += 0.5 * kappa * region.volume * region.volume;
    if (out.depth > result.deepest) result.deepest = out.depth;
    if (result.points.empty() || region.volume > result.points[largest].volume)
      largest = result.points.size();
    result.points.push_back(out);
  }
  if (result.points.empty() || !(law.friction > 0.0) || !(law.tangentialStiffness > 0.0))
    return result;
  // Friction at the largest region, its contact patch taken as a disc of area |S|.
  PointForce& main = result.points[largest];
  const Vec3 normal = -main.point.direction;
  const double area = main.volume / main.depth;
  const double polarMoment = area / (2.0 * std::numbers::pi);
  const double meanArm = (2.0 / 3.0) * std::sqrt(area / std::numbers::pi);
  const Friction friction =
      frictionAt(main.point.x, normal, result.normalForce, polarMoment, meanArm, first, second,
                 effectiveMass, previous, timeStep, law);
  main.force += friction.force;
  main.couple += normal * friction.torque;
  result.spring = friction.spring;
  result.sliding = friction.sliding;
  return result;
}

double volumeStiffness(double stiffness, double smallestRadius) noexcept {
  const double crossSection = std::numbers::pi * smallestRadius * smallestRadius;
  return stiffness / (crossSection * crossSection);
}

double equivalentRadius(double volume) noexcept {
  return std::cbrt(0.75 * volume / std::numbers::pi);
}

const char* contactModelName(ContactModel model) noexcept {
  return model == ContactModel::volume ? "volume" : "point";
}

std::optional<ContactModel> parseContactModel(std::string_view text) noexcept {
  for (const ContactModel model : {ContactModel::point, ContactModel::volume})
    if (text == contactModelName(model)) return model;
  return std::nullopt;
}

ContactModel contactModelNamed(const std::string& name) {
  if (const std::optional<ContactModel> model = parseContactModel(name)) return *model;
  throw Error("dem: contact model '" + name + "' is neither point nor volume");
}

double restitutionOf(double dampingRatio) noexcept {
  // Dimensionless (k = m = 1): δ'' = −δ − 2ζδ', δ(0) = 0, δ'(0) = 1. The contact ends at t*
  // where the force δ + 2ζδ' returns to zero, and there −δ'(t*) = exp(−ζt*) in every regime.
  const double zeta = std::max(0.0, dampingRatio);
  double endTime;
  if (zeta < 1.0) {
    const double damped = std::sqrt(1.0 - zeta * zeta);
    endTime = std::atan2(2.0 * zeta * damped, 2.0 * zeta * zeta - 1.0) / damped;
  } else if (zeta > 1.0) {
    const double spread = std::sqrt(zeta * zeta - 1.0);
    endTime = std::atanh(2.0 * zeta * spread / (2.0 * zeta * zeta - 1.0)) / spread;
  } else {
    endTime = 2.0;  // critical damping: δ = t·e⁻ᵗ, force zero at t = 2
  }
  return std::exp(-zeta * endTime);
}

double dampingRatio(double restitution) {
  if (!(restitution >= 0.0 && restitution <= 1.0))
    throw Error("dem: restitution = " + toString(restitution) + " must lie in [0, 1]");
  if (restitution == 1.0) return 0.0;
  double low = 0.0, high = kLargestDampingRatio;  // restitutionOf decreases on [low, high]
  for (int iteration = 0; iteration < 200 && high - low > 1e-15 * high; ++iteration) {
    const double middle = 0.5 * (low + high);
    (restitutionOf(middle) > restitution ? low : high) = middle;
  }
  return 0.5 * (low + high);
}

double contactDuration(double stiffness, double effectiveMass) noexcept {
  return std::numbers::pi * std::sqrt(effectiveMass / stiffness);
}

double suggestedTimeStep(double stiffness, double smallestMass) noexcept {
  return contactDuration(stiffness, 0.5 * smallestMass) / 30.0;
}

double stiffnessForImpact(double mass, double speed, double depth) noexcept {
  return mass * speed * speed / (depth * depth);
}

}  // namespace delta::dem
