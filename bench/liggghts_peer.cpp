#include "liggghts_peer.h"

#include <mpi.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "delta/dem/contact_model.h"

#include "library.h"  // LIGGGHTS' (and LAMMPS') library interface

namespace delta::bench {
namespace {

/// MPI for LIGGGHTS: initialised on first use, finalised at exit (after every LIGGGHTS instance
/// is closed: instances are closed by their destructors, which run before this static's).
struct MpiSession {
  bool ownsMpi = false;
  MpiSession() {
    int initialized = 0;
    MPI_Initialized(&initialized);
    if (!initialized) {
      int provided = 0;
      MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
      ownsMpi = true;
    }
  }
  ~MpiSession() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (ownsMpi && !finalized) MPI_Finalize();
  }
};

void ensureMpi() {
  static const MpiSession session;
}

std::string format(const char* pattern, auto... values) {
  char text[512];
  std::snprintf(text, sizeof text, pattern, values...);
  return text;
}

}  // namespace

struct LiggghtsSpheres::State {
  void* lammps = nullptr;
  std::size_t count = 0;
  bool setUp = false;

  void command(const std::string& text) const {
    lammps_command(lammps, const_cast<char*>(text.c_str()));
  }
  const double* positions() const {
    auto** x = static_cast<double**>(lammps_extract_atom(lammps, const_cast<char*>("x")));
    return x[0];
  }
};

