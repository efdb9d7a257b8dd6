// libFuzzer target: scenario YAML (parse_scenario_yaml, validate, the world's solids and
// footprints) and scripted-trajectory CSV (parse_trajectories_csv), both on the whole input.
// Oracle: what was accepted formats to text that parses back to the same text.
#include <cstdint>
#include <string>

#include "fuzz_support.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/scenario_file.hpp"

using namespace ringtrack;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fuzz::expect_errors([&] {
    const sim::Scenario s = sim::parse_scenario_yaml(text, "fuzz.yaml");
    sim::validate(s, "fuzz.yaml");
    (void)sim::static_primitives(s);
    (void)sim::ground_footprints(s);
    const std::string formatted = sim::format_scenario_yaml(s);
    fuzz::must_succeed([&] {
      const sim::Scenario again = sim::parse_scenario_yaml(formatted, "formatted.yaml");
      fuzz::require(sim::format_scenario_yaml(again) == formatted, "scenario round trip");
    });
  });
  fuzz::expect_errors([&] {
    const auto actors = sim::parse_trajectories_csv(text, "fuzz.csv");
    const std::string formatted = sim::format_trajectories_csv(actors);
    fuzz::must_succeed([&] {
      const auto again = sim::parse_trajectories_csv(formatted, "formatted.csv");
      fuzz::require(sim::format_trajectories_csv(again) == formatted, "trajectories round trip");
    });
  });
  return 0;
}
