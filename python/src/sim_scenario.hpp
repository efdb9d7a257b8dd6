#pragma once
// Scenario lookup shared by the simulator and experiment bindings.

#include <optional>
#include <string>

#include "ringtrack/sim/scenario.hpp"

namespace ringtrack::python {

/// A built-in scenario by number or name, or a scenario file (.yaml); duration replaced when
/// given; moving puts a static sensor on its figure 8. Validated.
sim::Scenario scenario_from(const std::string& name_or_file, std::optional<double> duration_s,
                            bool moving);

}  // namespace ringtrack::python
