#pragma once
// The band tau that tests and probes measure H - H* against: energy_tolerance (K + E_int +
// E_scale) of a step's new state (docs/method.md, section 7, takes the step's start; a step's
// report carries its end).
#include <stabint/simulator.hpp>

namespace stabint::testing {

inline double energyBand(const Simulator& sim, const StepReport& report) {
  return sim.options().energy_tolerance * (report.energy.kinetic + report.energy.elastic + sim.energyScale());
}

}  // namespace stabint::testing
