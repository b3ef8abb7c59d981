#pragma once

// LIGGGHTS 3.8 (Debian's libliggghts-dev) as the peer of Δ's sphere DEM (bench/dem_bench.cpp):
// compiled apart (bench/liggghts_peer.cpp, with LIGGGHTS' and MPI's headers), so that only this
// file sees them.

#include <cstddef>
#include <memory>
#include <vector>

#include "delta/core/aabb.h"
#include "delta/dem/world.h"

namespace delta::bench {

/// The same spheres as a Δ World of spheres in an open box, handed to LIGGGHTS through its
/// library interface (one process, MPI_COMM_SELF): positions, velocities and angular velocities
/// as the World has them, and the same contact law, as far as LIGGGHTS has it.
///
/// The law: Δ's point law between two spheres is a linear spring–dashpot on the depth
/// δ = 2ε − (|c₁ − c₂| − r₁ − r₂), never attractive, with a tangential spring k_t capped by
/// Coulomb's μ (contact_model.h). LIGGGHTS' `gran model hooke/stiffness tangential history
/// limitForce on` is the same on the overlap of spheres of radius r + ε: k_n = k, k_t = k_t, and
/// its damping coefficients (multiplied by the effective mass, absolute_damping off) set to
/// 2ζ·√(k/m_eff) and 2ζ·√(k_t/m_eff), with m_eff = m/2 between two spheres and m against a wall.
/// The box's five faces are `wall/gran` planes moved ε toward the inside (so that a sphere's
/// overlap with the plane is Δ's depth against the face). The density is set so that each
/// sphere has Δ's mass; its moment of inertia is then that of radius r + ε (a few per cent
/// larger, which a pile at rest does not feel). Not the same: Δ's first-step dashpot correction
/// (contact_model.h), and the torsion spring (zero for one point of contact anyway).
///
/// Neighbour lists: a bin size of `skin` (LIGGGHTS' `neighbor SKIN bin`, rebuilt when a sphere
/// has moved half of it; neigh_modify delay 0), by default r/4.
///
/// Threading: one object per thread; LIGGGHTS runs on the calling thread. MPI is initialised on
/// first use (MPI_THREAD_FUNNELED), and finalised at exit.
class LiggghtsSpheres {
 public:
  /// `world`: only sphere particles of one shape and a Parameters::contactModel of point;
  /// `box`: the open box's inside (its floor at box.lower.z; its walls at box.lower/upper x
  /// and y). Throws std::runtime_error where LIGGGHTS refuses a command.
  LiggghtsSpheres(const dem::World& world, const Aabb& box, double skin = 0.0);
  ~LiggghtsSpheres();
  LiggghtsSpheres(const LiggghtsSpheres&) = delete;
  LiggghtsSpheres& operator=(const LiggghtsSpheres&) = delete;

  /// Advances `steps` time steps (one LIGGGHTS `run`, setup skipped after the first).
  void run(std::size_t steps);
  /// Where the spheres' centres are now, in the World's order.
  std::vector<Vec3> positions() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace delta::bench
