#pragma once

#include <span>
#include <vector>

#include "delta/core/contact_point.h"
#include "delta/core/vec3.h"

/// @file
/// The DEM contact law: the seed's spring–dashpot on the ε-shell, per particle pair.
///
/// Two bodies are in contact where their surfaces come closer than 2ε. Each contact point i
/// (after filter(h)) has a depth δᵢ = 2ε − distanceᵢ into the soft shell, and a unit direction
/// nᵢ from the second body toward the first (ContactPoint::direction). The pair's normal law is a
/// linear spring on its deepest point plus a dashpot:
///
///     F = k·δ_max − c·v_n,   c = 2ζ√(k·m_eff),   m_eff = m₁m₂/(m₁+m₂) (or m₁ against an obstacle)
///
/// shared among the pair's m points that are inside the shell (δᵢ > 0): the spring in
/// proportion to their depths, wᵢ = δᵢ / Σδⱼ, the dashpot equally:
///
///     Fᵢ = max(0, wᵢ·k·δ_max − (c/m)·v_n,ᵢ) along nᵢ   (never attractive)
///
/// v_n,ᵢ is the relative velocity of the first body with respect to the second at xᵢ, along nᵢ
/// (negative while approaching). Why this sharing: the pair's total is k·δ_max − c·v_n whatever
/// the number of points, so the pair is one linear spring–dashpot and its restitution is e however
/// many triangle pairs touch (a full spring per point would stiffen a contact as its region grows
/// and spreads over more points; splitting k equally would make the force jump when a point
/// appears). A point enters with δ = 0 and so with no spring force: the spring stays continuous.
/// Deeper points carry more: a particle tilted on a floor is pushed back. The dashpot is split
/// equally so that a point that has just entered damps its own motion at once (depth weights
/// left a particle rocking onto a new point nearly undamped).
///
/// The dashpot jumps to full strength when the surfaces cross the shell; velocity Verlet applies
/// a force for the step centred on its evaluation, so the first evaluation of a contact charges
/// the dashpot only for the part of that step spent in contact (0.5 + δ/(|v_n|·dt), see the
/// source). Without it the measured restitution varied by ±1.7% with where the crossing fell
/// between two steps; with it, within 0.4% at thirty steps a contact.
///
/// Interpenetration (ContactPoint::overlap: the triangles intersect, or x lies inside both closed
/// meshes) should not happen at a stable time step — the shell keeps the surfaces apart — but is
/// defined: the depth is 2ε + distance (the force keeps growing past the shell rather than
/// vanishing), and the direction, which the faces give only roughly there, is replaced by the
/// depth-weighted mean direction of the pair's points that do not overlap, where there are any.
///
/// Friction (μ > 0): per pair, a tangential spring and a torsion spring (Cundall and Strack
/// 1979, with the stretch kept per pair rather than per point, since points come and go), both
/// kept from step to step by the caller (TangentialSpring). Each evaluation turns ξ into the
/// current tangent plane (keeping its length), adds v_t·dt (v_t the tangential relative velocity
/// at the depth-weighted contact centre), and sets F_t = −k_t·ξ − c_t·v_t, c_t = 2ζ√(k_t·m_eff);
/// where |F_t| > μ·ΣFᵢ the contact slides: F_t is cut to the Coulomb limit and ξ = −F_t / k_t.
/// The torsion spring turns by the relative spin about the mean normal; its stiffness is
/// k_t·Σwᵢ|rᵢ|² (rᵢ the points' offsets from the centre in the tangent plane), its limit
/// μ·ΣFᵢ·Σwᵢ|rᵢ| — without it a particle resting on a face could spin on it for ever. Both are
/// shared among the points: F_t by the weights wᵢ, the torque as forces along n × rᵢ that add up
/// to no force. So every force acts at a contact point, equal and opposite on the two bodies.
///
/// The damping ratio ζ comes from e for this clamped law (dampingRatio()), not from the textbook
/// e = exp(−πζ/√(1−ζ²)), which holds only if the dashpot may pull the bodies together at the end
/// of the contact (Schwager and Pöschel, Phys. Rev. E 75, 2007): that ζ would give 0.55 instead
/// of 0.5.

namespace delta::dem {

/// The contact law's constants, resolved from a World's parameters.
///
/// Threading: a value type; no shared state.
struct ContactLaw {
  double epsilon = 0.0;              ///< ε: contact below a gap of 2ε
  double stiffness = 0.0;            ///< k, normal spring per pair (force / length)
  double dampingRatio = 0.0;         ///< ζ, from the restitution by dampingRatio()
  double friction = 0.0;             ///< μ, Coulomb coefficient (0: frictionless)
  double tangentialStiffness = 0.0;  ///< k_t
};

/// Where a body is and how it moves, for the relative velocity at a contact point.
///
/// Threading: a value type; no shared state.
struct BodyMotion {
  Vec3 centre;           ///< the reference point of the velocities (a particle's centre of mass)
  Vec3 velocity;         ///< of that point
  Vec3 angularVelocity;  ///< world frame

