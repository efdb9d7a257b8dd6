// `ringtrack benchmark` end to end: a short run of two scenarios must write a report with the
// Table II rows, the paper's figures and the stage times, and its numbers must equal those of
// `ringtrack simulate` + `ringtrack run` + `ringtrack eval` on the same scenarios and seed.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "support/run_command.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;

std::string read(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class BenchmarkCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(testing::make_temp_dir("ringtrack_benchmark_cli"));
    result_ = new testing::CommandResult(run_command(
        kCli +
        " benchmark --scenarios 1,7 --duration 3 --seed 5 --no-plot --person-figures --json "
        "--out " +
        (*dir_ / "bench").string()));
  }
  static void TearDownTestSuite() {
    std::error_code ec;
    fs::remove_all(*dir_, ec);
    delete result_;
    delete dir_;
  }
  static fs::path* dir_;
  static testing::CommandResult* result_;
};

fs::path* BenchmarkCli::dir_ = nullptr;
testing::CommandResult* BenchmarkCli::result_ = nullptr;

TEST_F(BenchmarkCli, WritesReportTimingAndJson) {
  ASSERT_EQ(result_->exit_code, 0) << result_->err;
  const fs::path out = *dir_ / "bench";
  for (const char* f : {"report.md", "results.json", "timing.csv", "config.yaml", "run.json"}) {
    EXPECT_TRUE(fs::is_regular_file(out / f)) << f;
  }
  // Issue 16: the folder says its outputs are whole.
  const auto status = nlohmann::json::parse(read(out / "run.json"));
  EXPECT_EQ(status["complete"], true);
  EXPECT_EQ(status["command"], "benchmark");
  EXPECT_EQ(status["scans"]["processed"], 4 * 30);
  const auto j = nlohmann::json::parse(result_->out);
  ASSERT_EQ(j["cases"].size(), 4u);  // two scenarios x static/moving
  EXPECT_EQ(j["cases"][0]["scenario"], 1);
  EXPECT_EQ(j["cases"][0]["sensor"], "static");
  EXPECT_EQ(j["cases"][1]["sensor"], "moving");
  EXPECT_EQ(j["cases"][2]["scenario"], 7);
  for (const auto& c : j["cases"]) {
    EXPECT_EQ(c["scans"], 30);
    for (const char* stage : {"segmentation", "detection", "tracking", "mapping", "total"}) {
      const auto& t = c["times"][stage];
      EXPECT_LE(t["median_ms"].get<double>(), t["p95_ms"].get<double>()) << stage;
      EXPECT_LE(t["p95_ms"].get<double>(), t["max_ms"].get<double>()) << stage;
    }
    const auto& m = c["map"];
    EXPECT_GT(m["static_points"].get<long>(), 0);
    EXPECT_LE(m["static_kept"].get<long>(), m["static_points"].get<long>());
    EXPECT_LE(m["dynamic_removed"].get<long>(), m["dynamic_points"].get<long>());
  }
  // Groups are sums of their cases.
  long fp = 0;
  for (const auto& c : j["cases"]) fp += c["metrics"]["false_positives"].get<long>();
  EXPECT_EQ(j["groups"]["overall"]["metrics"]["false_positives"].get<long>(), fp);
  EXPECT_EQ(j["paper"][0]["mota"].get<double>(), 0.677);

  // One timing row per scan and case, plus the header.
  const std::string timing = read(out / "timing.csv");
  EXPECT_EQ(timing.rfind("case,scenario,sensor,scan,segmentation_ms,detection_ms,tracking_ms,"
                         "mapping_ms,total_ms\n",
                         0),
            0u);
  EXPECT_EQ(std::count(timing.begin(), timing.end(), '\n'), 1 + 4 * 30);

  const std::string report = read(out / "report.md");
  for (const char* needle :
       {"## Accuracy (as the paper's Table II)", "| 1 empty-field (static) | 30 |",
        "| 7 hall (moving) | 30 |", "**all static**", "**all moving**", "**overall**",
        "paper: simulated, static sensor | 0.677 | 0.044 | 0.75 / 0.25 / 0.00",
        "paper: simulated, moving sensor | 0.533 | 0.033 | 0.57 / 0.40 / 0.03",
        "InLiDa (real, indoor; not comparable) | 0.562", "## Time per stage (ms per scan)",
        "## Accuracy in person mode (standing people included)"}) {
    EXPECT_NE(report.find(needle), std::string::npos) << needle;
  }
}

