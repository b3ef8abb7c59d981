#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "delta/core/vec3.h"
#include "delta/dem/world.h"
#include "delta/mesh/mesh.h"

/// @file
/// Built-in DEM scenarios, ready to run, in SI units: granulates of about a centimetre
/// (primitives::granulate, 42 points, 80 triangles, semi-axes r·(1, a, b) with a, b drawn in
/// [0.6, 1], r = 1 cm), density 2500 kg/m³, ε = r/20, h = r/4.
///
/// Each scenario sets the stiffness from the fastest impact it expects (a free fall onto the
/// floor, or the two-particle approach speed) so that an undamped impact of the
/// heaviest particle on a wall stops at depth ε, half the shell: the surfaces never touch. The
/// time step is then World::suggestedTimeStep() (about thirty steps a contact).
///
/// Threading: each function builds a new World from nothing shared; any number of threads may
/// call them at once.

namespace delta::dem {

/// A World ready to run with what to run it for.
///
/// Threading: as World.
struct Scenario {
  std::string name;
  World world;
  std::size_t steps = 0;           ///< a sensible run at world.parameters().timeStep
  std::size_t outputInterval = 1;  ///< steps between frames for about a hundred frames
};

/// Two icospheres (3 subdivisions, 1280 triangles, radius 1 cm) approaching along x at a
/// relative speed of 1 m/s, no gravity, starting 1 mm (r/10) outside each other's shells. The
/// second is shifted along y by `offsetFraction` times the sum of the radii (0: head-on; toward
/// 1: grazing). Runs until well after they separate. `model`: the contact law (either works;
/// with the volume law, at the same k, the spheres sink √(2rε) ≈ 0.32·r into each other, and the
/// run is longer by as much as the contact is: about five times).
/// Throws delta::Error unless 0 ≤ e ≤ 1, 0 ≤ offsetFraction < 1 and friction ≥ 0.
Scenario twoParticles(double restitution = 0.9, double offsetFraction = 0.0, double friction = 0.0,
                      ContactModel model = ContactModel::point);

/// `count` granulates (default 100), randomly shaped and turned (from `seed`), on a lattice in
/// an open-top box whose floor is a little wider than the lattice, falling under gravity and
/// settling (e = 0.5, μ = 0.5). Runs for twice the fall time of the top layer plus 0.1 s.
/// Throws delta::Error for count = 0.
///
/// `kind` = ParticleKind::Sphere puts spheres in their place, for comparing costs: one sphere
/// shape whose volume is the mean volume of the granulates drawn for that seed (the same mass
/// flows), on the same lattice with the same jitter, in the same box; ε, h, e and μ are the
/// same, and the stiffness and time step follow the same rules from the sphere's mass.
///
/// `model` = ContactModel::volume (which needs closed obstacles and mesh particles: a sphere
/// kind is refused) makes the box openBoxWalls, r thick: the same inner faces, as five closed
/// convex obstacles. The stiffness k and time step
/// are the point law's (contact_model.h: κ = k/(π·r_min²)²); impacts then sink deeper than ε
/// (about √(rε) for a sphere on the floor).
Scenario settle(std::size_t count = 100, std::uint64_t seed = 1,
                ParticleKind kind = ParticleKind::Mesh, ContactModel model = ContactModel::point);

/// `count` granulates (default 1000) on a lattice just above a conical funnel (walls at 60° to
/// the horizontal, outlet radius 4.5 r, 10 r above a floor), flowing through it onto the floor
/// (e = 0.5, μ = 0.3). The stiffness is set for the first particles through the outlet, which
/// fall from the lattice's first layer to the floor; later ones land on particles. Runs for
/// 0.5 s (tens of thousands of steps: the flow has started; draining 1000 takes seconds).
/// Construction is O(count). Throws delta::Error for count = 0.
///
/// `kind` = ParticleKind::Sphere: spheres of the granulates' mean volume instead, with the same
/// lattice, funnel and floor and the same rules as settle() states.
///
/// `model` = ContactModel::volume: the funnel as funnelWalls (48 closed convex obstacles, r thick)
/// and the floor a box r thick whose top is the floor.
Scenario hopper(std::size_t count = 1000, std::uint64_t seed = 1,
                ParticleKind kind = ParticleKind::Mesh, ContactModel model = ContactModel::point);

/// An open-top box: a floor of `width` × `depth` at height `floor`, centred on the z axis, and
/// four walls `height` high; 10 triangles, normals inward. An obstacle for World::addObstacle.
/// Throws delta::Error for a size that is not finite and positive or a floor that is not finite.
Mesh openBox(double width, double depth, double height, double floor = 0.0);

/// A funnel about the z axis: the side of a truncated cone from radius `outletRadius` at height
/// `outletHeight` up to `topRadius` at `topHeight`, open at both ends, `segments` (≥ 3) around
/// and `rows` (≥ 1) up, 2·segments·rows triangles, normals toward the axis. Rows keep the
/// triangles, and so their boxes, near the particles' size: a long strip's box would reach
/// into the funnel and send every particle there to the triangle kernels. Throws delta::Error
/// for non-positive radii, too few segments or rows, or topHeight ≤ outletHeight.
Mesh funnel(double outletRadius, double topRadius, double outletHeight, double topHeight,
            int segments = 48, int rows = 12);

/// openBox made solid for the volume contact law, which needs closed meshes: five boxes
/// `thickness` thick whose inner faces are openBox's (a floor slab under the floor, as wide as
/// the walls' outsides, and four walls on it, touching and not overlapping), 12 triangles each.
/// Convex pieces, as obstacles of their own: a convex particle's overlap with each is one region,
/// so the volume law's energy stays continuous (contact_model.h), where one closed tray would have
/// a particle's overlap split in two at its inner corners. Throws delta::Error as openBox does,
/// and for a thickness that is not finite and positive.
std::vector<Mesh> openBoxWalls(double width, double depth, double height, double floor,
                               double thickness);

/// funnel made solid for the volume contact law: `segments` convex pieces, each the wall between
/// two of funnel's generators (its inner face funnel's strip there) and `thickness` wider
/// outward at every height, 12 triangles each; obstacles of their own, as openBoxWalls says.
/// Throws delta::Error as funnel does, and for a thickness that is not finite and positive.
std::vector<Mesh> funnelWalls(double outletRadius, double topRadius, double outletHeight,
                              double topHeight, int segments, double thickness);

/// Measures the normal coefficient of restitution of a collision of two particles: the
/// relative velocity along the line of centres after they part over the one before they met,
/// the line taken when they first touch.
///
/// Use: make it from the World before the run, call observe() after every step.
///
/// Threading: not thread-safe; one object per run.
class RestitutionMeter {
 public:
  /// Records the particles' relative velocity now, as "before". Throws delta::Error when
  /// either particle does not exist or they are the same.
  RestitutionMeter(const World& world, std::size_t first = 0, std::size_t second = 1);
  /// The same from the particles alone, by index (e.g. DistributedWorld::gatherParticles).
  RestitutionMeter(std::span<const Particle> particles, std::size_t first = 0,
                   std::size_t second = 1);

  /// Looks at the world after a step: notes the first contact between the two particles and,
  /// once they are apart again, their relative velocity as "after".
  void observe(const World& world);
  /// The same from the particles by index and the step's contacts (e.g. a DistributedWorld's,
  /// gathered).
  void observe(std::span<const Particle> particles, std::span<const Contact> contacts);

  bool collided() const noexcept { return collided_; }
  /// They touched and are apart now.
  bool separated() const noexcept { return separated_; }
  /// |v_after · n| / |v_before · n|; NaN until separated().
  double restitution() const noexcept;

 private:
  std::size_t first_, second_;
  Vec3 before_, after_, lineOfCentres_;
  bool collided_ = false, separated_ = false;
};

}  // namespace delta::dem