LiggghtsSpheres::LiggghtsSpheres(const dem::World& world, const Aabb& box, double skin)
    : state_(std::make_unique<State>()) {
  ensureMpi();
  const dem::Parameters& parameters = world.parameters();
  const std::span<const dem::Particle> particles = world.particles();
  if (particles.empty() || parameters.contactModel != dem::ContactModel::point)
    throw std::runtime_error("LiggghtsSpheres: a world of spheres under the point law");
  const dem::ParticleShape& shape = world.shapes()[particles.front().shape];
  for (const dem::Particle& particle : particles)
    if (particle.shape != particles.front().shape || !shape.isSphere())
      throw std::runtime_error("LiggghtsSpheres: spheres of one shape only");

  State& s = *state_;
  s.count = particles.size();
  const double radius = shape.boundingRadius() + parameters.epsilon;  // LIGGGHTS' radius
  const double e = parameters.epsilon;
  const Aabb walls{box.lower + Vec3{e, e, e}, box.upper - Vec3{e, e, 0.0}};  // moved ε inward
  if (skin <= 0.0) skin = 0.25 * shape.boundingRadius();

  const char* arguments[] = {"liggghts", "-screen", "none", "-log", "none"};
  lammps_open(5, const_cast<char**>(arguments), MPI_COMM_SELF, &s.lammps);
  if (!s.lammps) throw std::runtime_error("LiggghtsSpheres: lammps_open failed");

  const double mass = shape.mass();
  const double zeta = dem::dampingRatio(parameters.restitution);
  const double k = parameters.stiffness;
  const double kt = parameters.tangentialStiffnessRatio * k;
  // Damping per unit effective mass (absolute_damping off): type pair 1–1 is two spheres
  // (m_eff = m/2), 1–2 a sphere and a wall (m_eff = m).
  const double gammaPair = 2.0 * zeta * std::sqrt(k / (0.5 * mass));
  const double gammaWall = 2.0 * zeta * std::sqrt(k / mass);
  const double gammatPair = 2.0 * zeta * std::sqrt(kt / (0.5 * mass));
  const double gammatWall = 2.0 * zeta * std::sqrt(kt / mass);
  // A density that gives Δ's mass at LIGGGHTS' radius r + ε.
  const double density = mass / (4.0 / 3.0 * std::numbers::pi * std::pow(radius, 3));

  Aabb domain = box;
  for (const dem::Particle& particle : particles)
    domain.extend(particle.position);
  const Vec3 margin{4.0 * radius, 4.0 * radius, 4.0 * radius};
  domain.lower -= margin;
  domain.upper += margin;

  s.command("atom_style granular");
  s.command("atom_modify map array");
  s.command("boundary f f f");
  s.command("newton off");
  s.command("communicate single vel yes");
  s.command("units si");
  s.command(format("region domain block %.17g %.17g %.17g %.17g %.17g %.17g units box",
                   domain.lower.x, domain.upper.x, domain.lower.y, domain.upper.y, domain.lower.z,
                   domain.upper.z));
  s.command("create_box 2 domain");
  s.command(format("neighbor %.17g bin", skin));
  s.command("neigh_modify delay 0");
  s.command(format("fix m1 all property/global kn peratomtypepair 2 %.17g %.17g %.17g %.17g", k, k,
                   k, k));
  s.command(format("fix m2 all property/global kt peratomtypepair 2 %.17g %.17g %.17g %.17g", kt,
                   kt, kt, kt));
  s.command(format("fix m3 all property/global gamman peratomtypepair 2 %.17g %.17g %.17g %.17g",
                   gammaPair, gammaWall, gammaWall, gammaWall));
  s.command(format("fix m4 all property/global gammat peratomtypepair 2 %.17g %.17g %.17g %.17g",
                   gammatPair, gammatWall, gammatWall, gammatWall));
  const double mu = parameters.friction;
  s.command(format(
      "fix m5 all property/global coefficientFriction peratomtypepair 2 %.17g %.17g %.17g %.17g",
      mu, mu, mu, mu));
  s.command("pair_style gran model hooke/stiffness tangential history limitForce on");
  s.command("pair_coeff * *");
  s.command(format("timestep %.17g", parameters.timeStep));
  const Vec3 g = parameters.gravity;
  const double gravity = length(g);
  if (gravity > 0.0)
    s.command(format("fix gravity all gravity %.17g vector %.17g %.17g %.17g", gravity,
                     g.x / gravity, g.y / gravity, g.z / gravity));
  const auto wall = [&](const char* id, const char* plane, double at) {
    s.command(
        format("fix %s all wall/gran model hooke/stiffness tangential history primitive "
               "type 2 %s %.17g limitForce on",
               id, plane, at));
  };
  wall("floor", "zplane", walls.lower.z);
  wall("xlow", "xplane", walls.lower.x);
  wall("xhigh", "xplane", walls.upper.x);
  wall("ylow", "yplane", walls.lower.y);
  wall("yhigh", "yplane", walls.upper.y);
  s.command("fix integrate all nve/sphere");
  for (const dem::Particle& particle : particles)
    s.command(format("create_atoms 1 single %.17g %.17g %.17g units box", particle.position.x,
                     particle.position.y, particle.position.z));
  s.command(format("set group all diameter %.17g density %.17g", 2.0 * radius, density));
  s.command("thermo 1000000000");
  const auto atoms =
      *static_cast<std::int64_t*>(lammps_extract_global(s.lammps, const_cast<char*>("natoms")));
  if (atoms != static_cast<std::int64_t>(s.count))
    throw std::runtime_error("LiggghtsSpheres: LIGGGHTS made " + std::to_string(atoms) +
                             " atoms of " + std::to_string(s.count));
  // Velocities and angular velocities by atom id (1 … count, in the World's order).
  std::vector<double> values(3 * s.count);
  for (std::size_t i = 0; i < s.count; ++i) {
    const Vec3& v = particles[i].velocity;
    values[3 * i] = v.x, values[3 * i + 1] = v.y, values[3 * i + 2] = v.z;
  }
  lammps_scatter_atoms(s.lammps, const_cast<char*>("v"), 1, 3, values.data());
  for (std::size_t i = 0; i < s.count; ++i) {
    const Vec3& w = particles[i].angularVelocity;
    values[3 * i] = w.x, values[3 * i + 1] = w.y, values[3 * i + 2] = w.z;
  }
  lammps_scatter_atoms(s.lammps, const_cast<char*>("omega"), 1, 3, values.data());
}

LiggghtsSpheres::~LiggghtsSpheres() {
  if (state_->lammps) lammps_close(state_->lammps);
}

void LiggghtsSpheres::run(std::size_t steps) {
  state_->command(format("run %zu%s", steps, state_->setUp ? " pre no post no" : " post no"));
  state_->setUp = true;
}

std::vector<Vec3> LiggghtsSpheres::positions() const {
  const double* x = state_->positions();
  std::vector<Vec3> centres(state_->count);
  for (std::size_t i = 0; i < state_->count; ++i)
    centres[i] = {x[3 * i], x[3 * i + 1], x[3 * i + 2]};
  return centres;
}

}  // namespace delta::bench
