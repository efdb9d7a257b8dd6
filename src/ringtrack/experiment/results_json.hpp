#pragma once
/// The JSON shapes of evaluation results, one definition for `ringtrack eval --json`,
/// `ringtrack benchmark` (results.json), the tuner and the Python package.

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ringtrack/eval/map_metrics.hpp"
#include "ringtrack/eval/mot_accumulator.hpp"
#include "ringtrack/experiment/aggregate.hpp"
#include "ringtrack/experiment/benchmark_case.hpp"

namespace ringtrack::experiment {

/// v as a JSON number, or null when it is not finite (a ratio over zero objects).
nlohmann::ordered_json number_or_null(double v);
/// Every CLEAR MOT, MT/PT/ML and identity figure of a summary, with its count fields.
nlohmann::ordered_json metrics_json(const eval::MotSummary& s);
/// The "moving objects only" figures: how many objects move and never move, and the metrics over
/// the moving ones (the others are don't-care).
nlohmann::ordered_json moving_only_json(std::int64_t moving_objects, std::int64_t still_objects,
                                        const eval::MotSummary& moving_only);
/// Map preservation and rejection with their point counts.
nlohmann::ordered_json map_json(const eval::MapCounts& m);
/// Median, p95 and max (ms) of every stage.
nlohmann::ordered_json times_json(const StageSeries& s);
/// One benchmark case: identity, metrics (paper mode, moving objects only, person mode when
/// evaluated), map and times.
nlohmann::ordered_json case_json(const BenchmarkCase& c);
/// One group of cases; person_figures adds the person-mode metrics.
nlohmann::ordered_json group_json(const Aggregate& g, bool person_figures);
/// Every group by its label ({"all static": ..., ...}), as results.json's "groups".
nlohmann::ordered_json groups_json(const std::vector<Aggregate>& groups, bool person_figures);

/// One row of the paper's Table II (ICRA 2019), the reference results.json and report.md quote.
struct PaperRow {
  const char* data;               ///< e.g. "simulated, static sensor"
  double mota, motp, mt, pt, ml;  ///< MOTA, MOTP (m), mostly tracked / partially / mostly lost
};
/// The paper's rows: simulated static sensor, simulated moving sensor, InLiDa (real, indoor).
inline constexpr PaperRow kPaperRows[] = {
    {"simulated, static sensor", 0.677, 0.044, 0.75, 0.25, 0.0},
    {"simulated, moving sensor", 0.533, 0.033, 0.57, 0.40, 0.03},
    {"InLiDa (real, indoor; not comparable)", 0.562, 0.108, 0.49, 0.43, 0.08},
};

/// What results.json says about the benchmark itself, before its cases.
struct ResultsHeader {
  std::string date;                  ///< when it ran (utc_minute_now())
  std::string machine;               ///< machine_description()
  std::uint64_t seed{1};             ///< the simulator's
  std::optional<double> duration_s;  ///< seconds per scenario when not each one's full length
  double threshold_m{0.5};           ///< the match distance
  double moving_radius_m{1.0};       ///< for the "moving objects only" figures
  double wall_s{0.0};                ///< the whole benchmark's wall time
  std::size_t runs_planned{0};       ///< runs asked for (more than cases when interrupted)
  std::string interrupted;           ///< the signal that stopped it early, "" when none
};

/// `ringtrack benchmark`'s results.json: the header, every case, the groups and the paper's rows.
nlohmann::ordered_json results_json(const ResultsHeader& header,
                                    const std::vector<BenchmarkCase>& cases,
                                    const std::vector<Aggregate>& groups, bool person_figures);

/// timing.csv's header line (with its newline) and one line per scan of a case, labelled `label`.
inline constexpr const char* kBenchmarkTimingHeader =
    "case,scenario,sensor,scan,segmentation_ms,detection_ms,tracking_ms,mapping_ms,total_ms\n";
std::string timing_rows(const BenchmarkCase& c, const std::string& label);

/// The CPU's model name (/proc/cpuinfo) and the number of cores, for a result's provenance.
std::string machine_description();
/// The time now as "YYYY-MM-DD HH:MM UTC".
std::string utc_minute_now();

}  // namespace ringtrack::experiment
