// `ringtrack simulate`: runs the simulator and writes a sequence folder (docs/formats.md).

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "output_rows.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/sim/scenario_file.hpp"
#include "ringtrack/sim/simulator.hpp"
#include "stop_signals.hpp"

namespace ringtrack::cli {
namespace {

struct SimulateOptions {
  std::string scenario;
  std::string out;
  std::uint64_t seed{1};
  std::optional<double> duration_s;
  bool moving_sensor{false};
  bool list{false};
  bool overwrite{false};
  std::string sensor;
};

void list_scenarios() {
  std::cout << "built-in scenarios (add --moving-sensor or the suffix -moving for the figure-8 "
               "flight):\n";
  for (const auto& s : sim::builtin_scenarios()) {
    const auto full = sim::builtin_scenario(std::to_string(s.number));
    std::cout << "  " << s.number << "  " << std::left << std::setw(12) << s.name << std::right
              << std::setw(5) << full.duration_s << " s  " << s.description << "\n";
  }
}

void simulate_into(const SimulateOptions& o, const sim::Scenario& scenario,
                   sim::Simulator& simulator, io::SequenceWriter& writer, io::RunStatus& status);

void run_simulate(const SimulateOptions& o) {
  if (o.list) {
    list_scenarios();
    return;
  }
  if (o.scenario.empty())
    throw core::ConfigError("simulate: expected a scenario (1-7, a name or a .yaml file)");
  if (o.out.empty()) throw core::ConfigError("simulate: --out DIR is required");
  sim::Scenario scenario = sim::resolve_scenario(o.scenario);
  if (o.moving_sensor) scenario = sim::with_moving_sensor(std::move(scenario));
  if (o.duration_s) {
    if (!(*o.duration_s > 0)) throw core::ConfigError("simulate: --duration must be > 0");
    scenario.duration_s = *o.duration_s;
  }
  if (!o.sensor.empty()) scenario.sensor.model = o.sensor;
  sim::Simulator simulator(scenario, o.seed);
  // Ctrl-C or SIGTERM ends the sequence after the scan at hand, as a complete shorter sequence.
  const StopSignals stop_signals;

  io::SequenceMeta meta =
      io::SequenceMeta::for_sensor(simulator.model(), simulator.model().columns());
  meta.name = scenario.description;
  meta.scenario =
      scenario.number > 0 ? std::to_string(scenario.number) + " " + scenario.name : scenario.name;
  if (scenario.sensor.motion == sim::SensorMotion::kFigure8) meta.scenario += " (moving sensor)";
  meta.seed = o.seed;
  // The pipeline's ground (detection.sensor_height_m) for `run` on this sequence.
  meta.sensor_height_m =
      sim::sensor_pose(scenario.sensor, 0).translation.z() - scenario.ground.height_m;
  io::SequenceWriteOptions wo;
  wo.overwrite = o.overwrite;
  io::SequenceWriter writer(o.out, meta, wo);
  // After the writer claimed the folder (it refuses one holding another sequence).
  io::RunStatusFile status_file(std::filesystem::path(o.out) / "run.json",
                                new_run_status("simulate", o.scenario));
  status_file.start();
  try {
    simulate_into(o, scenario, simulator, writer, status_file.status());
  } catch (const std::exception& e) {
    status_file.fail(e.what());
    throw;
  }
  status_file.finish(StopSignals::signal_name());
}

void simulate_into(const SimulateOptions& o, const sim::Scenario& scenario,
                   sim::Simulator& simulator, io::SequenceWriter& writer, io::RunStatus& status) {
  {
    // The effective scenario beside the output, so a run can be repeated from the folder alone.
    // Scripted actors go beside it as trajectories.csv.
    sim::Scenario effective = scenario;
    if (!scenario.scripted.empty()) {
      effective.trajectories_file = "trajectories.csv";
      const auto csv = std::filesystem::path(o.out) / effective.trajectories_file;
      std::ofstream t(csv, std::ios::binary);
      t << sim::format_trajectories_csv(scenario.scripted);
      if (!t.good()) throw core::Error(csv.string() + ": cannot write");
    }
    const auto path = std::filesystem::path(o.out) / "scenario.yaml";
    std::ofstream f(path, std::ios::binary);
    f << sim::format_scenario_yaml(effective);
    if (!f.good()) throw core::Error(path.string() + ": cannot write");
  }
  const bool moving = scenario.sensor.motion != sim::SensorMotion::kStatic;
  const std::int64_t n = simulator.scan_count();
  sim::SimulatedScan scan;
  std::vector<io::ObjectRow> rows;
  std::uint64_t seen = 0;
  for (std::int64_t k = 0; k < n; ++k) {
    if (StopSignals::requested()) break;
    simulator.next(scan);
    ++status.scans_read;
    rows.clear();
    for (const auto& t : scan.objects) {
      // scan and stamp are set by the writer from the scan itself
      rows.push_back(object_row(0, 0, t));
      seen += t.hit_points > 0 ? 1 : 0;
    }
    writer.add_scan(scan.scan, scan.labels, scan.pose, rows);
    ++status.scans_processed;
    if (moving) {
      // The trajectory at 100 Hz between scans, for motion compensation.
      const std::int64_t next_stamp = simulator.scan_stamp_ns(k + 1);
      for (std::int64_t t = scan.scan.stamp_ns + 10'000'000; t < next_stamp; t += 10'000'000) {
        writer.add_pose(simulator.sensor_pose_at(t));
      }
    }
  }
  writer.finish();
  const std::string signal = StopSignals::signal_name();
  std::cout << "simulated " << writer.size() << " scans of scenario '" << scenario.name << "' ("
            << (moving ? "moving" : "static") << " sensor, seed " << o.seed << ", "
            << simulator.actors().size() << " objects, " << seen << " object observations) into "
            << o.out << (signal.empty() ? "" : " (stopped by " + signal + ")") << "\n";
}

}  // namespace

void register_simulate(CLI::App& app) {
  auto opts = std::make_shared<SimulateOptions>();
  CLI::App* cmd = app.add_subcommand(
      "simulate", "simulate a spinning LiDAR in a scenario and write a sequence folder");
  cmd->add_option("scenario", opts->scenario,
                  "built-in scenario (1-7 or name, see --list) or scenario .yaml file");
  cmd->add_option("--out", opts->out, "output sequence folder");
  cmd->add_option("--seed", opts->seed, "random seed (actors, noise); same seed, same output")
      ->capture_default_str();
  cmd->add_option("--duration", opts->duration_s, "seconds to simulate (default: the scenario's)");
  cmd->add_flag("--moving-sensor", opts->moving_sensor,
                "fly the sensor on a figure 8 (MAV speeds)");
  cmd->add_option("--sensor", opts->sensor,
                  "sensor model (vlp16, vlp32c, hdl32e; default: the scenario's)");
  cmd->add_flag("--overwrite", opts->overwrite, "replace an existing sequence in --out");
  cmd->add_flag("--list", opts->list, "list the built-in scenarios and exit");
  cmd->callback([opts] { run_simulate(*opts); });
}

}  // namespace ringtrack::cli
