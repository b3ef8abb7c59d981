#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "delta/core/contact_point.h"
#include "delta/core/sphere.h"
#include "delta/core/vec3.h"
#include "delta/query/overlap.h"

/// @file
/// The DEM contact laws, per particle pair: the seed's spring–dashpot on the ε-shell (the point
/// law, ContactModel::point, the default) and an energy-conserving law on the overlap volume
/// (the volume law, ContactModel::volume; at the end of this comment).
///
/// **The point law.** Two bodies are in contact where their surfaces come closer than 2ε. Each
/// contact point i (after filter(h)) has a depth δᵢ = 2ε − distanceᵢ into the soft shell, and a
/// unit direction nᵢ from the second body toward the first (ContactPoint::direction). The pair's
/// normal law is a linear spring on its deepest point plus a dashpot:
///
///     F = k·δ_max − c·v_n,   c = 2ζ√(k·m_eff),   m_eff = m₁m₂/(m₁+m₂) (or m₁ against an obstacle)
///
/// shared among the pair's m points that are inside the shell (δᵢ > 0): the spring in
/// proportion to their depths, wᵢ = δᵢ / Σδⱼ, the dashpot equally, fᵢ = wᵢ·k·δ_max −
/// (c/m)·v_n,ᵢ, never attractive:
///
///     Fᵢ = max(0, fᵢ)·s along nᵢ,   s = max(0, Σfⱼ) / Σmax(0, fⱼ)   (s = 1 where no fⱼ < 0)
///
/// v_n,ᵢ is the relative velocity of the first body with respect to the second at xᵢ, along nᵢ
/// (negative while approaching). Why this sharing: the pair's total is max(0, k·δ_max − c·v̄_n),
/// v̄_n the points' mean, whatever the number of points (where shallow points' shares are negative
/// while the bodies separate, the others carry them: cut at zero point by point, they left the
/// pair under-damped, an icosphere on a floor rebounding at 0.123 for e = 0.1), so the pair is
/// one linear spring–dashpot and its restitution is e however many triangle pairs touch (a full
/// spring per point would stiffen a contact as its region grows and spreads over more points;
/// splitting k equally would make the force jump when a point appears). A point enters with δ = 0
/// and so with no spring force: the spring stays continuous. Deeper points carry more: a particle
/// tilted on a floor is pushed back. The dashpot is split equally so that a point that has just
/// entered damps its own motion at once (depth weights left a particle rocking onto a new point
/// nearly undamped).
///
/// The dashpot jumps to full strength when the surfaces cross the shell; velocity Verlet applies
/// a force for the step centred on its evaluation, so the first evaluation of a contact charges
/// the dashpot only for the part of that step spent in contact (0.5 + δ/(|v_n|·dt), see the
/// source). Without it the measured restitution varied by ±1.7% with where the crossing fell
/// between two steps; with it, within 0.42% for e ≥ 0.5 at thirty steps a contact (the error of
/// the time step grows with the damping: −1.7% at e = 0.1, −2.4% at 0.05; docs/guide.md).
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
///
/// The point law is not conservative: its spring acts on the deepest point, whose depth jumps as
/// points come and go, and its directions are the faces' (an elastic, frictionless settle of 27
/// granulates gains energy step after step). The volume law is.
///
/// **The volume law** (Feng, "An energy-conserving contact theory for discrete element
/// modelling of arbitrarily shaped particles", CMAME 373, 2021). Two triangulated bodies A (the
/// pair's first) and B are in contact where their closed meshes overlap (no ε-shell: the
/// surfaces must cross). Per connected region of A ∩ B (contactdetection::overlap), with its
/// volume V, centroid x_c, area vector S = ∫ n dA over ∂A inside B (pointing from A into B) and
/// moment M about x_c, the potential is
///
///     w(V) = ½·κ·V²,   κ = k / (π·r_min²)²
///
/// r_min the smaller of the two bodies' equivalent radii (of the sphere of the same volume; the
/// particle's against an obstacle). The spring's force on B is F = κ·V·S, its torque on B about
/// B's centre c_B is κ·V·(M + (x_c − c_B) × S), and A gets the opposites: exactly −∂w/∂(pose of
/// B), so the elastic, frictionless law conserves energy up to the integrator's error, and
/// whatever the triangulation (V, S and M are integrals of the solid, not of its facets).
/// κ makes a contact over a whole cross-section, |S| = π·r², as stiff as the point law's spring
/// k (dF/dx = κ·|S|²). Real overlaps are far smaller, so the law is softer than k where it acts
/// and the point law's suggestedTimeStep(k, m) is a safe step for it too: the pair's stiffness
/// dF/dδ = κ·(|S|² + V·d|S|/dδ) of a sphere pressed into a wall is 5% of k at a depth of a tenth
/// of its radius, 40% at three tenths, and k only once it is sunk to its centre. (A particle
/// whose largest cross-section exceeds π·r_min², as an elongated one's does, could exceed k at
/// such depths; the scenarios' granulates, semi-axes ratios ≥ 0.6, by at most 1.18² ≈ 1.4×.) The
/// same k therefore lets bodies sink deeper than the point law's ε: head-on, two spheres stop at δ
/// = √(2rε) (w = k·δ⁴/(8r²)), about 0.3·r in the scenarios, and their contact lasts about five
/// times as long (scenarios.h).
///
/// Damping (Feng's universal damping: in the energy coordinate q = √(2w) the contact is a
/// harmonic oscillator): a dashpot along n = S/|S| at the centroid,
///
///     c = 2ζ·√(m_eff)·|F_spring|/√(2w) = 2ζ·√(m_eff·κ)·|S|
///
/// with ζ = dampingRatio(e) as for the point law (in q the kinetic energy is
/// ½·m_eff/(κ·|S|²)·q̇², so this c is the oscillator's damping ratio ζ however |S| changes; the
/// two-particle scenario measures e = 0.4999 and 0.9000 for 0.5 and 0.9), and v_n the relative
/// normal velocity of B with respect to A at x_c; the normal force κ·V·|S| − c·v_n is clamped at 0
/// (never attractive; the spring's couple κ·V·M stays). c grows from 0 with |S|, so the dashpot
/// needs no onset correction. Friction: the point law's tangential spring at the centroid of the
/// pair's largest region with its normal n, Coulomb limit μ·(the pair's summed normal force); its
/// torsion spring takes the overlap's contact patch as a disc of area |S| (polar moment |S|/(2π)
/// per unit area, mean arm ⅔·√(|S|/π)). The elastic energy is Σ w(V) over the regions.
///
/// The potential is per region, as each region is a contact of its own: where the overlap of a
/// pair splits in two (or two regions merge), w jumps by κ·V₁·V₂ and the force jumps with it, so
/// energy is conserved exactly only while each pair's overlap keeps its number of regions. Two
/// convex bodies' overlap is convex, one region always: with convex particles (the scenarios'
/// granulates) give concave obstacles as convex pieces, each an obstacle of its own
/// (scenarios.h: openBoxWalls, funnelWalls). One closed tray instead, whose floor meets its walls
/// at concave edges, made a granulate's overlap split at the corners, and an elastic settle's
/// energy jump by up to 1.4% in a step.
///
/// Faces pressed flat on one another: V of a slab of depth d between faces of side L shrinks
/// as the bodies slide apart (by d·L per unit of slide), so the law pushes them sideways with
/// d/L of its normal force, away from the aligned position: a frictionless stack of aligned
/// cubes is unstable under it (an audit's three cubes 2 cm across, started aligned: 3.6 cm
/// apart after 20,000 steps, the middle one spinning), where friction holds it (μ = 0.5: 5.6e-5
/// m of creep). Exactly aligned, the sideways derivative is two-sided and overlap() answers
/// their mean (no push); a rounding's tilt picks one side.
///
/// The volume law needs closed, consistently oriented meshes that do not cross themselves: a
/// World refuses sphere particles, open obstacles and self-intersecting meshes with it.

