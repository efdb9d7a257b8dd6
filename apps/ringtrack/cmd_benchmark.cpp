// `ringtrack benchmark`: every built-in scenario with a static and a moving sensor, the default
// configuration, the paper's Table II metrics, map metrics and time per stage, as a Markdown
// report, a per-scan timing CSV, a plot and optionally JSON. Scenario files (the validation set in
// config/validation/, never tuned on) run the same way and are reported as their own group.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "commands.hpp"
#include "data_dirs.hpp"
#include "output_rows.hpp"
#include "plots.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/experiment/aggregate.hpp"
#include "ringtrack/experiment/benchmark_case.hpp"
#include "ringtrack/experiment/plan.hpp"
#include "ringtrack/experiment/results_json.hpp"
#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/io/output_file.hpp"
#include "ringtrack/runner/run.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/scenario_file.hpp"
#include "ringtrack/version.hpp"
#include "stop_signals.hpp"

namespace ringtrack::cli {
namespace {

namespace fs = std::filesystem;
using experiment::Aggregate;
using experiment::BenchmarkCase;
using experiment::StageSeries;
using experiment::StageStats;

struct BenchmarkOptions {
  std::vector<int> scenarios{1, 2, 3, 4, 5, 6, 7};
  bool scenarios_given{false};              // --scenarios on the command line
  std::vector<std::string> scenario_files;  // validation scenarios (YAML)
  bool validation{false};                   // all of config/validation/
  std::optional<double> duration_s;
  std::string out{"benchmark"};
  bool json{false};
  std::uint64_t seed{1};
  std::string sensors{"both"};
  bool no_plot{false};
  bool no_deskew{false};
  bool odometry{false};  // poses from the odometry, not the simulator
  bool quiet{false};
  bool save_tracks{false};
  bool person_figures{false};  // also the person-mode table (standing people count)
  double moving_radius_m{1.0};
  ConfigOptions config;
};

struct Goal {
  double static_mota = 0.80, moving_mota = 0.70, motp_m = 0.05, ml_ratio = 0.05;
};

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string case_label(const BenchmarkCase& c) {
  return (c.validation ? std::string("V ") : std::to_string(c.scenario) + " ") + c.name +
         (c.moving ? " (moving)" : " (static)");
}

// The tracking cells both accuracy tables share: MOTA to GT.
std::string mot_cells(const eval::MotSummary& s) {
  std::ostringstream o;
  o << fixed(s.mota(), 3) << " | " << fixed(s.motp(), 3) << " | " << fixed(s.horizontal_motp(), 3)
    << " | " << fixed(s.mean_vertical_error(), 3) << " | " << fixed(s.mostly_tracked_ratio(), 2)
    << " / " << fixed(s.partially_tracked_ratio(), 2) << " / " << fixed(s.mostly_lost_ratio(), 2)
    << " (" << s.mostly_tracked << "/" << s.partially_tracked << "/" << s.mostly_lost << ") | "
    << s.switches << " | " << s.false_positives << " | " << s.misses << " | " << s.gt_presences;
  return o.str();
}

// The header and alignment rows of a table whose rows are label | count | mot_cells | extras:
// the count column's name and alignment ("---:" for a number, "---" for text), and the extra
// columns with their alignments, each " name |" / " ---: |".
std::string mot_header(const std::string& count_column, const std::string& count_alignment,
                       const std::string& extra_columns = "",
                       const std::string& extra_alignment = "") {
  return "| scenario | " + count_column +
         " | MOTA | MOTP (m) | MOTP x-y (m) | z bias (m) | MT / PT / ML | IDSW | FP | FN | GT |" +
         extra_columns + "\n| --- | " + count_alignment +
         " | ---: | ---: | ---: | ---: | --- | ---: | ---: | ---: | ---: |" + extra_alignment +
         "\n";
}

// The two map columns of a row: preservation and rejection, four decimals.
std::string map_cells(const eval::MapCounts& m) {
  return fixed(m.preservation_rate(), 4) + " | " + fixed(m.rejection_rate(), 4);
}

std::string table_row(const std::string& label, std::int64_t scans, const eval::MotSummary& s,
                      const eval::MapCounts& m) {
  std::ostringstream o;
  o << "| " << label << " | " << scans << " | " << mot_cells(s) << " | " << map_cells(m) << " |\n";
  return o.str();
}

// The report's sections, in order (report_markdown).

// stopped_by: the signal that interrupted the benchmark after cases.size() of runs_planned runs
// ("" when it ran them all).
void report_header(std::ostringstream& md, const BenchmarkOptions& o, std::size_t cases,
                   double wall_s, std::size_t runs_planned, const std::string& stopped_by) {
  md << "# ringtrack benchmark\n\n";
  if (!stopped_by.empty()) {
    md << "**Interrupted by " << stopped_by << " after " << cases << " of " << runs_planned
       << " runs: every figure below covers the finished runs only.**\n\n";
  }
  md << "- date: " << experiment::utc_minute_now() << "\n";
  md << "- machine: " << experiment::machine_description()
     << " (shared with other processes: times are "
        "indicative)\n";
  md << "- ringtrack " << kVersion << ", seed " << o.seed << ", "
     << (o.duration_s ? "duration " + fixed(*o.duration_s, 1) + " s per scenario"
                      : std::string("full scenario durations"))
     << ", "
     << (o.config.file.empty() && o.config.overrides.empty() ? "default configuration"
                                                             : "configuration: see config.yaml")
     << (o.no_deskew ? ", moving-sensor scans not motion-compensated" : "")
     << (o.odometry ? ", poses estimated by the odometry from the scans (--odometry)" : "") << "\n";
  md << "- wall time " << fixed(wall_s, 1) << " s (simulation + pipeline + evaluation)\n\n";
}

void accuracy_section(std::ostringstream& md, const std::vector<BenchmarkCase>& cases,
                      const std::vector<Aggregate>& groups) {
  md << "## Accuracy (as the paper's Table II)\n\n";
  md << "Paper mode (hypotheses classified dynamic at least once), class person, match below "
        "0.5 m; MT/PT/ML as ratios (counts); FN = misses; GT = ground-truth presences. Map: "
        "preservation = static points kept, rejection = dynamic-object points removed "
        "(docs/evaluation.md). Groups are sums over their scenarios, never averages.\n\n";
  if (std::any_of(cases.begin(), cases.end(),
                  [](const BenchmarkCase& c) { return c.validation; })) {
    md << "Rows marked V are validation scenarios (config/validation/, docs/simulator.md): they "
          "are never used to tune the defaults, so their groups show how the defaults generalise."
          "\n\n";
  }
  md << mot_header("scans", "---:", " map preservation | map rejection |", " ---: | ---: |");
  for (const BenchmarkCase& c : cases) {
    md << table_row(case_label(c), c.scans, c.tracking.summary, c.map);
  }
  for (const Aggregate& g : groups) {
    md << table_row("**" + g.label + "**", g.scans, g.mot, g.map);
  }
}

void moving_only_section(std::ostringstream& md, const BenchmarkOptions& o,
                         const std::vector<BenchmarkCase>& cases,
                         const std::vector<Aggregate>& groups) {
  md << "\n## Accuracy on moving objects only\n\n";
  md << "The same tracks against ground truth restricted to objects that move: an object moves "
        "when its true centre leaves a disc of radius "
     << fixed(o.moving_radius_m, 2)
     << " m around its first position at some time. Objects that never move are don't-care: "
        "they count neither as misses nor as matches, and a hypothesis matched to one is neither "
        "a true nor a false positive (docs/evaluation.md). Objects: moving / never moving.\n\n";
  md << mot_header("objects", "---");
  const auto moving_row = [&](const std::string& label, std::int64_t moving, std::int64_t still,
                              const eval::MotSummary& s) {
    md << "| " << label << " | " << moving << " / " << still << " | " << mot_cells(s) << " |\n";
  };
  for (const BenchmarkCase& c : cases) {
    moving_row(case_label(c), c.tracking.moving_objects, c.tracking.still_objects,
               c.tracking.moving_only);
  }
  for (const Aggregate& g : groups) {
    moving_row("**" + g.label + "**", g.moving_objects, g.never_moving_objects, g.moving_only);
  }
}

void person_section(std::ostringstream& md, const std::vector<BenchmarkCase>& cases,
                    const std::vector<Aggregate>& groups) {
  md << "\n## Accuracy in person mode (standing people included)\n\n";
  md << "The same tracks, evaluating the hypotheses flagged `person` at least once (confirmed "
        "and person-shaped for `tracking.person_min_scans` scans, moving or not; "
        "docs/tracking.md) in all their scans, against the same ground truth as the paper mode "
        "(every person with hit points, standing or walking). Hypotheses: person-flagged ids "
        "evaluated.\n\n";
  md << mot_header("hypotheses", "---:");
  for (const BenchmarkCase& c : cases) {
    if (!c.person) continue;
    md << "| " << case_label(c) << " | " << c.person->hypotheses_evaluated << " | "
       << mot_cells(c.person->summary) << " |\n";
  }
  for (const Aggregate& g : groups) {
    md << "| **" << g.label << "** | " << g.person_hypotheses << " | " << mot_cells(g.person)
       << " |\n";
  }
}

// The map figures again, counted against the map at the end of the run (BenchmarkCase::final_map),
// beside the per-scan decisions; absent when no run has them (mapping.map_radius_m > 0).
void final_map_section(std::ostringstream& md, const std::vector<BenchmarkCase>& cases,
                       const std::vector<Aggregate>& groups) {
  if (std::none_of(cases.begin(), cases.end(),
                   [](const BenchmarkCase& c) { return c.final_map.has_value(); })) {
    return;
  }
  md << "\n## Static map at the end of the run\n\n";
  md << "The map figures above count a point as removed when the filter's decision as its scan "
        "left the log removed it. Decisions made later (an object that turns dynamic after "
        "standing longer than the log: its static era's voxels leave the map) change the map "
        "the run writes, not those scans; here a kept point whose voxel the final map no longer "
        "holds counts as removed (docs/evaluation.md).\n\n";
  md << "| scenario | map preservation | map rejection | final map preservation | final map "
        "rejection |\n| --- | ---: | ---: | ---: | ---: |\n";
  const auto row = [&](const std::string& label, const eval::MapCounts& m,
                       const std::optional<eval::MapCounts>& f) {
    md << "| " << label << " | " << map_cells(m) << " | "
       << (f ? map_cells(*f) : std::string("- | -")) << " |\n";
  };
  for (const BenchmarkCase& c : cases) row(case_label(c), c.map, c.final_map);
  for (const Aggregate& g : groups) row("**" + g.label + "**", g.map, g.final_map);
}

// The paper's figures beside the static and moving groups, and the goal for the defaults.
void paper_section(std::ostringstream& md, const std::vector<Aggregate>& groups) {
  md << "\n## Beside the paper\n\n";
  md << "The paper's figures are after leave-one-out tuning on its own Gazebo scenarios; ours use "
        "the default configuration on ringtrack's simulator, so they are alike in kind, not "
        "identical data.\n\n";
  md << "| data | MOTA | MOTP (m) | MT / PT / ML |\n| --- | ---: | ---: | --- |\n";
  const auto paper_row = [&](const experiment::PaperRow& p) {
    md << "| paper: " << p.data << " | " << fixed(p.mota, 3) << " | " << fixed(p.motp, 3) << " | "
       << fixed(p.mt, 2) << " / " << fixed(p.pt, 2) << " / " << fixed(p.ml, 2) << " |\n";
  };
  const auto our_row = [&](const Aggregate& g) {
    md << "| ringtrack: " << g.label << " | " << fixed(g.mot.mota(), 3) << " | "
       << fixed(g.mot.motp(), 3) << " | " << fixed(g.mot.mostly_tracked_ratio(), 2) << " / "
       << fixed(g.mot.partially_tracked_ratio(), 2) << " / " << fixed(g.mot.mostly_lost_ratio(), 2)
       << " |\n";
  };
  for (const Aggregate& g : groups) {
    if (g.label == "all static") {
      paper_row(experiment::kPaperRows[0]);
      our_row(g);
    } else if (g.label == "all moving") {
      paper_row(experiment::kPaperRows[1]);
      our_row(g);
    }
  }
  paper_row(experiment::kPaperRows[2]);

  const Goal goal;
  md << "\nGoal for the defaults (issue 5): MOTA >= " << fixed(goal.static_mota, 2)
     << " static, >= " << fixed(goal.moving_mota, 2) << " moving, MOTP <= " << fixed(goal.motp_m, 2)
     << " m, ML <= " << fixed(goal.ml_ratio, 2) << ".";
  for (const Aggregate& g : groups) {
    if (g.label != "all static" && g.label != "all moving") continue;
    const double need = g.label == "all static" ? goal.static_mota : goal.moving_mota;
    const bool met = g.mot.mota() >= need && g.mot.motp() <= goal.motp_m &&
                     g.mot.mostly_lost_ratio() <= goal.ml_ratio;
    md << " " << g.label << ": " << (met ? "met" : "not met") << ".";
  }
}

void time_section(std::ostringstream& md, const std::vector<BenchmarkCase>& cases,
                  const std::vector<Aggregate>& groups, bool plotted) {
  md << "\n\n## Time per stage (ms per scan)\n\n";
  md << "Wall time of each stage of `Pipeline::process`, one thread; median / p95 / max over the "
        "scans.\n\n";
  md << "| scenario | segmentation | detection | tracking | mapping | total |\n";
  md << "| --- | --- | --- | --- | --- | --- |\n";
  const auto time_row = [&](const std::string& label, const StageSeries& s) {
    md << "| " << label;
    for (const auto& [name, member] : experiment::stage_members()) {
      const StageStats st = experiment::stats_of(s.*member);
      md << " | " << fixed(st.median, 2) << " / " << fixed(st.p95, 2) << " / " << fixed(st.max, 2);
    }
    md << " |\n";
  };
  for (const BenchmarkCase& c : cases) time_row(case_label(c), c.times);
  for (const Aggregate& g : groups) time_row("**" + g.label + "**", g.times);
  md << "\nPer-scan times: `timing.csv`"
     << (plotted ? "; plot: `stage_times.png` (time per stage over each sequence, as the paper's "
                   "Fig. 6)."
                 : " (no plot: python3-matplotlib unavailable or --no-plot).")
     << "\n\n";
}

std::string report_markdown(const BenchmarkOptions& o, const std::vector<BenchmarkCase>& cases,
                            const std::vector<Aggregate>& groups, double wall_s,
                            const std::string& config_text, bool plotted, std::size_t runs_planned,
                            const std::string& stopped_by) {
  std::ostringstream md;
  report_header(md, o, cases.size(), wall_s, runs_planned, stopped_by);
  accuracy_section(md, cases, groups);
  moving_only_section(md, o, cases, groups);
  if (o.person_figures) person_section(md, cases, groups);
  final_map_section(md, cases, groups);
  paper_section(md, groups);
  time_section(md, cases, groups, plotted);
  md << "<details><summary>configuration</summary>\n\n```yaml\n"
     << config_text << "```\n\n</details>\n";
  return md.str();
}

// The Fig. 6-style picture of the stage times; false (and a warning) when it cannot be drawn.
bool plot_stage_times(const fs::path& timing_csv, const fs::path& png) {
  return run_plot_script("plot_stage_times.py", {timing_csv, png});
}

void benchmark_into(const BenchmarkOptions& o, const core::Config& config,
                    const std::vector<experiment::PlannedRun>& runs, io::RunStatus& status);

void run_benchmark(const BenchmarkOptions& o) {
  core::Config config = o.config.load();
  // As `run`: with the odometry, --no-deskew leaves the scans uncompensated there too.
  if (o.odometry && o.no_deskew) config.odometry.deskew = false;
  core::validate_config(config);
  experiment::PlanOptions plan;
  plan.builtins = o.scenarios;
  plan.builtins_given = o.scenarios_given;
  plan.scenario_files = o.scenario_files;
  if (o.validation) {
    const fs::path dir = config_dir() / "validation";
    for (const std::string& f : experiment::scenario_files_in(dir))
      plan.scenario_files.push_back(f);
  }
  plan.duration_s = o.duration_s;
  plan.with_static = o.sensors != "moving";
  plan.with_moving = o.sensors != "static";
  const std::vector<experiment::PlannedRun> runs = experiment::plan_runs(plan);

  const fs::path out = o.out;
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw core::InputError(o.out + ": cannot create the output folder: " + ec.message());
  // run.json says whether the folder's outputs are whole (docs/formats.md).
  io::RunStatusFile status_file(out / "run.json", new_run_status("benchmark", ""));
  // Ctrl-C and SIGTERM stop after the scan at hand and report the runs that finished.
  const StopSignals stop_signals;
  status_file.start();
  try {
    benchmark_into(o, config, runs, status_file.status());
  } catch (const std::exception& e) {
    status_file.fail(e.what());
    throw;
  }
  status_file.finish(StopSignals::signal_name());
}

// --save-tracks: the same files as `simulate` + `run` write, for `ringtrack eval` and plots.
struct SavedTracks {
  io::TracksCsvWriter tracks;
  io::ObjectsCsvWriter objects;

