// `ringtrack eval-trajectory EST --reference GT`: ATE and KITTI-style relative error of an
// estimated trajectory (e.g. the poses.txt of `ringtrack run` with odometry) against a reference.

#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "ringtrack/eval/trajectory_metrics.hpp"
#include "ringtrack/io/poses.hpp"

namespace ringtrack::cli {
namespace {

struct TrajectoryEvalOptions {
  std::string estimate;
  std::string reference;
  std::vector<double> segments_m{10, 20, 30, 40, 50, 60, 70, 80, 90, 100};
  std::size_t step{1};
  bool json{false};
};

void run_trajectory_eval(const TrajectoryEvalOptions& o) {
  const auto estimate = io::read_tum(o.estimate);
  const auto reference = io::read_tum(o.reference);
  eval::TrajectoryMetricsOptions options;
  options.segment_lengths_m = o.segments_m;
  options.segment_step = o.step;
  const auto m = eval::trajectory_metrics(estimate.poses(), reference.poses(), options);
  if (o.json) {
    const nlohmann::ordered_json j = {
        {"estimate", o.estimate},           {"reference", o.reference},
        {"matched_poses", m.matched_poses}, {"path_length_m", m.path_length_m},
        {"ate_rmse_m", m.ate_rmse_m},       {"ate_mean_m", m.ate_mean_m},
        {"ate_max_m", m.ate_max_m},         {"segments", m.segments},
        {"rte_percent", m.rte_percent},     {"rre_deg_per_m", m.rre_deg_per_m},
        {"final_drift_m", m.final_drift_m}};
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::printf("matched poses    %zu (path %.1f m)\n", m.matched_poses, m.path_length_m);
  std::printf("ATE              RMSE %.4f m, mean %.4f m, max %.4f m (rigidly aligned)\n",
              m.ate_rmse_m, m.ate_mean_m, m.ate_max_m);
  if (m.segments == 0) {
    std::printf("RTE              no segment: the path is shorter than the shortest length\n");
  } else {
    std::printf("RTE              %.3f %%, %.5f deg/m (%zu segments)\n", m.rte_percent,
                m.rre_deg_per_m, m.segments);
  }
  std::printf("end drift        %.4f m (tied at the first pose)\n", m.final_drift_m);
}

}  // namespace

void register_eval_trajectory(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "eval-trajectory",
      "absolute and relative (KITTI-style) error of an estimated TUM trajectory against a "
      "reference (docs/evaluation.md, \"Trajectories\")");
  auto o = std::make_shared<TrajectoryEvalOptions>();
  cmd->add_option("estimate", o->estimate, "estimated trajectory (TUM), e.g. run's poses.txt")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--reference", o->reference,
                  "reference trajectory (TUM), e.g. a simulated sequence's poses.txt")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--segments", o->segments_m,
                  "segment lengths of the relative error, metres along the reference")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--step", o->step, "start a segment at every this many poses")
      ->check(CLI::Range(std::size_t{1}, std::size_t{1000000}))
      ->capture_default_str();
  cmd->add_flag("--json", o->json, "print JSON instead of a table");
  cmd->callback([o] { run_trajectory_eval(*o); });
}

}  // namespace ringtrack::cli