namespace delta::dem {

/// Which contact law a World uses (the file comment).
///
/// Threading: a value type.
enum class ContactModel : std::uint8_t {
  point,   ///< the seed's spring–dashpot on the deepest point of the ε-shell (default)
  volume,  ///< Feng's energy-conserving law on the overlap volume
};

/// "point" or "volume".
///
/// Threading: a pure function.
const char* contactModelName(ContactModel model) noexcept;

/// The ContactModel contactModelName() names `text`; nullopt for anything else.
///
/// Threading: a pure function.
std::optional<ContactModel> parseContactModel(std::string_view text) noexcept;

/// The ContactModel named `name` ("point" or "volume"); throws delta::Error naming it otherwise.
///
/// Threading: a pure function.
ContactModel contactModelNamed(const std::string& name);

/// The contact law's constants, resolved from a World's parameters.
///
/// Threading: a value type; no shared state.
struct ContactLaw {
  double epsilon = 0.0;              ///< ε: contact below a gap of 2ε
  double stiffness = 0.0;            ///< k, normal spring per pair (force / length)
  double dampingRatio = 0.0;         ///< ζ, from the restitution by dampingRatio()
  double friction = 0.0;             ///< μ, Coulomb coefficient (0: frictionless)
  double tangentialStiffness = 0.0;  ///< k_t
  ContactModel model = ContactModel::point;
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
  /// A pure moment on the first body besides `force` (the second gets −couple): the volume
  /// law's κ·V·M and torsion; zero in the point law.
  Vec3 couple;
  double volume = 0.0;  ///< the volume law's overlap V; 0 in the point law
};

/// What the law gives a pair besides its points' forces.
///
/// Threading: a value type; no shared state.
struct PairForceSummary {
  TangentialSpring spring;    ///< to keep for the next step (zero without friction)
  double normalForce = 0.0;   ///< Σ of the normal components |Fᵢ|
  double deepest = 0.0;       ///< δ_max (the volume law: the largest V/|S|)
  double springEnergy = 0.0;  ///< ½·k·δ_max² (the volume law: Σ ½·κ·V²)
  bool sliding = false;       ///< the tangential force is at the Coulomb limit
};

/// The law applied to one pair's contact points.
///
/// Threading: a value type; no shared state.
struct PairForces : PairForceSummary {
  std::vector<PointForce> points;  ///< one per contact point, in input order
};

/// The law applied to a pair of one contact point, held without a buffer (a World's sphere
/// pairs, whose forces it keeps in one array rather than a buffer a pair).
///
/// Threading: a value type; no shared state.
struct OnePointForces : PairForceSummary {
  PointForce point;
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

/// pairForces into `result`, the same values, its buffer of points reused: a World's loop over
/// its pairs allocates nothing once a pair has seen as many points.
///
/// Threading: as pairForces; `result` is the caller's.
void pairForces(std::span<const ContactPoint> points, const BodyMotion& first,
                const BodyMotion& second, double effectiveMass, const TangentialSpring& previous,
                double timeStep, const ContactLaw& law, PairForces& result);

/// The dashpots of a pair of effective mass m_eff: c = 2ζ√(k·m_eff) and c_t = 2ζ√(k_t·m_eff).
///
/// Threading: a value type; no shared state.
struct PairDamping {
  double normal = 0.0;
  double tangential = 0.0;
};
/// A pair's PairDamping, as pairForces computes it.
///
/// Threading: a pure function.
PairDamping pairDamping(const ContactLaw& law, double effectiveMass) noexcept;

/// What the batched one-point law (sphereSphereForces, onePointForces) reads of a pair besides
/// its geometry: the bodies' motions, the pair's dashpots (pairDamping of its effective mass:
/// the same for every pair of two shapes), its spring from the step before, and where its
/// forces go.
///
/// Threading: a value type; `result` is the caller's.
struct OnePointLaw {
  const BodyMotion* firstMotion = nullptr;
  const BodyMotion* secondMotion = nullptr;
  PairDamping damping;
  const TangentialSpring* previous = nullptr;  ///< null: none (a new contact)
  OnePointForces* result = nullptr;
};

/// A pair of spheres for sphereSphereForces.
///
/// Threading: a value type.
struct SpherePair {
  const Sphere* first = nullptr;
  const Sphere* second = nullptr;
  OnePointLaw law;
};

/// The point law of pairs of spheres, straight from their centres (a World's sphere particles):
/// for each pair, the one point and its forces that pairForces gives for sphereSphereContacts'
/// point (narrow_phase.h: x halfway between the surfaces on the line of centres, the direction
/// from the second centre toward the first, +x for concentric ones), computed with one square
/// root and one division for the point (equal to rounding rather than bit for bit), into
/// `*pairs[i].law.result` with touching[i] = true; touching[i] = false (the result untouched) where
/// the gap between the surfaces is 2ε or more. A pair's answer does not depend on the others
/// in the call. Unscaled: centres more than about 1e154 apart are apart. `touching` must be as
/// long as `pairs`.
///
/// Threading: a pure function on its arguments; the results must be distinct.
void sphereSphereForces(std::span<const SpherePair> pairs, double timeStep, const ContactLaw& law,
                        std::span<bool> touching) noexcept;

/// A pair of one contact point for onePointForces: the point (its direction a unit vector, its
/// gap below 2ε, as the sphere queries give them).
///
/// Threading: a value type.
struct OnePointPair {
  const ContactPoint* point = nullptr;
  OnePointLaw law;
};

/// The point law of pairs of one contact point each (a World's spheres against the obstacles):
/// for each, what pairForces gives its point, equal to rounding (the general law's sums of one
/// term left out), into `*pairs[i].law.result` (its point a copy of `*pairs[i].point`, which
/// may be the result's own). A pair's answer does not depend on the others in the call, and is the
/// same arithmetic as sphereSphereForces' once the point is known.
///
/// Threading: a pure function on its arguments; the results must be distinct.
void onePointForces(std::span<const OnePointPair> pairs, double timeStep,
                    const ContactLaw& law) noexcept;

/// The volume law's κ = k / (π·r_min²)² for a pair whose smaller equivalent radius (of the sphere
/// of the same volume) is `smallestRadius`. Not validated.
///
/// Threading: a pure function.
double volumeStiffness(double stiffness, double smallestRadius) noexcept;

/// The radius of the sphere of volume `volume`: ∛(3V/4π).
///
/// Threading: a pure function.
double equivalentRadius(double volume) noexcept;

/// The volume law (file comment) applied to one pair's overlap regions, as
/// contactdetection::overlap(first's mesh, second's mesh) gives them (world frame; the first
/// body's surface is A). One PointForce per region with a positive area vector, in input order:
/// `point.x` the region's centroid, `point.direction` = −S/|S| (from the second body toward the
/// first, as the point law's), `point.overlap` true, `depth` = V/|S| (the mean depth), `volume`
/// V, `force` and `couple` on the first body (the torque on the first body about its centre c₁ is
/// (x − c₁) × force + couple; the second gets the opposites). Friction acts at the largest
/// region's centroid with its normal, limited by the pair's summed normal force. `volumeStiffness`
/// is κ (volumeStiffness()); the rest as pairForces. No regions give no forces and zero springs.
/// Pure: does not validate.
///
/// Threading: a pure function; may be called from any number of threads at once.
PairForces volumePairForces(std::span<const contactdetection::OverlapRegion> regions,
                            const BodyMotion& first, const BodyMotion& second, double effectiveMass,
                            double volumeStiffness, const TangentialSpring& previous,
                            double timeStep, const ContactLaw& law);

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
/// for the rotational inertia of off-centre contacts. The same step serves the volume law,
/// whose stiffness stays below k (file comment). Not validated, as contactDuration.
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
