// The benchmark engine and evaluation: recorded scenarios run many times in-process (the
// tuner's trials), and objects.csv / tracks.csv evaluated as `ringtrack eval` does.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/experiment/aggregate.hpp"
#include "ringtrack/experiment/benchmark_case.hpp"
#include "ringtrack/experiment/evaluate_files.hpp"
#include "ringtrack/experiment/plan.hpp"
#include "ringtrack/experiment/recorded_scenario.hpp"
#include "ringtrack/experiment/recorded_sequence.hpp"
#include "ringtrack/experiment/results_json.hpp"
#include "ringtrack/io/run_status.hpp"
#include "ringtrack/version.hpp"
#include "sim_scenario.hpp"

namespace ringtrack::python {
namespace {

// A recording with the identity the benchmark reports it under: a simulated scenario run, or a
// sequence folder with objects.csv.
struct Recorded {
  std::shared_ptr<const experiment::RecordedScenario> scans;
  std::shared_ptr<const experiment::RecordedSequence> sequence;
  bool validation{false};
  std::string stem;
  [[nodiscard]] std::string name() const {
    return scans ? scans->scenario().name : sequence->name();
  }
  [[nodiscard]] bool moving() const { return scans ? scans->moving() : sequence->moving(); }
  [[nodiscard]] std::size_t size() const { return scans ? scans->size() : sequence->size(); }
  [[nodiscard]] std::size_t memory_bytes() const {
    return scans ? scans->memory_bytes() : sequence->memory_bytes();
  }
};

Recorded record(const experiment::PlannedRun& run, std::uint64_t seed, bool deskew) {
  return {std::make_shared<experiment::RecordedScenario>(run.scenario, seed, deskew), nullptr,
          run.validation, run.stem()};
}

experiment::BenchmarkCaseOptions case_options(bool person_figures, double threshold_m,
                                              double moving_radius_m) {
  experiment::BenchmarkCaseOptions o;
  o.person_figures = person_figures;
  o.evaluation.threshold_m = threshold_m;
  o.evaluation.moving_radius_m = moving_radius_m;
  return o;
}

experiment::BenchmarkCase run_one(const Recorded& r, const core::Config& config,
                                  const experiment::BenchmarkCaseOptions& options) {
  experiment::BenchmarkCase c = r.scans
                                    ? experiment::run_benchmark_case(*r.scans, config, options)
                                    : experiment::run_benchmark_case(*r.sequence, config, options);
  c.validation = r.validation;
  return c;
}

py::object case_result(const experiment::BenchmarkCase& c, const std::string& stem) {
  nlohmann::ordered_json j = experiment::case_json(c);
  j["stem"] = stem;
  return to_python(j);
}

std::vector<Recorded> record_runs(const std::vector<int>& builtins,
                                  const std::vector<std::string>& files,
                                  std::optional<double> duration_s, const std::string& sensors,
                                  std::uint64_t seed, bool deskew) {
  if (sensors != "both" && sensors != "static" && sensors != "moving") {
    throw core::ConfigError("sensors: expected both, static or moving, got '" + sensors + "'");
  }
  experiment::PlanOptions plan;
  plan.builtins = builtins;
  plan.builtins_given = !files.empty() && !builtins.empty();
  if (files.empty() && builtins.empty()) {
    throw core::ConfigError("record_runs: no scenarios (builtins and scenario_files are empty)");
  }
  plan.scenario_files = files;
  plan.duration_s = duration_s;
  plan.with_static = sensors != "moving";
  plan.with_moving = sensors != "static";
  const std::vector<experiment::PlannedRun> runs = experiment::plan_runs(plan);
  std::vector<Recorded> out;
  py::gil_scoped_release release;
  for (const experiment::PlannedRun& run : runs) out.push_back(record(run, seed, deskew));
  return out;
}

void bind_recorded(py::module_& m) {
  py::class_<Recorded>(m, "RecordedScenario",
                       "A scenario run simulated once and kept in memory (compact), to run the "
                       "pipeline on it many times with the same scans.")
      .def(py::init([](const std::string& scenario, std::uint64_t seed,
                       std::optional<double> duration_s, bool moving, bool deskew) {
             experiment::PlannedRun run{scenario_from(scenario, duration_s, moving), false};
             py::gil_scoped_release release;
             return record(run, seed, deskew);
           }),
           py::arg("scenario"), py::arg("seed") = 1, py::arg("duration_s") = py::none(),
           py::arg("moving") = false, py::arg("deskew") = true)
      .def_readonly("stem", &Recorded::stem, "e.g. \"3-static\", \"V-plaza-moving\"")
      .def_readonly("validation", &Recorded::validation)
      .def_static(
          "from_sequence",
          [](const std::string& folder) {
            Recorded r;
            {
              py::gil_scoped_release release;
              r.sequence = std::make_shared<experiment::RecordedSequence>(folder);
            }
            r.stem = "S-" + r.sequence->name();
            return r;
          },
          py::arg("folder"),
          "A sequence folder with objects.csv, read once (deskewed as `ringtrack run` does).")
      .def_property_readonly("name", &Recorded::name)
      .def_property_readonly("moving", &Recorded::moving)
      .def_property_readonly("memory_bytes", &Recorded::memory_bytes)
      .def("__len__", &Recorded::size);
  m.def("record_runs", &record_runs, py::arg("builtins") = std::vector<int>{1, 2, 3, 4, 5, 6, 7},
        py::arg("scenario_files") = std::vector<std::string>{}, py::arg("duration_s") = py::none(),
        py::arg("sensors") = "both", py::arg("seed") = 1, py::arg("deskew") = true,
        "The benchmark's runs (each scenario with a static and a moving sensor), simulated once: "
        "built-ins (numbers 1-7) and scenario files (the validation group).");
  m.def("scenario_files_in", &experiment::scenario_files_in, py::arg("folder"),
        "The *.yaml scenario files of a folder, sorted.");
}

void bind_runs(py::module_& m) {
  m.def(
      "run_case",
      [](const Recorded& r, const core::Config& config, bool person_figures, double threshold_m,
         double moving_radius_m) {
        core::validate_config(config);
        const auto options = case_options(person_figures, threshold_m, moving_radius_m);
        experiment::BenchmarkCase c;
        {
          py::gil_scoped_release release;
          c = run_one(r, config, options);
        }
        return case_result(c, r.stem);
      },
      py::arg("recorded"), py::arg("config"), py::arg("person_figures") = false,
      py::arg("threshold_m") = 0.5, py::arg("moving_radius_m") = 1.0,
      "Runs a fresh pipeline on every scan and evaluates (paper mode): a dict as one case of "
      "`ringtrack benchmark`'s results.json.");
  m.def(
      "run_cases",
      [](const std::vector<Recorded>& runs, const core::Config& config, bool person_figures,
         double threshold_m, double moving_radius_m) {
        core::validate_config(config);
        const auto options = case_options(person_figures, threshold_m, moving_radius_m);
        std::vector<experiment::BenchmarkCase> cases;
        {
          py::gil_scoped_release release;
          for (const Recorded& r : runs) cases.push_back(run_one(r, config, options));
        }
        nlohmann::ordered_json j;
        j["cases"] = nlohmann::ordered_json::array();
        for (std::size_t i = 0; i < cases.size(); ++i) {
          j["cases"].push_back(experiment::case_json(cases[i]));
          j["cases"].back()["stem"] = runs[i].stem;
        }
        j["groups"] = experiment::groups_json(experiment::group_cases(cases), person_figures);
        return to_python(j);
      },
      py::arg("runs"), py::arg("config"), py::arg("person_figures") = false,
      py::arg("threshold_m") = 0.5, py::arg("moving_radius_m") = 1.0,
      "run_case over several recordings, with the benchmark's groups (sums, never averages): "
      "{'cases': [...], 'groups': {'all static': ..., ...}}.");
}

void bind_evaluate(py::module_& m) {
  m.def(
      "evaluate",
      [](const std::string& objects_csv, const std::string& tracks_csv, double threshold_m,
         const std::string& hypotheses, const std::string& target_class, std::int64_t min_points,
         double moving_radius_m, bool ignore_stamps) {
        experiment::FileEvalOptions o;
        o.evaluation.threshold_m = threshold_m;
        o.evaluation.hypotheses = eval::parse_selection(hypotheses);
        o.evaluation.target_class = target_class;
        o.evaluation.min_points = min_points;
        o.evaluation.moving_radius_m = moving_radius_m;
        o.ignore_stamps = ignore_stamps;
        const eval::TrackingEvalResult r =
            experiment::evaluate_track_files(objects_csv, tracks_csv, o);
        nlohmann::ordered_json j;
        j["hypotheses_total"] = r.hypotheses_total;
        j["hypotheses_evaluated"] = r.hypotheses_evaluated;
        j["metrics"] = experiment::metrics_json(r.summary);
        j["moving_only"] =
            experiment::moving_only_json(r.moving_objects, r.still_objects, r.moving_only);
        return to_python(j);
      },
      py::arg("objects_csv"), py::arg("tracks_csv"), py::arg("threshold_m") = 0.5,
      py::arg("hypotheses") = "dynamic", py::arg("target_class") = "person",
      py::arg("min_points") = 1, py::arg("moving_radius_m") = 1.0, py::arg("ignore_stamps") = false,
      "CLEAR MOT, MT/PT/ML and identity metrics of tracks.csv against objects.csv, as "
      "`ringtrack eval --json` (docs/evaluation.md).");
  m.def(
      "map_rates",
      [](std::int64_t static_points, std::int64_t static_kept, std::int64_t dynamic_points,
         std::int64_t dynamic_removed) {
        eval::MapCounts c;
        c.static_points = static_points;
        c.static_kept = static_kept;
        c.dynamic_points = dynamic_points;
        c.dynamic_removed = dynamic_removed;
        return to_python(experiment::map_json(c));
      },
      py::arg("static_points"), py::arg("static_kept"), py::arg("dynamic_points"),
      py::arg("dynamic_removed"), "Map preservation and rejection from point counts.");
}

}  // namespace

// run.json for an output folder written from Python (`ringtrack tune`): the CLI's writer, so
// the file is the same (docs/formats.md) and every write is atomic.
void bind_run_status(py::module_& m) {
  py::class_<io::RunStatusFile>(m, "RunStatusFile",
                                "run.json of an output folder: whether its outputs are whole "
                                "(docs/formats.md).")
      .def(py::init([](const std::string& path, const std::string& command,
                       const std::vector<std::string>& arguments) {
             io::RunStatus status;
             status.command = command;
             status.arguments = arguments;
             status.version = kVersion;
             return io::RunStatusFile(path, status);
           }),
           py::arg("path"), py::arg("command"), py::arg("arguments"))
      .def("start", &io::RunStatusFile::start, "Writes it as running (complete: false).")
      .def("finish", &io::RunStatusFile::finish, py::arg("signal") = "",
           "Marks the outputs whole: finished, or interrupted by signal (\"SIGINT\", "
           "\"SIGTERM\") after writing them.")
      .def("fail", &io::RunStatusFile::fail, py::arg("error"),
           "Marks the run failed (not complete) with the error; never raises.");
}

void bind_experiment(py::module_& m) {
  bind_recorded(m);
  bind_runs(m);
  bind_evaluate(m);
  bind_run_status(m);
}

}  // namespace ringtrack::python
