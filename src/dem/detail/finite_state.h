// What "finite" means for the state a DEM checkpoint holds: one list of fields, read by the
// checkpoint reader (which refuses a file holding anything else) and by World's check after each
// step (which refuses to end a step with anything else), so that every checkpoint a World writes
// reads back.
#pragma once

#include <cmath>

#include "delta/core/rotation.h"
#include "delta/core/vec3.h"
#include "delta/dem/contact_model.h"
#include "delta/dem/world.h"

namespace delta::detail {

/// Every field of a particle a checkpoint holds is finite (its shape index aside).
inline bool holdsFiniteState(const dem::Particle& p) noexcept {
  const Quaternion& q = p.orientation;
  return isFinite(p.position) && isFinite(p.velocity) && isFinite(p.angularVelocity) &&
         isFinite(p.angularMomentum) && isFinite(p.force) && isFinite(p.torque) &&
         std::isfinite(q.w) && std::isfinite(q.x) && std::isfinite(q.y) && std::isfinite(q.z);
}

/// A friction spring's displacement and twist are finite.
inline bool holdsFiniteState(const dem::TangentialSpring& spring) noexcept {
  return isFinite(spring.displacement) && std::isfinite(spring.twist);
}

}  // namespace delta::detail
