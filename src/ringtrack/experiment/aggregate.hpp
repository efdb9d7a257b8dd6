#pragma once
/// Groups of benchmark cases summed (never averaged), as the benchmark report and the tuner
/// present them: "all static", "all moving", "overall" and the same for validation scenarios.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "ringtrack/experiment/benchmark_case.hpp"

namespace ringtrack::experiment {

/// A group of cases summed: metrics, map counts and pooled per-scan times.
struct Aggregate {
  std::string label;
  eval::MotSummary mot;
  eval::MotSummary moving_only;  ///< ground truth restricted to objects that move
  std::int64_t moving_objects{0};
  std::int64_t never_moving_objects{0};
  eval::MotSummary person;  ///< person mode (cases run with person_figures)
  std::int64_t person_hypotheses{0};
  eval::MapCounts map;
  std::optional<eval::MapCounts> final_map;  ///< summed when every case has it
  StageSeries times;
  std::int64_t scans{0};
  int cases{0};
  /// Adds one case's counts and times.
  void add(const BenchmarkCase& c);
};

/// The non-empty groups of the cases, built-ins and validation scenarios apart: "all static",
/// "all moving", "overall" (when both exist), then "validation static/moving/overall".
std::vector<Aggregate> group_cases(const std::vector<BenchmarkCase>& cases);

}  // namespace ringtrack::experiment
