#include "ringtrack/experiment/results_json.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <thread>

#include "ringtrack/version.hpp"

namespace ringtrack::experiment {

nlohmann::ordered_json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::ordered_json(v) : nlohmann::ordered_json(nullptr);
}

nlohmann::ordered_json metrics_json(const eval::MotSummary& s) {
  return {
      {"mota", number_or_null(s.mota())},
      {"motp", number_or_null(s.motp())},
      {"motp_horizontal", number_or_null(s.horizontal_motp())},
      {"mean_vertical_error", number_or_null(s.mean_vertical_error())},
      {"true_positives", s.true_positives()},
      {"matches", s.matches},
      {"false_positives", s.false_positives},
      {"misses", s.misses},
      {"id_switches", s.switches},
      {"fragmentations", s.fragmentations},
      {"recall", number_or_null(s.recall())},
      {"precision", number_or_null(s.precision())},
      {"mostly_tracked", s.mostly_tracked},
      {"partially_tracked", s.partially_tracked},
      {"mostly_lost", s.mostly_lost},
      {"mostly_tracked_ratio", number_or_null(s.mostly_tracked_ratio())},
      {"partially_tracked_ratio", number_or_null(s.partially_tracked_ratio())},
      {"mostly_lost_ratio", number_or_null(s.mostly_lost_ratio())},
      {"idf1", number_or_null(s.idf1())},
      {"idp", number_or_null(s.idp())},
      {"idr", number_or_null(s.idr())},
      {"id_true_positives", s.id_true_positives},
      {"id_false_positives", s.id_false_positives},
      {"id_false_negatives", s.id_false_negatives},
      {"gt_objects", s.gt_objects},
      {"hypotheses", s.hypotheses},
      {"gt_presences", s.gt_presences},
      {"hypothesis_presences", s.hypothesis_presences},
      {"frames", s.frames},
  };
}

nlohmann::ordered_json moving_only_json(std::int64_t moving_objects, std::int64_t still_objects,
                                        const eval::MotSummary& moving_only) {
  return {{"moving_objects", moving_objects},
          {"never_moving_objects", still_objects},
          {"metrics", metrics_json(moving_only)}};
}

nlohmann::ordered_json map_json(const eval::MapCounts& m) {
  return {{"preservation_rate", number_or_null(m.preservation_rate())},
          {"rejection_rate", number_or_null(m.rejection_rate())},
          {"static_points", m.static_points},
          {"static_kept", m.static_kept},
          {"dynamic_points", m.dynamic_points},
          {"dynamic_removed", m.dynamic_removed}};
}

nlohmann::ordered_json times_json(const StageSeries& s) {
  nlohmann::ordered_json j;
  for (const auto& [name, member] : stage_members()) {
    const StageStats st = stats_of(s.*member);
    j[name] = {{"median_ms", st.median}, {"p95_ms", st.p95}, {"max_ms", st.max}};
  }
  return j;
}

nlohmann::ordered_json case_json(const BenchmarkCase& c) {
  nlohmann::ordered_json j = {
      {"scenario", c.scenario},
      {"name", c.name},
      {"validation", c.validation},
      {"sensor", c.moving ? "moving" : "static"},
      {"scans", c.scans},
      {"hypotheses_total", c.tracking.hypotheses_total},
      {"hypotheses_evaluated", c.tracking.hypotheses_evaluated},
      {"metrics", metrics_json(c.tracking.summary)},
      {"moving_only", moving_only_json(c.tracking.moving_objects, c.tracking.still_objects,
                                       c.tracking.moving_only)},
      {"map", map_json(c.map)},
      {"final_map", c.final_map ? map_json(*c.final_map) : nlohmann::ordered_json()},
      {"times", times_json(c.times)},
      {"simulate_s", c.simulate_s},
      {"pipeline_s", c.pipeline_s}};
  if (c.person) {
    j["person_mode"] = {{"hypotheses_evaluated", c.person->hypotheses_evaluated},
                        {"metrics", metrics_json(c.person->summary)}};
  }
  return j;
}

nlohmann::ordered_json group_json(const Aggregate& g, bool person_figures) {
  nlohmann::ordered_json j = {
      {"scans", g.scans},
      {"metrics", metrics_json(g.mot)},
      {"moving_only", moving_only_json(g.moving_objects, g.never_moving_objects, g.moving_only)},
      {"map", map_json(g.map)},
      {"final_map", g.final_map ? map_json(*g.final_map) : nlohmann::ordered_json()},
      {"times", times_json(g.times)}};
  if (person_figures) {
    j["person_mode"] = {{"hypotheses_evaluated", g.person_hypotheses},
                        {"metrics", metrics_json(g.person)}};
  }
  return j;
}

nlohmann::ordered_json groups_json(const std::vector<Aggregate>& groups, bool person_figures) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const Aggregate& g : groups) j[g.label] = group_json(g, person_figures);
  return j;
}

namespace {

nlohmann::ordered_json paper_json() {
  nlohmann::ordered_json j = nlohmann::ordered_json::array();
  for (const PaperRow& p : kPaperRows) {
    j.push_back({{"data", p.data},
                 {"mota", p.mota},
                 {"motp", p.motp},
                 {"mostly_tracked_ratio", p.mt},
                 {"partially_tracked_ratio", p.pt},
                 {"mostly_lost_ratio", p.ml}});
  }
  return j;
}

}  // namespace

nlohmann::ordered_json results_json(const ResultsHeader& h, const std::vector<BenchmarkCase>& cases,
                                    const std::vector<Aggregate>& groups, bool person_figures) {
  nlohmann::ordered_json j;
  j["ringtrack"] = kVersion;
  j["date"] = h.date;
  j["machine"] = h.machine;
  j["seed"] = h.seed;
  j["duration_s"] =
      h.duration_s ? nlohmann::ordered_json(*h.duration_s) : nlohmann::ordered_json(nullptr);
  j["threshold_m"] = h.threshold_m;
  j["moving_radius_m"] = h.moving_radius_m;
  j["wall_s"] = h.wall_s;
  // Interrupted (Ctrl-C, SIGTERM): the cases and groups cover the runs that finished.
  j["runs_planned"] = h.runs_planned;
  j["interrupted"] = h.interrupted.empty() ? nlohmann::ordered_json(nullptr)
                                           : nlohmann::ordered_json(h.interrupted);
  j["cases"] = nlohmann::ordered_json::array();
  for (const BenchmarkCase& c : cases) j["cases"].push_back(case_json(c));
  j["groups"] = groups_json(groups, person_figures);
  j["paper"] = paper_json();
  return j;
}

std::string timing_rows(const BenchmarkCase& c, const std::string& label) {
  std::string rows;
  char buf[256];
  for (std::size_t k = 0; k < c.times.total.size(); ++k) {
    std::snprintf(buf, sizeof buf, "%s,%d,%s,%zu,%.4f,%.4f,%.4f,%.4f,%.4f\n", label.c_str(),
                  c.scenario, c.moving ? "moving" : "static", k, c.times.segmentation[k],
                  c.times.detection[k], c.times.tracking[k], c.times.mapping[k], c.times.total[k]);
    rows += buf;
  }
  return rows;
}

std::string machine_description() {
  std::string model = "unknown CPU";
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      if (colon != std::string::npos) model = line.substr(colon + 2);
      break;
    }
  }
  return model + ", " + std::to_string(std::thread::hardware_concurrency()) + " cores";
}

std::string utc_minute_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[64];
  std::strftime(buf, sizeof buf, "%Y-%m-%d %H:%M UTC", &tm);
  return buf;
}

}  // namespace ringtrack::experiment
