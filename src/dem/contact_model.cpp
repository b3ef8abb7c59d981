#include "delta/dem/contact_model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "delta/core/error.h"
#include "delta/core/format.h"

namespace delta::dem {
namespace {

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
double onsetFactor(const std::vector<PointForce>& points, std::size_t deepestIndex,
                   const BodyMotion& first, const BodyMotion& second, double timeStep) noexcept {
  const PointForce& deepest = points[deepestIndex];
  const Vec3 relative = first.velocityAt(deepest.point.x) - second.velocityAt(deepest.point.x);
  const double approach = -dot(relative, deepest.point.direction) * timeStep;  // per step
  if (!(approach > 0.0) || deepest.depth >= approach) return 1.0;
  return 0.5 + deepest.depth / approach;
}

}  // namespace

PairForces pairForces(std::span<const ContactPoint> points, const BodyMotion& first,
                      const BodyMotion& second, double effectiveMass,
                      const TangentialSpring& previous, double timeStep, const ContactLaw& law) {
  PairForces result;
  if (points.empty()) return result;
  const double shell = 2.0 * law.epsilon;
  result.points.resize(points.size());
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
  if (!(depthSum > 0.0)) return result;  // every point exactly on the shell: no force yet

  const double damping = 2.0 * law.dampingRatio * std::sqrt(law.stiffness * effectiveMass) *
                         onsetFactor(result.points, deepestIndex, first, second, timeStep);
  const double pointDamping = damping / static_cast<double>(pressed);
  const double spring = law.stiffness * result.deepest;
  Vec3 centre, meanDirection;
  for (PointForce& out : result.points) {
    if (!(out.depth > 0.0)) continue;
    const double weight = out.depth / depthSum;
    const Vec3& n = out.point.direction;
    const Vec3 relative = first.velocityAt(out.point.x) - second.velocityAt(out.point.x);
    const double normalForce = std::max(0.0, weight * spring - pointDamping * dot(relative, n));
    out.force = n * normalForce;
    result.normalForce += normalForce;
    centre += out.point.x * weight;
    meanDirection += n * weight;
  }

  meanDirection = normalized(meanDirection);
  if (!(law.friction > 0.0) || !(law.tangentialStiffness > 0.0) ||
      !(lengthSquared(meanDirection) > 0.5))
    return result;
  const double tangentialDamping =
      2.0 * law.dampingRatio * std::sqrt(law.tangentialStiffness * effectiveMass);

  // Sliding: the spring at the contact centre, turned into the current tangent plane at its
  // length, stretched by the tangential relative velocity there.
  const Vec3 relative = first.velocityAt(centre) - second.velocityAt(centre);
  const Vec3 slidingVelocity = relative - meanDirection * dot(relative, meanDirection);
  const double previousLength = length(previous.displacement);
  Vec3 displacement =
      previous.displacement - meanDirection * dot(previous.displacement, meanDirection);
  const double projectedLength = length(displacement);
  displacement = projectedLength > 0.0 ? displacement * (previousLength / projectedLength) : Vec3{};
  displacement += slidingVelocity * timeStep;
  Vec3 tangential = displacement * -law.tangentialStiffness - slidingVelocity * tangentialDamping;
  const double limit = law.friction * result.normalForce;
  const double magnitude = length(tangential);
  if (magnitude > limit) {
    tangential = magnitude > 0.0 ? tangential * (limit / magnitude) : Vec3{};
    displacement = tangential * (-1.0 / law.tangentialStiffness);
    result.sliding = true;
  }
  result.spring.displacement = displacement;

  // Twisting: the points' tangential springs turned about the normal through the centre, a
  // torsion spring of stiffness k_t·Σwᵢ|rᵢ|² (rᵢ the points' offsets in the tangent plane),
  // cut at the Coulomb limit μ·F·Σwᵢ|rᵢ|. One point, or points on a line through the centre
  // along which the body turns, have no arm and no twist.
  double polarMoment = 0.0, meanArm = 0.0;
  for (PointForce& out : result.points) {
    if (!(out.depth > 0.0)) continue;
    const double weight = out.depth / depthSum;
    const Vec3 arm = out.point.x - centre;
    const Vec3 planar = arm - meanDirection * dot(arm, meanDirection);
    polarMoment += weight * lengthSquared(planar);
    meanArm += weight * length(planar);
  }
  double torque = 0.0;
  if (polarMoment > 0.0) {
    const double spin = dot(first.angularVelocity - second.angularVelocity, meanDirection);
    double twist = previous.twist + spin * timeStep;
    const double torsionStiffness = law.tangentialStiffness * polarMoment;
    torque = -torsionStiffness * twist - tangentialDamping * polarMoment * spin;
    const double torqueLimit = law.friction * result.normalForce * meanArm;
    if (std::fabs(torque) > torqueLimit) {
      torque = std::copysign(torqueLimit, torque);
      twist = -torque / torsionStiffness;
      result.sliding = true;
    }
    result.spring.twist = twist;
  }

  // Shared by the points: the sliding force by depth, the twisting torque as forces along
  // n × rᵢ whose sum is zero (Σwᵢrᵢ = 0 about the weighted centre) and whose moment is the torque.
  for (PointForce& out : result.points) {
    if (!(out.depth > 0.0)) continue;
    const double weight = out.depth / depthSum;
    out.force += tangential * weight;
    if (polarMoment > 0.0)
      out.force += cross(meanDirection, out.point.x - centre) * (weight * torque / polarMoment);
  }
  return result;
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
