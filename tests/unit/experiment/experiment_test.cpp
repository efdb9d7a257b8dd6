// The library's benchmark engine: a recorded scenario replays exactly what the simulator
// produced, runs on it give the live runs' results, and cases group as the report sums them.

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/experiment/aggregate.hpp"
#include "ringtrack/experiment/benchmark_case.hpp"
#include "ringtrack/experiment/plan.hpp"
#include "ringtrack/experiment/recorded_scenario.hpp"
#include "ringtrack/experiment/results_json.hpp"
#include "ringtrack/sim/scenario_file.hpp"

namespace ringtrack::experiment {
namespace {

// Bitwise equality, so that NaN cells compare equal to NaN cells.
bool same_floats(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

sim::Scenario short_scenario(const char* number, double seconds, bool moving) {
  sim::Scenario s = sim::builtin_scenario(number);
  s.duration_s = seconds;
  if (moving) s = sim::with_moving_sensor(s);
  return s;
}

void expect_same_scan(const sim::SimulatedScan& a, const sim::SimulatedScan& b) {
  EXPECT_TRUE(same_floats(a.scan.ranges(), b.scan.ranges()));
  EXPECT_TRUE(same_floats(a.scan.xs(), b.scan.xs()));
  EXPECT_TRUE(same_floats(a.scan.ys(), b.scan.ys()));
  EXPECT_TRUE(same_floats(a.scan.zs(), b.scan.zs()));
  EXPECT_TRUE(same_floats(a.scan.intensities(), b.scan.intensities()));
  EXPECT_EQ(a.scan.statuses(), b.scan.statuses());
  EXPECT_EQ(a.scan.column_stamp_ns, b.scan.column_stamp_ns);
  EXPECT_EQ(a.scan.column_azimuth_rad, b.scan.column_azimuth_rad);
  EXPECT_EQ(a.scan.stamp_ns, b.scan.stamp_ns);
  EXPECT_EQ(a.labels, b.labels);
  ASSERT_EQ(a.objects.size(), b.objects.size());
  for (std::size_t i = 0; i < a.objects.size(); ++i) {
    EXPECT_EQ(a.objects[i].id, b.objects[i].id);
    EXPECT_EQ(a.objects[i].hit_points, b.objects[i].hit_points);
    EXPECT_EQ(a.objects[i].moving, b.objects[i].moving);
  }
}

TEST(RecordedScenario, ExpandsToTheSimulatorsScansBitForBit) {
  for (const bool moving : {false, true}) {
    const sim::Scenario s = short_scenario("2", 1.0, moving);
    const RecordedScenario recorded(s, 7, /*deskew=*/false);
    sim::Simulator simulator(s, 7);
    ASSERT_EQ(recorded.size(), static_cast<std::size_t>(simulator.scan_count()));
    EXPECT_EQ(recorded.moving(), moving);
    sim::SimulatedScan live, replay;
    core::Pose pose;
    for (std::size_t k = 0; k < recorded.size(); ++k) {
      simulator.next(live);
      recorded.expand(k, replay, pose);
      expect_same_scan(live, replay);
      EXPECT_EQ(pose.translation, live.pose.translation);
      EXPECT_EQ(pose.rotation.coeffs(), live.pose.rotation.coeffs());
    }
    // Only cells with a return are kept: well below the 25 bytes per cell of a full scan.
    const std::size_t full = recorded.size() * replay.scan.size() * 25;
    EXPECT_LT(recorded.memory_bytes(), full / 2);
  }
}

TEST(RecordedScenario, OutOfRangeCellsKeepTheirStatus) {
  sim::Scenario s = short_scenario("1", 0.2, false);
  const RecordedScenario recorded(s, 3);
  sim::Simulator simulator(s, 3);
  sim::SimulatedScan live, replay;
  core::Pose pose;
  simulator.next(live);
  recorded.expand(0, replay, pose);
  // The empty field's ground ends inside the range limit, so every status must match, whichever
  // occur; at least the valid ones and the no-returns (sky) do.
  EXPECT_EQ(live.scan.statuses(), replay.scan.statuses());
  EXPECT_GT(live.scan.valid_count(), 0u);
}

TEST(BenchmarkCase, RecordedRunGivesTheLiveRunsResults) {
  const core::Config config;
  for (const bool moving : {false, true}) {
    const sim::Scenario s = short_scenario("2", 4.0, moving);
    BenchmarkCaseOptions options;
    options.seed = 5;
    const BenchmarkCase live = run_benchmark_case(s, config, options);
    const RecordedScenario recorded(s, 5, options.deskew);
    const BenchmarkCase replay = run_benchmark_case(recorded, config, options);
    EXPECT_EQ(metrics_json(live.tracking.summary), metrics_json(replay.tracking.summary));
    EXPECT_EQ(map_json(live.map), map_json(replay.map));
    EXPECT_EQ(live.scans, replay.scans);
    EXPECT_EQ(live.moving, moving);
    EXPECT_GT(live.tracking.summary.gt_presences, 0);
    // A second run on the same recording is independent of the first.
    const BenchmarkCase again = run_benchmark_case(recorded, config, options);
    EXPECT_EQ(metrics_json(again.tracking.summary), metrics_json(replay.tracking.summary));
  }
}

// The final-map figures (BenchmarkCase::final_map) count the same points as the per-scan ones;
// they differ only where a decision came after a scan had left the log. People in the chat
// circles stand for seconds before they walk off: with a log of 5 scans their static era is in
// the map when their tracks turn dynamic, and its voxels leave the map then. With a log longer
// than the run every decision is made while the scans are logged, so both counts agree; with a
// map radius (voxels leave memory) there are no final-map figures.
TEST(BenchmarkCase, FinalMapCreditsRemovalsAfterTheLog) {
  const sim::Scenario s = [] {
    sim::Scenario v = sim::load_scenario_file(std::string(RINGTRACK_SOURCE_DIR) +
                                              "/config/validation/v2-chat-circles.yaml");
    v.duration_s = 12.0;
    return v;
  }();
  BenchmarkCaseOptions options;
  options.seed = 1;
  options.final_map = true;
  core::Config short_log;
  short_log.mapping.log_delay_scans = 5;
  short_log.mapping.transient_scans = 0;  // needs a log of at least transient_scans
  const BenchmarkCase later = run_benchmark_case(s, short_log, options);
  ASSERT_TRUE(later.final_map.has_value());
  const eval::MapCounts& m = later.map;
  const eval::MapCounts& f = *later.final_map;
  EXPECT_EQ(f.static_points, m.static_points);
  EXPECT_EQ(f.dynamic_points, m.dynamic_points);
  EXPECT_GT(m.dynamic_points, 0);
  EXPECT_LE(f.static_kept, m.static_kept);
  EXPECT_GT(f.dynamic_removed, m.dynamic_removed) << "no static era left the map later";

  core::Config long_log = short_log;
  long_log.mapping.log_delay_scans = 1000;
  const BenchmarkCase logged = run_benchmark_case(s, long_log, options);
  ASSERT_TRUE(logged.final_map.has_value());
  EXPECT_EQ(map_json(*logged.final_map), map_json(logged.map));

  core::Config bounded = short_log;
  bounded.mapping.map_radius_m = 500.0;
  EXPECT_FALSE(run_benchmark_case(s, bounded, options).final_map.has_value());
  options.final_map = false;
  EXPECT_FALSE(run_benchmark_case(s, short_log, options).final_map.has_value());
}

TEST(BenchmarkCase, OdometryEstimatesThePosesFromTheScansAsMeasured) {
  const core::Config config;
  const sim::Scenario s = short_scenario("4", 4.0, /*moving=*/true);
  sim::Simulator truth(s, 5);  // the true pose of every scan, for comparison
  BenchmarkCaseOptions options;
  options.seed = 5;
  options.odometry = true;
  std::vector<core::Pose> estimated;
  std::vector<core::Pose> measured_at;
  options.on_scan = [&](const sim::SimulatedScan& scan, const pipeline::FrameResult& result) {
    estimated.push_back(result.pose);
    measured_at.push_back(scan.pose);
  };
  const BenchmarkCase live = run_benchmark_case(s, config, options);
  ASSERT_EQ(estimated.size(), 40U);
  EXPECT_GT(live.tracking.summary.gt_presences, 0);
  double squared_errors = 0.0;
  bool any_differs = false;
  for (std::size_t k = 0; k < estimated.size(); ++k) {
    sim::SimulatedScan scan;
    truth.next(scan);
    // The scans reach the case as measured: their pose is the simulator's at the first column.
    EXPECT_EQ(measured_at[k].translation, scan.pose.translation);
    const double error = (estimated[k].translation - scan.pose.translation).norm();
    squared_errors += error * error;
    any_differs = any_differs || error > 0.0;
  }
  EXPECT_EQ((estimated[0].translation - measured_at[0].translation).norm(), 0.0);  // the start
  EXPECT_TRUE(any_differs);  // estimated, not the simulator's poses
  // 4 s of the figure 8 from a moving start, the young map's worst seconds: centimetres, not
  // metres (OdometryCli bounds 3 s of it the same way; docs/odometry.md: 2 cm RMSE over 100 s).
  EXPECT_LT(std::sqrt(squared_errors / static_cast<double>(estimated.size())), 0.1);

  // A recording made without deskew replays the same; one deskewed with the true poses cannot
  // serve the odometry and says so.
  const RecordedScenario raw(s, 5, /*deskew=*/false);
  options.on_scan = nullptr;
  const BenchmarkCase replay = run_benchmark_case(raw, config, options);
  EXPECT_EQ(metrics_json(live.tracking.summary), metrics_json(replay.tracking.summary));
  EXPECT_EQ(map_json(live.map), map_json(replay.map));
  const RecordedScenario deskewed(s, 5, /*deskew=*/true);
  EXPECT_THROW((void)run_benchmark_case(deskewed, config, options), std::invalid_argument);
}

BenchmarkCase hand_case(bool moving, bool validation, std::int64_t misses, double ms) {
  BenchmarkCase c;
  c.moving = moving;
  c.validation = validation;
  c.scans = 2;
  c.tracking.summary.misses = misses;
  c.tracking.summary.gt_presences = 10;
  c.map.static_points = 100;
  c.map.static_kept = 90;
  c.times.total = {ms, ms};
  c.times.segmentation = c.times.detection = c.times.tracking = c.times.mapping = {0.0, 0.0};
  return c;
}

TEST(Aggregate, GroupsSumBuiltinsAndValidationApart) {
  const std::vector<BenchmarkCase> cases = {
      hand_case(false, false, 1, 1.0), hand_case(true, false, 2, 2.0),
      hand_case(false, false, 4, 3.0), hand_case(false, true, 8, 4.0)};
  const std::vector<Aggregate> groups = group_cases(cases);
  ASSERT_EQ(groups.size(), 4u);  // no validation moving -> no validation overall
  EXPECT_EQ(groups[0].label, "all static");
  EXPECT_EQ(groups[0].mot.misses, 5);
  EXPECT_EQ(groups[0].cases, 2);
  EXPECT_EQ(groups[0].map.static_points, 200);
  EXPECT_EQ(groups[0].times.total.size(), 4u);
  EXPECT_EQ(groups[1].label, "all moving");
  EXPECT_EQ(groups[1].mot.misses, 2);
  EXPECT_EQ(groups[2].label, "overall");
  EXPECT_EQ(groups[2].mot.misses, 7);
  EXPECT_EQ(groups[2].mot.gt_presences, 30);
  EXPECT_EQ(groups[3].label, "validation static");
  EXPECT_EQ(groups[3].mot.misses, 8);
  EXPECT_EQ(stats_of(groups[2].times.total).max, 3.0);
  EXPECT_EQ(stats_of(groups[2].times.total).median, 2.0);
}

TEST(ResultsJson, HeaderCasesGroupsAndThePaperInTheirOrder) {
  std::vector<BenchmarkCase> cases = {hand_case(false, false, 1, 1.0),
                                      hand_case(true, false, 2, 2.0)};
  cases[0].scenario = 3;
  ResultsHeader header;
  header.date = "2026-01-02 03:04 UTC";
  header.seed = 7;
  header.runs_planned = 3;
  header.interrupted = "SIGINT";
  const auto j = results_json(header, cases, group_cases(cases), false);
  std::vector<std::string> keys;
  for (const auto& item : j.items()) keys.push_back(item.key());
  EXPECT_EQ(keys,
            (std::vector<std::string>{"ringtrack", "date", "machine", "seed", "duration_s",
                                      "threshold_m", "moving_radius_m", "wall_s", "runs_planned",
                                      "interrupted", "cases", "groups", "paper"}));
  EXPECT_EQ(j["date"], "2026-01-02 03:04 UTC");
  EXPECT_TRUE(j["duration_s"].is_null());
  EXPECT_EQ(j["interrupted"], "SIGINT");
  ASSERT_EQ(j["cases"].size(), 2u);
  EXPECT_EQ(j["cases"][0], case_json(cases[0]));
  EXPECT_EQ(j["groups"]["all moving"]["metrics"]["misses"], 2);
  ASSERT_EQ(j["paper"].size(), 3u);
  EXPECT_EQ(j["paper"][1]["mota"], 0.533);
  header.interrupted.clear();
  EXPECT_TRUE(results_json(header, cases, group_cases(cases), false)["interrupted"].is_null());
}

TEST(ResultsJson, TimingRowsAreOnePerScanWithTheCasesLabel) {
  BenchmarkCase c = hand_case(true, false, 0, 1.5);
  c.scenario = 4;
  EXPECT_EQ(timing_rows(c, "4 x (moving)"),
            "4 x (moving),4,moving,0,0.0000,0.0000,0.0000,0.0000,1.5000\n"
            "4 x (moving),4,moving,1,0.0000,0.0000,0.0000,0.0000,1.5000\n");
  EXPECT_EQ(std::string(kBenchmarkTimingHeader).substr(0, 9), "case,scen");
}

TEST(Plan, BuiltinsRunStaticThenMoving) {
  PlanOptions o;
  o.builtins = {1, 3};
  o.duration_s = 2.0;
  const std::vector<PlannedRun> runs = plan_runs(o);
  ASSERT_EQ(runs.size(), 4u);
  EXPECT_EQ(runs[0].stem(), "1-static");
  EXPECT_EQ(runs[1].stem(), "1-moving");
  EXPECT_EQ(runs[3].stem(), "3-moving");
  EXPECT_TRUE(runs[1].moving());
  EXPECT_EQ(runs[2].scenario.duration_s, 2.0);
  o.with_moving = false;
  EXPECT_EQ(plan_runs(o).size(), 2u);
}

TEST(Plan, RejectsANonPositiveDurationAndAnEmptyFolder) {
  PlanOptions o;
  o.duration_s = 0.0;
  EXPECT_THROW(plan_runs(o), core::ConfigError);
  EXPECT_THROW(scenario_files_in("/nonexistent-ringtrack-folder"), core::InputError);
}

TEST(Plan, ValidationFilesAloneSkipTheBuiltins) {
  PlanOptions o;
  o.scenario_files = scenario_files_in(std::string(RINGTRACK_SOURCE_DIR) + "/config/validation");
  ASSERT_FALSE(o.scenario_files.empty());
  o.with_moving = false;
  const std::vector<PlannedRun> runs = plan_runs(o);
  ASSERT_EQ(runs.size(), o.scenario_files.size());
  for (const PlannedRun& r : runs) {
    EXPECT_TRUE(r.validation);
    EXPECT_EQ(r.stem().rfind("V-", 0), 0u);
  }
}

}  // namespace
}  // namespace ringtrack::experiment