// Horizontal MOTP, vertical error and the moving-objects-only figures, per run and per group.
TEST_F(BenchmarkCli, ReportsHorizontalMotpAndMovingObjectsOnly) {
  ASSERT_EQ(result_->exit_code, 0) << result_->err;
  const auto j = nlohmann::json::parse(result_->out);
  EXPECT_EQ(j["moving_radius_m"].get<double>(), 1.0);
  long fp = 0;
  long gt = 0;
  long moving_objects = 0;
  for (const auto& c : j["cases"]) {
    const auto& m = c["metrics"];
    ASSERT_FALSE(m["motp"].is_null());
    // Per pair the x-y distance and |dz| are at most the 3-D distance; so are their means.
    EXPECT_LE(m["motp_horizontal"].get<double>(), m["motp"].get<double>() + 1e-12);
    EXPECT_LE(std::abs(m["mean_vertical_error"].get<double>()), m["motp"].get<double>() + 1e-12);
    const auto& r = c["moving_only"];
    EXPECT_EQ(r["moving_objects"].get<long>() + r["never_moving_objects"].get<long>(),
              m["gt_objects"].get<long>());
    EXPECT_EQ(r["metrics"]["gt_objects"], r["moving_objects"]);
    EXPECT_LE(r["metrics"]["gt_presences"].get<long>(), m["gt_presences"].get<long>());
    EXPECT_LE(r["metrics"]["false_positives"].get<long>(), m["false_positives"].get<long>());
    fp += r["metrics"]["false_positives"].get<long>();
    gt += r["metrics"]["gt_presences"].get<long>();
    moving_objects += r["moving_objects"].get<long>();
  }
  EXPECT_GT(moving_objects, 0) << "a vacuous restriction";
  const auto& overall = j["groups"]["overall"]["moving_only"];
  EXPECT_EQ(overall["metrics"]["false_positives"].get<long>(), fp);
  EXPECT_EQ(overall["metrics"]["gt_presences"].get<long>(), gt);
  EXPECT_EQ(overall["moving_objects"].get<long>(), moving_objects);

  const std::string report = read(*dir_ / "bench" / "report.md");
  for (const char* needle :
       {"| scenario | scans | MOTA | MOTP (m) | MOTP x-y (m) | z bias (m) | MT / PT / ML |",
        "## Accuracy on moving objects only", "leaves a disc of radius 1.00 m",
        "| scenario | objects | MOTA | MOTP (m) | MOTP x-y (m) | z bias (m) |",
        "## Static map at the end of the run"}) {
    EXPECT_NE(report.find(needle), std::string::npos) << needle;
  }
  // Two tables with a row per run and per group.
  std::size_t rows = 0;
  for (std::size_t at = report.find("| 7 hall (moving) |"); at != std::string::npos;
       at = report.find("| 7 hall (moving) |", at + 1)) {
    ++rows;
  }
  EXPECT_EQ(rows, 5u);  // accuracy, moving objects only, person mode, final map, time per stage
  // The final-map figures count the same points as the per-scan ones.
  const auto& final_map = j["groups"]["overall"]["final_map"];
  ASSERT_TRUE(final_map.is_object());
  EXPECT_EQ(final_map["static_points"], j["groups"]["overall"]["map"]["static_points"]);
  EXPECT_EQ(final_map["dynamic_points"], j["groups"]["overall"]["map"]["dynamic_points"]);
}

// Counts of the benchmark against the file-based tools: equal for a static sensor. A moving
// sensor's scans are deskewed from different poses on the two paths (below), which moves points by
// fractions of a millimetre; a threshold test (the recent views' column under a far hit, whose
// box edge a beam grazes) may then decide one cluster differently: one presence in 137 of the
// first scenario's person mode, measured. So a moving run's counts may differ by 2 %, at least 2.
void expect_counts_agree(const nlohmann::json& bench, const nlohmann::json& files, bool moving,
                         const std::string& what) {
  const long a = bench.get<long>();
  const long b = files.get<long>();
  if (!moving) {
    EXPECT_EQ(a, b) << what;
    return;
  }
  EXPECT_LE(std::abs(a - b), std::max(2L, std::max(a, b) / 50)) << what << ": " << a << " vs " << b;
}