  Vec3 velocityAt(const Vec3& x) const noexcept {
    return velocity + cross(angularVelocity, x - centre);
  }
};

/// What friction remembers of a touching pair from one step to the next.
///
/// Threading: a value type; no shared state.
struct TangentialSpring {
  Vec3 displacement;   ///< ξ: the sliding spring's stretch at the contact centre
  double twist = 0.0;  ///< θ: the torsion spring's turn about the mean normal (radians)
};

/// One contact point with the force the law puts there.
///
/// Threading: a value type; no shared state.
struct PointForce {
  ContactPoint point;  ///< as detected (world frame); its direction replaced where it overlaps
  double depth = 0.0;  ///< δ into the shell (2ε − distance; see the law for overlaps)
  Vec3 force;          ///< on the first body (the second gets −force), normal plus tangential
};

/// The law applied to one pair's contact points.
///
/// Threading: a value type; no shared state.
struct PairForces {
  std::vector<PointForce> points;  ///< one per contact point, in input order
  TangentialSpring spring;         ///< to keep for the next step (zero without friction)
  double normalForce = 0.0;        ///< Σ of the normal components |Fᵢ|
  double deepest = 0.0;            ///< δ_max
  double springEnergy = 0.0;       ///< ½·k·δ_max²
  bool sliding = false;            ///< the tangential force is at the Coulomb limit
};

/// The forces on the first body of a pair at its contact points (found by
/// contactdetection::contacts with the first body as the first mesh, filtered with filter(h)).
/// `effectiveMass` is m₁m₂/(m₁+m₂), or m₁ against an obstacle; `previous` is
/// the pair's springs from the previous step (zero for a new contact) and `timeStep` the time
/// since. No points give no forces and zero springs; points outside the shell (δ ≤ 0) get no
/// force. Overlapping points are handled as the law above says. Pure: does not validate (World
/// does, once); the ContactPoints must be finite with unit directions, as the queries give them.
///
/// Threading: a pure function; may be called from any number of threads at once.
PairForces pairForces(std::span<const ContactPoint> points, const BodyMotion& first,
                      const BodyMotion& second, double effectiveMass,
                      const TangentialSpring& previous, double timeStep, const ContactLaw& law);

/// The coefficient of restitution of the clamped linear spring–dashpot (force never attractive)
/// with damping ratio ζ ≥ 0, in closed form: the normal relative speed after a head-on impact
/// over the speed before: exp(−ζ·t*), t* the (dimensionless) time at which the force k·δ + c·δ'
/// returns to zero. 1 at ζ = 0, decreasing toward 0 as ζ grows (e⁻² at ζ = 1, ≈ 1/(4ζ²) beyond).
/// A negative ratio counts as 0.
///
/// Threading: a pure function.
double restitutionOf(double dampingRatio) noexcept;

/// The damping ratio ζ for which restitutionOf(ζ) = e, by bisection to round-off. Throws
/// delta::Error unless 0 ≤ e ≤ 1; e = 0 gives the largest ratio searched (ζ = 50, e ≈ 1e-4:
/// the clamped law never reaches 0).
///
/// Threading: a pure function.
double dampingRatio(double restitution);

/// The duration of an undamped contact of a pair with effective mass m: π√(m/k). Not
/// validated: both must be positive (NaN or ±∞ otherwise).
///
/// Threading: a pure function.
double contactDuration(double stiffness, double effectiveMass) noexcept;

/// A time step for the explicit integrator: a thirtieth of the undamped duration of a contact
/// between two of the lightest particles (effective mass m_min/2), which resolves every contact
/// in about thirty steps (energy error of velocity Verlet ≈ (ω·dt)²/8 ≈ 0.1%) and leaves room
/// for the rotational inertia of off-centre contacts. Not validated, as contactDuration.
///
/// Threading: a pure function.
double suggestedTimeStep(double stiffness, double smallestMass) noexcept;

/// The stiffness at which a body of mass m hitting a wall at `speed` stops at depth `depth` in
/// an undamped contact: k = m·speed²/depth². Scenarios set it from the fastest impact they
/// expect and a depth below 2ε, so the shell is never crossed. Not validated: a depth of 0 gives
/// +∞, a speed of 0 gives 0 (which World refuses).
///
/// Threading: a pure function.
double stiffnessForImpact(double mass, double speed, double depth) noexcept;

}  // namespace delta::dem
