#pragma once
/// The JSON shapes of evaluation results, one definition for `ringtrack eval --json`,
/// `ringtrack benchmark` (results.json), the tuner and the Python package.

#include <cstdint>
#include <nlohmann/json.hpp>
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

}  // namespace ringtrack::experiment
