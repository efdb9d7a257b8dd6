#pragma once
// `ringtrack benchmark`'s engine: simulate a built-in scenario in memory, run the pipeline on it,
// evaluate tracks (the paper's protocol) and the dynamic-object filter (map metrics), and time
// each stage. No files are read or written here.

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/eval/map_metrics.hpp"
#include "ringtrack/eval/tracking_eval.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace ringtrack::cli {

/// Per-scan wall times of each pipeline stage (ms), in scan order.
struct StageSeries {
  std::vector<double> segmentation, detection, tracking, mapping, total;
};

/// How one scenario run is done.
struct BenchmarkCaseOptions {
  std::uint64_t seed{1};
  bool deskew{true};                     ///< motion-compensate moving-sensor scans (exact poses)
  eval::TrackingEvalOptions evaluation;  ///< paper mode, 0.5 m, class person
  /// Also evaluate the same tracks in person mode (person-flagged hypotheses, standing people
  /// included) into BenchmarkCase::person.
  bool person_figures{false};
  /// Called after every scan with the simulated scan (deskewed) and the pipeline's result,
  /// e.g. to write tracks.csv and objects.csv; may be empty.
  std::function<void(const sim::SimulatedScan&, const pipeline::FrameResult&)> on_scan;
};

/// Results of one scenario with one sensor motion.
struct BenchmarkCase {
  int scenario{0};
  std::string name;        ///< e.g. "empty-field"
  bool moving{false};      ///< sensor on the figure 8
  bool validation{false};  ///< a validation scenario (config/validation/), reported apart
  std::int64_t scans{0};
  eval::TrackingEvalResult tracking;
  std::optional<eval::TrackingEvalResult> person;  ///< person mode, with person_figures
  eval::MapCounts map;
  StageSeries times;
  double simulate_s{0};  ///< wall time in the simulator
  double pipeline_s{0};  ///< wall time in the pipeline (process + finish)
};

/// Simulates the scenario (its duration as given), runs a fresh pipeline with config on every
/// scan and evaluates. Map metrics: a point is dynamic when it belongs to an object that moves
/// in any scan of the run; it counts as removed when the filter's final decision (when the scan
/// leaves the log) removed it (docs/evaluation.md, "Benchmark map metrics").
BenchmarkCase run_benchmark_case(const sim::Scenario& scenario, const core::Config& config,
                                 const BenchmarkCaseOptions& options);

/// Value at quantile q (0..1) by nearest rank on a copy; 0 for an empty series.
double quantile(std::vector<double> values, double q);

}  // namespace ringtrack::cli
