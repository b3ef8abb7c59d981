#include "dem_warnings.h"

#include <cstdio>
#include <utility>

#include "delta/core/format.h"

namespace delta::cli {

void DemWarnings::warn(std::string text) {
  if (print_) {
    std::fprintf(stderr, "delta: warning: %s\n", text.c_str());
    std::fflush(stderr);
  }
  warnings_.push_back(std::move(text));
}

void DemWarnings::atStart(const dem::World& world) {
  const double dt = world.parameters().timeStep, suggested = world.suggestedTimeStep();
  // A relative margin: a time step set to the suggested one passes however it was rounded.
  if (suggested > 0.0 && dt > suggested * (1.0 + 1e-9))
    warn("time step " + toString(dt) + " is above the stable one " + toString(suggested) +
         " (dem::suggestedTimeStep for the stiffness and the lightest particle): contacts are "
         "resolved in too few steps, energy drifts and the state may stop being finite");
}

void DemWarnings::afterFirstStep(const dem::StepStatistics& statistics) {
  if (statistics.overlappingContacts > 0)
    warn("particles start overlapping: " + std::to_string(statistics.overlappingContacts) +
         " contact points where surfaces interpenetrate after the first step; the contact law "
         "pushes them apart with energy from nothing (place particles at least 2ε apart)");
}

}  // namespace delta::cli