// The benchmark's in-memory path must give what the file-based tools give.
TEST_F(BenchmarkCli, MatchesSimulateRunEval) {
  ASSERT_EQ(result_->exit_code, 0) << result_->err;
  const auto bench = nlohmann::json::parse(result_->out);
  // Moving sensor: the benchmark deskews with the simulator's exact poses, `run` with the poses
  // of the sequence folder (this scan's and the next one's) and its nominal column times.
  for (const int k : {0, 1, 2, 3}) {
    const auto& c = bench["cases"][static_cast<std::size_t>(k)];
    ASSERT_GT(c["metrics"]["matches"].get<long>(), 0) << "a vacuous comparison";
    const bool moving = c["sensor"] == "moving";
    const std::string scenario =
        std::to_string(c["scenario"].get<int>()) + (moving ? "-moving" : "");
    const fs::path seq = *dir_ / ("seq" + scenario);
    const fs::path run = *dir_ / ("run" + scenario);
    auto r = run_command(kCli + " simulate " + std::to_string(c["scenario"].get<int>()) +
                         (moving ? " --moving-sensor" : "") + " --duration 3 --seed 5 --out " +
                         seq.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = run_command(kCli + " run " + seq.string() + " --quiet --out " + run.string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.out.find("deskew           30 of 30 scans"), std::string::npos) << r.out;
    r = run_command(kCli + " eval --json --gt " + seq.string() + " --tracks " +
                    (run / "tracks.csv").string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto ev = nlohmann::json::parse(r.out)["overall"];
    const auto& m = c["metrics"];
    for (const char* key : {"matches", "false_positives", "misses", "id_switches", "mostly_tracked",
                            "partially_tracked", "mostly_lost", "gt_objects", "hypotheses",
                            "gt_presences", "hypothesis_presences"}) {
      expect_counts_agree(m[key], ev[key], moving, "scenario " + scenario + ": " + key);
    }
    if (!m["mota"].is_null()) {
      EXPECT_NEAR(m["mota"].get<double>(), ev["mota"].get<double>(), moving ? 0.02 : 1e-9)
          << scenario;
    }
    if (!m["motp"].is_null()) {
      // tracks.csv and objects.csv round positions to millimetres or finer.
      EXPECT_NEAR(m["motp"].get<double>(), ev["motp"].get<double>(), 1e-3) << scenario;
    }
    // The moving-objects-only figures agree too (objects.csv carries the true centres).
    const auto evj = nlohmann::json::parse(r.out);
    EXPECT_EQ(c["moving_only"]["moving_objects"], evj["overall_moving_only"]["moving_objects"]);
    const auto& bm = c["moving_only"]["metrics"];
    const auto& em = evj["overall_moving_only"]["metrics"];
    for (const char* key : {"matches", "false_positives", "misses", "id_switches", "gt_presences",
                            "hypothesis_presences"}) {
      expect_counts_agree(bm[key], em[key], moving,
                          "scenario " + scenario + ": moving only " + key);
    }
    // --person-figures: the same counts as `eval --hypotheses person` on run's tracks.csv.
    r = run_command(kCli + " eval --json --hypotheses person --gt " + seq.string() + " --tracks " +
                    (run / "tracks.csv").string());
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const auto pe = nlohmann::json::parse(r.out)["overall"];
    ASSERT_TRUE(c.contains("person_mode")) << scenario;
    const auto& pm = c["person_mode"]["metrics"];
    for (const char* key : {"matches", "false_positives", "misses", "id_switches", "gt_presences",
                            "hypothesis_presences", "hypotheses"}) {
      expect_counts_agree(pm[key], pe[key], moving,
                          "scenario " + scenario + ": person mode " + key);
    }
    EXPECT_EQ(pm["gt_presences"], m["gt_presences"]) << "the same ground truth";
    if (!m["motp_horizontal"].is_null()) {
      const double tolerance = moving ? 3e-3 : 1e-3;
      EXPECT_NEAR(m["motp_horizontal"].get<double>(), ev["motp_horizontal"].get<double>(),
                  tolerance);
      EXPECT_NEAR(m["mean_vertical_error"].get<double>(), ev["mean_vertical_error"].get<double>(),
                  tolerance);
    }
  }
}

// Validation scenarios (config/validation/): simulated like the built-ins, reported apart.
TEST(BenchmarkValidationCli, RunsTheValidationSetAsItsOwnGroup) {
  const fs::path dir = testing::make_temp_dir("ringtrack_benchmark_validation");
  const auto r = run_command(kCli + " benchmark --validation --duration 2 --seed 3 --no-plot " +
                             "--json --out " + (dir / "v").string());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j["cases"].size(), 10u);  // five scenarios x static/moving, no built-ins
  EXPECT_EQ(j["cases"][0]["name"], "v1-plaza-groups");
  EXPECT_EQ(j["cases"][0]["sensor"], "static");
  EXPECT_EQ(j["cases"][1]["sensor"], "moving");
  EXPECT_EQ(j["cases"][9]["name"], "v5-far-field");
  long fp = 0;
  for (const auto& c : j["cases"]) {
    EXPECT_TRUE(c["validation"].get<bool>());
    EXPECT_EQ(c["scans"], 20);
    fp += c["metrics"]["false_positives"].get<long>();
  }
  EXPECT_FALSE(j["groups"].contains("all static"));
  EXPECT_FALSE(j["cases"][0].contains("person_mode"));  // only with --person-figures
  EXPECT_TRUE(j["groups"].contains("validation static"));
  EXPECT_TRUE(j["groups"].contains("validation moving"));
  EXPECT_EQ(j["groups"]["validation overall"]["metrics"]["false_positives"].get<long>(), fp);
  const std::string report = read(dir / "v" / "report.md");
  EXPECT_EQ(report.find("person mode"), std::string::npos);
  for (const char* needle :
       {"| V v1-plaza-groups (static) | 20 |", "| V v4-parking (moving) | 20 |",
        "**validation static**", "**validation moving**", "never used to tune the defaults"}) {
    EXPECT_NE(report.find(needle), std::string::npos) << needle;
  }

  // Scenario files beside chosen built-ins: both groups, each summing only its own cases.
  const std::string file = std::string(RINGTRACK_SOURCE_DIR) + "/config/validation/v4-parking.yaml";
  const auto both =
      run_command(kCli + " benchmark --scenarios 7 --scenario-files " + file +
                  " --sensors static --duration 1 --no-plot --json --out " + (dir / "b").string());
  ASSERT_EQ(both.exit_code, 0) << both.err;
  const auto k = nlohmann::json::parse(both.out);
  ASSERT_EQ(k["cases"].size(), 2u);
  EXPECT_EQ(k["cases"][0]["name"], "hall");
  EXPECT_FALSE(k["cases"][0]["validation"].get<bool>());
  EXPECT_EQ(k["cases"][1]["name"], "v4-parking");
  EXPECT_EQ(k["groups"]["all static"]["metrics"]["gt_presences"],
            k["cases"][0]["metrics"]["gt_presences"]);
  EXPECT_EQ(k["groups"]["validation static"]["metrics"]["gt_presences"],
            k["cases"][1]["metrics"]["gt_presences"]);

  // A scenario file whose path runs through a parked car fails before anything runs.
  std::ofstream(dir / "bad.yaml") << "duration_s: 5\nactors: {trajectories: bad.csv}\n"
                                     "boxes: [{center_m: [10, 0], size_m: [4.5, 1.8, 1.5]}]\n";
  std::ofstream(dir / "bad.csv")
      << "# a person\nt,id,class,x,y\n0,1,person,10,4\n5,1,person,10,-4\n";
  const auto bad = run_command(kCli + " benchmark --scenario-files " + (dir / "bad.yaml").string() +
                               " --duration 1 --no-plot --out " + (dir / "c").string());
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("bad.yaml: trajectory of id 1: segment t=0-5 s"), std::string::npos)
      << bad.err;
  EXPECT_NE(bad.err.find("crosses boxes[0]"), std::string::npos) << bad.err;
  EXPECT_EQ(std::count(bad.err.begin(), bad.err.end(), '\n'), 1) << bad.err;
  std::error_code ec;
  fs::remove_all(dir, ec);
}

}  // namespace
}  // namespace ringtrack
