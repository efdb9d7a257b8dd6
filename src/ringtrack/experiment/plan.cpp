#include "ringtrack/experiment/plan.hpp"

#include <algorithm>

#include "ringtrack/core/error.hpp"
#include "ringtrack/sim/scenario_file.hpp"

namespace ringtrack::experiment {

bool PlannedRun::moving() const {
  return scenario.sensor.motion != sim::SensorMotion::kStatic;
}

std::string PlannedRun::stem() const {
  std::string s = validation ? "V-" + scenario.name : std::to_string(scenario.number);
  s += moving() ? "-moving" : "-static";
  return s;
}

std::vector<PlannedRun> plan_runs(const PlanOptions& options) {
  if (options.duration_s && !(*options.duration_s > 0)) {
    throw core::ConfigError("duration must be > 0 s");
  }
  std::vector<PlannedRun> runs;
  const auto add = [&](sim::Scenario s, bool validation) {
    if (options.duration_s) s.duration_s = *options.duration_s;
    const bool scripted = s.sensor.motion == sim::SensorMotion::kScripted;
    sim::Scenario still = s;
    still.sensor.motion = sim::SensorMotion::kStatic;
    if (options.with_static) runs.push_back({still, validation});
    if (options.with_moving) {
      runs.push_back({scripted ? s : sim::with_moving_sensor(still), validation});
    }
  };
  const bool with_builtins = options.scenario_files.empty() || options.builtins_given;
  if (with_builtins) {
    for (const int number : options.builtins) {
      add(sim::builtin_scenario(std::to_string(number)), false);
    }
  }
  for (const std::string& f : options.scenario_files) add(sim::load_scenario_file(f), true);
  for (const PlannedRun& r : runs) sim::validate(r.scenario, r.scenario.name);
  return runs;
}

std::vector<std::string> scenario_files_in(const std::filesystem::path& dir) {
  std::vector<std::string> out;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (e.is_regular_file() && e.path().extension() == ".yaml") out.push_back(e.path().string());
  }
  if (ec || out.empty()) {
    std::string why = dir.string() + ": no scenario files (*.yaml) found";
    if (ec) why.append(": ").append(ec.message());
    throw core::InputError(why);
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace ringtrack::experiment