  SavedTracks(const fs::path& out, const std::string& stem)
      : tracks(out / ("tracks-" + stem + ".csv")), objects(out / ("objects-" + stem + ".csv")) {}

  void write(const sim::SimulatedScan& scan, const pipeline::FrameResult& r) {
    const auto k = static_cast<std::uint64_t>(scan.index);
    for (const tracking::Hypothesis& h : r.hypotheses) {
      if (h.reported) tracks.write(runner::track_row(k, scan.scan.stamp_ns, h, r.origin));
    }
    for (const sim::ObjectTruth& t : scan.objects)
      objects.write(object_row(k, scan.scan.stamp_ns, t));
  }
};

// Runs the planned cases in order until all ran or a signal stopped one (which is dropped with
// its saved tracks: the outputs cover the finished runs only); writes timing.csv.
std::vector<BenchmarkCase> run_cases(const BenchmarkOptions& o, const core::Config& config,
                                     const std::vector<experiment::PlannedRun>& runs,
                                     experiment::BenchmarkCaseOptions& case_options,
                                     io::RunStatus& status) {
  const fs::path out = o.out;
  const bool progress = !o.quiet && !o.json;
  std::vector<BenchmarkCase> cases;
  io::OutputFile timing(out / "timing.csv");
  timing.write(experiment::kBenchmarkTimingHeader);
  for (const experiment::PlannedRun& run : runs) {
    if (StopSignals::requested()) break;
    const sim::Scenario& s = run.scenario;
    if (progress) {
      std::cerr << "scenario " << (run.validation ? std::string("V") : std::to_string(s.number))
                << " " << s.name << (run.moving() ? " (moving)" : " (static)") << " ..."
                << std::flush;
    }
    std::optional<SavedTracks> saved;
    case_options.on_scan = {};
    if (o.save_tracks) {
      saved.emplace(out, run.stem());
      case_options.on_scan = [&](const sim::SimulatedScan& scan, const pipeline::FrameResult& r) {
        saved->write(scan, r);
      };
    }
    BenchmarkCase c = experiment::run_benchmark_case(s, config, case_options);
    if (c.interrupted) {
      if (saved) {
        saved->tracks.discard();
        saved->objects.discard();
      }
      if (progress) std::cerr << " stopped by " << StopSignals::signal_name() << "\n";
      break;
    }
    c.validation = run.validation;
    status.scans_read += static_cast<std::uint64_t>(c.scans);
    status.scans_processed += static_cast<std::uint64_t>(c.scans);
    if (saved) {
      saved->tracks.close();
      saved->objects.close();
    }
    if (progress) {
      std::cerr << " " << c.scans << " scans, MOTA " << fixed(c.tracking.summary.mota(), 3)
                << ", simulate " << fixed(c.simulate_s, 1) << " s, pipeline "
                << fixed(c.pipeline_s, 1) << " s\n";
    }
    timing.write(experiment::timing_rows(c, case_label(c)));
    cases.push_back(std::move(c));
  }
  timing.close();
  return cases;
}

// The one-line-per-group summary on stdout.
void print_summary(const BenchmarkOptions& o, std::size_t runs_planned,
                   const std::vector<BenchmarkCase>& cases, const std::vector<Aggregate>& groups,
                   double wall_s, const std::string& stopped_by, bool plotted) {
  std::cout << "benchmark of " << cases.size() << " runs in " << fixed(wall_s, 1) << " s";
  if (!stopped_by.empty()) {
    std::cout << " (interrupted by " << stopped_by << " after " << cases.size() << " of "
              << runs_planned << " runs: the figures cover these runs only)";
  }
  std::cout << "\n";
  for (const Aggregate& g : groups) {
    std::cout << "  " << g.label << ": MOTA " << fixed(g.mot.mota(), 3) << ", MOTP "
              << fixed(g.mot.motp(), 3) << " m (x-y " << fixed(g.mot.horizontal_motp(), 3)
              << ", z bias " << fixed(g.mot.mean_vertical_error(), 3) << "), MT/PT/ML "
              << fixed(g.mot.mostly_tracked_ratio(), 2) << "/"
              << fixed(g.mot.partially_tracked_ratio(), 2) << "/"
              << fixed(g.mot.mostly_lost_ratio(), 2) << ", IDSW " << g.mot.switches << ", FP "
              << g.mot.false_positives << ", FN " << g.mot.misses << ", map preservation "
              << fixed(g.map.preservation_rate(), 4) << ", rejection "
              << fixed(g.map.rejection_rate(), 4) << "; moving objects only: MOTA "
              << fixed(g.moving_only.mota(), 3) << ", FP " << g.moving_only.false_positives
              << ", FN " << g.moving_only.misses;
    if (o.person_figures) {
      std::cout << "; person mode: MOTA " << fixed(g.person.mota(), 3) << ", FP "
                << g.person.false_positives << ", FN " << g.person.misses;
    }
    std::cout << "\n";
  }
  std::cout << "outputs: " << o.out << "/{report.md,results.json,timing.csv,config.yaml,run.json"
            << (plotted ? ",stage_times.png" : "") << "}\n";
}

void benchmark_into(const BenchmarkOptions& o, const core::Config& config,
                    const std::vector<experiment::PlannedRun>& runs, io::RunStatus& status) {
  const fs::path out = o.out;
  const std::string config_text = core::dump_config(config);
  io::write_file(out / "config.yaml", config_text);

  experiment::BenchmarkCaseOptions case_options;
  case_options.seed = o.seed;
  case_options.deskew = !o.no_deskew;
  case_options.odometry = o.odometry;
  case_options.evaluation.moving_radius_m = o.moving_radius_m;
  case_options.person_figures = o.person_figures;
  case_options.final_map = true;
  case_options.interrupt = &StopSignals::stop_flag();
  const auto start = std::chrono::steady_clock::now();
  const std::vector<BenchmarkCase> cases = run_cases(o, config, runs, case_options, status);
  if (cases.empty()) {
    throw core::InputError("benchmark stopped by " + StopSignals::signal_name() +
                           " before its first run finished: nothing to report");
  }
  const std::string stopped_by = StopSignals::signal_name();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // Built-ins and validation scenarios are summed apart: "all ..." are the built-ins only.
  const std::vector<Aggregate> groups = experiment::group_cases(cases);

  const bool plotted = !o.no_plot && plot_stage_times(out / "timing.csv", out / "stage_times.png");
  io::write_file(out / "report.md", report_markdown(o, cases, groups, wall_s, config_text, plotted,
                                                    runs.size(), stopped_by));

  experiment::ResultsHeader header;
  header.date = experiment::utc_minute_now();
  header.machine = experiment::machine_description();
  header.seed = o.seed;
  header.duration_s = o.duration_s;
  header.threshold_m = case_options.evaluation.threshold_m;
  header.moving_radius_m = case_options.evaluation.moving_radius_m;
  header.wall_s = wall_s;
  header.runs_planned = runs.size();
  header.interrupted = stopped_by;
  const nlohmann::ordered_json j =
      experiment::results_json(header, cases, groups, o.person_figures);
  io::write_file(out / "results.json", j.dump(2) + "\n");
  if (o.json) {
    std::cout << j.dump(2) << "\n";
    return;
  }
  print_summary(o, runs.size(), cases, groups, wall_s, stopped_by, plotted);
}

}  // namespace

void register_benchmark(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "benchmark",
      "simulate the built-in scenarios (static and moving sensor), run the pipeline with one "
      "configuration, and report the paper's Table II metrics, map metrics and time per stage; "
      "--validation/--scenario-files: the validation scenarios, as their own group");
  auto o = std::make_shared<BenchmarkOptions>();
  auto* scenarios_opt =
      cmd->add_option("--scenarios", o->scenarios,
                      "built-in scenarios to run (1-7; with scenario files: only when given)")
          ->delimiter(',')
          ->check(CLI::Range(1, 7))
          ->capture_default_str();
  cmd->add_option("--scenario-files", o->scenario_files,
                  "validation scenario files (YAML) to run with a static and a moving sensor, "
                  "reported as the validation group")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--validation", o->validation,
                "run the validation scenarios of config/validation/ (never tuned on; see "
                "docs/simulator.md)");
  cmd->add_option("--duration", o->duration_s,
                  "seconds to simulate per scenario (default: each scenario's full length)");
  cmd->add_option("--out", o->out, "output folder (created)")->capture_default_str();
  cmd->add_flag("--json", o->json, "print the results as JSON on stdout");
  cmd->add_option("--seed", o->seed, "simulator seed (actors, noise)")->capture_default_str();
  cmd->add_option("--sensors", o->sensors, "sensor motions to run: both, static or moving")
      ->check(CLI::IsMember({"both", "static", "moving"}))
      ->capture_default_str();
  cmd->add_flag("--no-plot", o->no_plot, "do not draw stage_times.png");
  cmd->add_flag("--no-deskew", o->no_deskew,
                "give moving-sensor scans to the pipeline without motion compensation");
  cmd->add_flag("--odometry", o->odometry,
                "estimate the sensor poses from the scans (docs/odometry.md), as `run` does for a "
                "recording without poses, instead of taking the simulator's; the odometry starts "
                "at the true pose of the first scan and compensates the scans itself");
  cmd->add_flag("--save-tracks", o->save_tracks,
                "also write tracks-<N>-<sensor>.csv and objects-<N>-<sensor>.csv per run");
  cmd->add_option("--moving-radius", o->moving_radius_m,
                  "for the \"moving objects only\" table: an object moves when its x-y position "
                  "leaves the disc of this radius around its first position, metres")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--person-figures", o->person_figures,
                "also report the tracks in person mode (hypotheses flagged person, standing or "
                "moving, against every person; `eval --hypotheses person`) as an extra table and "
                "person_mode in the JSON");
  cmd->add_flag("--quiet", o->quiet, "no progress on stderr");
  o->config.add_to(*cmd);
  cmd->callback([o, scenarios_opt] {
    o->scenarios_given = scenarios_opt->count() > 0;
    run_benchmark(*o);
  });
}

}  // namespace ringtrack::cli
