#pragma once
// The checks of SimulatorOptions, one place for every simulator that takes them (Simulator,
// BatchSimulator).
#include <stabint/simulator.hpp>

namespace stabint {

/// Throws InvalidInputError ("simulator options: ...") naming the first bad option.
void validateOptions(const SimulatorOptions& options);

}  // namespace stabint
