#pragma once
/// The benchmark's engine: run the pipeline on a simulated scenario (live or recorded), evaluate
/// the tracks (the paper's protocol) and the dynamic-object filter (map metrics), and time each
/// stage. No files are read or written here; `ringtrack benchmark`, `ringtrack tune` and the
/// Python package share it.

#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/eval/map_metrics.hpp"
#include "ringtrack/eval/tracking_eval.hpp"
#include "ringtrack/experiment/recorded_scenario.hpp"
#include "ringtrack/experiment/recorded_sequence.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace ringtrack::experiment {

/// Per-scan wall times of each pipeline stage (ms), in scan order.
struct StageSeries {
  std::vector<double> segmentation, detection, tracking, mapping, total;
};

/// Median, 95th percentile and maximum of a series (ms).
struct StageStats {
  double median{0}, p95{0}, max{0};
};
/// Order statistics of one stage's series; zeros for an empty series.
StageStats stats_of(const std::vector<double>& series);

/// The stages of StageSeries with their names, in pipeline order, "total" last.
const std::vector<std::pair<const char*, std::vector<double> StageSeries::*>>& stage_members();

/// How one scenario run is done.
struct BenchmarkCaseOptions {
  std::uint64_t seed{1};  ///< simulator seed (live runs; a recording has its own)
  bool deskew{true};      ///< motion-compensate moving-sensor scans (exact poses)
  /// The pipeline's odometry estimates the poses from the scans (as `run` does for a recording
  /// without poses), starting at the simulator's pose of the first scan; the scans reach it as
  /// measured, and it compensates them itself unless config.odometry.deskew is off. Live runs and
  /// recordings made without deskew only.
  bool odometry{false};
  eval::TrackingEvalOptions evaluation;  ///< paper mode, 0.5 m, class person
  /// Also evaluate the same tracks in person mode (person-flagged hypotheses, standing people
  /// included) into BenchmarkCase::person.
  bool person_figures{false};
  /// Also count the map figures against the map at the end of the run into
  /// BenchmarkCase::final_map (a tally of every kept point by map voxel: about a tenth more time;
  /// `ringtrack benchmark` sets it, tuning trials leave it off).
  bool final_map{false};
  /// Called after every scan with the simulated scan (deskewed) and the pipeline's result,
  /// e.g. to write tracks.csv and objects.csv; may be empty.
  std::function<void(const sim::SimulatedScan&, const pipeline::FrameResult&)> on_scan;
  /// When given and set (e.g. by Ctrl-C or SIGTERM), a run over scans stops before its next scan
  /// and returns with BenchmarkCase::interrupted and no evaluation.
  const std::atomic<bool>* interrupt{nullptr};
};

/// Results of one scenario with one sensor motion.
struct BenchmarkCase {
  int scenario{0};
  std::string name;        ///< e.g. "empty-field"
  bool moving{false};      ///< the sensor moves (figure 8 or scripted)
  bool validation{false};  ///< a validation scenario (config/validation/), reported apart
  std::int64_t scans{0};
  eval::TrackingEvalResult tracking;
  std::optional<eval::TrackingEvalResult> person;  ///< person mode, with person_figures
  eval::MapCounts map;
  /// The same points counted against the map at the end of the run: a point the filter kept
  /// whose voxel a later decision removed from the map (an object's static era older than the
  /// log) counts as removed. Empty unless BenchmarkCaseOptions::final_map, without per-cell
  /// labels, or with mapping.map_radius_m > 0.
  std::optional<eval::MapCounts> final_map;
  StageSeries times;
  double simulate_s{0};  ///< wall time producing scans (simulation or expanding a recording)
  double pipeline_s{0};  ///< wall time in the pipeline (process + finish)
  /// Stopped by BenchmarkCaseOptions::interrupt: the figures are not evaluated (discard it).
  bool interrupted{false};
};

/// Simulates the simulator's next scan into `scan` and returns the pose to give the pipeline:
/// the scan's own, or with `deskew` (a moving sensor) the scan motion-compensated in place from
/// its pose to the next scan's (pipeline::deskew_scan) and the pose of its first column.
core::Pose next_simulated_scan(sim::Simulator& simulator, sim::SimulatedScan& scan, bool deskew);

/// Simulates the scenario (its duration as given), runs a fresh pipeline with config on every
/// scan and evaluates. Map metrics: a point is dynamic when it belongs to an object that moves
/// in any scan of the run; it counts as removed when the filter's final decision (when the scan
/// leaves the log) removed it (docs/evaluation.md, "Benchmark map metrics").
BenchmarkCase run_benchmark_case(const sim::Scenario& scenario, const core::Config& config,
                                 const BenchmarkCaseOptions& options);

/// The same on a recorded scenario (its own seed and deskew setting; options.seed and
/// options.deskew are not used): identical results to the live run with that seed.
BenchmarkCase run_benchmark_case(const RecordedScenario& recorded, const core::Config& config,
                                 const BenchmarkCaseOptions& options);

/// The same on a recorded sequence folder against its objects.csv. Without per-cell labels the
/// map figures stay zero (BenchmarkCase::map); scenario is 0 and name the folder's name;
/// options.on_scan is not called (there is no simulated scan).
BenchmarkCase run_benchmark_case(const RecordedSequence& recorded, const core::Config& config,
                                 const BenchmarkCaseOptions& options);

}  // namespace ringtrack::experiment
