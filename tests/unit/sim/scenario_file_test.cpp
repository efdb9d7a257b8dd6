// Scenario YAML files and trajectory CSV files: round trips, shipped files, and errors that name
// the entry.

#include "ringtrack/sim/scenario_file.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ringtrack/core/error.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace ringtrack::sim {
namespace {

namespace fs = std::filesystem;

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const core::Error& e) {
    return e.what();
  }
  return "(no error)";
}

fs::path temp_dir(const std::string& name) {
  const fs::path p =
      fs::temp_directory_path() / ("ringtrack_sim_test_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

void write(const fs::path& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary);
  f << text;
}

TEST(ScenarioFile, ShippedFilesAreTheBuiltins) {
  const fs::path dir = fs::path(RINGTRACK_SOURCE_DIR) / "config" / "scenarios";
  for (const auto& info : builtin_scenarios()) {
    const fs::path file = dir / (std::to_string(info.number) + "-" + info.name + ".yaml");
    ASSERT_TRUE(fs::exists(file)) << file;
    Scenario loaded = load_scenario_file(file);
    loaded.number = info.number;  // files carry no number
    EXPECT_EQ(format_scenario_yaml(loaded), format_scenario_yaml(builtin_scenario(info.name)))
        << file;
  }
}

TEST(ScenarioFile, RoundTripKeepsEverything) {
  Scenario s = builtin_scenario("hall");
  s.sensor.motion = SensorMotion::kScripted;
  s.sensor.keyframes = {{0.0, {0, 0, 1.2}, {0, 0, 0}}, {5.0, {1, 0.5, 1.3}, {2, -1, 30}}};
  s.ground.amplitude_m = 0.2;
  s.drones = 2;
  const Scenario back = parse_scenario_yaml(format_scenario_yaml(s), "x.yaml");
  EXPECT_EQ(format_scenario_yaml(back), format_scenario_yaml(s));
  EXPECT_EQ(back.walls.size(), 4u);
  EXPECT_EQ(back.sensor.keyframes.size(), 2u);
  EXPECT_DOUBLE_EQ(back.sensor.keyframes[1].rpy_deg.z(), 30.0);
}

TEST(ScenarioFile, ErrorsNameTheEntry) {
  EXPECT_NE(error_of([] {
              (void)parse_scenario_yaml("boxes:\n  - {center_m: [1, 2], sise_m: [1, 1, 1]}\n",
                                        "a.yaml");
            }).find("a.yaml:2: boxes[0]: unknown key 'sise_m'"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)parse_scenario_yaml("duration_s: long\n", "a.yaml");
            }).find("duration_s: expected a number"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)parse_scenario_yaml("sensor: {motion: circle}\n", "a.yaml");
            }).find("motion"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)parse_scenario_yaml("colour: red\n", "a.yaml");
            }).find("unknown key 'colour'"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)parse_scenario_yaml("walls: [{from_m: [1, 2, 3]}]\n", "a.yaml");
            }).find("walls[0]: from_m: expected a list of 2 numbers"),
            std::string::npos);
  const fs::path dir = temp_dir("errors");
  write(dir / "neg.yaml",
        "cylinders:\n  - {center_m: [3, 3], radius_m: 0.3, height_m: 2}\n  - {center_m: [5, 3], "
        "radius_m: -0.3, height_m: 2}\n");
  const std::string neg = error_of([&] { (void)load_scenario_file(dir / "neg.yaml"); });
  EXPECT_NE(neg.find("neg.yaml: cylinders[1]: radius_m must be > 0"), std::string::npos) << neg;
  // A person whose trajectory starts inside a wall.
  write(dir / "walled.yaml",
        "walls:\n  - {from_m: [5, -2], to_m: [5, 2], height_m: 3, thickness_m: 0.4}\nactors: "
        "{people: 0, trajectories: t.csv}\n");
  write(dir / "t.csv",
        "t,id,class,x,y\n0,1,person,8,0\n5,1,person,8,3\n0,2,person,5.1,0.5\n4,2,person,8,-3\n");
  const std::string walled = error_of([&] { (void)load_scenario_file(dir / "walled.yaml"); });
  EXPECT_NE(walled.find("trajectory of id 2"), std::string::npos) << walled;
  EXPECT_NE(walled.find("inside walls[0]"), std::string::npos) << walled;
  fs::remove_all(dir);
}

TEST(TrajectoryCsv, ParsesGroupsAndRejectsBadRows) {
  const auto actors = parse_trajectories_csv(
      "t,id,class,x,y,z\n# a "
      "comment\n0,7,drone,1,2,5\n1,3,person,0,0\n2,7,drone,3,2,6\n2,3,person,1,0\n",
      "t.csv");
  ASSERT_EQ(actors.size(), 2u);
  EXPECT_EQ(actors[0].id, 3u);
  EXPECT_EQ(actors[0].waypoints.size(), 2u);
  EXPECT_TRUE(std::isnan(actors[0].waypoints[0].xyz_m.z()));
  EXPECT_EQ(actors[1].object_class, ObjectClass::kDrone);
  EXPECT_DOUBLE_EQ(actors[1].waypoints[1].xyz_m.z(), 6.0);
  EXPECT_NE(
      error_of([] { (void)parse_trajectories_csv("0,1,person,1\n", "t.csv"); }).find("t.csv:1:"),
      std::string::npos);
  EXPECT_NE(error_of([] {
              (void)parse_trajectories_csv("0,1,person,1,2\n0,1,person,2,2\n", "t.csv");
            }).find("t.csv:2: id 1: times must increase"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)parse_trajectories_csv("0,1,cat,1,2\n", "t.csv");
            }).find("unknown object class 'cat'"),
            std::string::npos);
  EXPECT_NE(error_of([] {
              (void)parse_trajectories_csv("0,0,person,1,2\n", "t.csv");
            }).find("id: expected"),
            std::string::npos);
  EXPECT_NE(
      error_of([] { (void)parse_trajectories_csv("0,1,person,1,x2\n", "t.csv"); }).find("field 5"),
      std::string::npos);
}

TEST(TrajectoryCsv, HeaderAfterCommentsAndBodyColumns) {
  // Comments and blank lines before the header; columns in any order; body values per actor,
  // given once or repeated, empty cells = not given.
  const auto actors = parse_trajectories_csv(
      "# generated by hand\n\n# second comment\n"
      "id,t,class,x,y,height_m,width_m,reflectivity\n"
      "3,0,person,1,2,1.62,0.5,\n"
      "3,1.5,person,2,2,,,0.7\n"
      "4,0,drone,5,5,,,0.2\n"
      "4,2,drone,6,5,,,\n"
      "5,0,person,8,8,1.9,,\n"
      "5,1,person,8,9,1.9,,\n",
      "t.csv");
  ASSERT_EQ(actors.size(), 3u);
  EXPECT_EQ(actors[0].id, 3u);
  ASSERT_EQ(actors[0].waypoints.size(), 2u);
  EXPECT_DOUBLE_EQ(actors[0].waypoints[1].t_s, 1.5);
  EXPECT_DOUBLE_EQ(actors[0].waypoints[1].xyz_m.x(), 2.0);
  EXPECT_TRUE(std::isnan(actors[0].waypoints[1].xyz_m.z()));
  EXPECT_DOUBLE_EQ(actors[0].height_m.value_or(0), 1.62);
  EXPECT_DOUBLE_EQ(actors[0].width_m.value_or(0), 0.5);
  EXPECT_DOUBLE_EQ(actors[0].reflectivity.value_or(0), 0.7);
  EXPECT_FALSE(actors[1].height_m);
  EXPECT_DOUBLE_EQ(actors[1].reflectivity.value_or(0), 0.2);
  EXPECT_DOUBLE_EQ(actors[2].height_m.value_or(0), 1.9);
  EXPECT_FALSE(actors[2].width_m);
  // Positional body columns without a header.
  const auto positional = parse_trajectories_csv(
      "# t,id,class,x,y,z,height_m,width_m,reflectivity\n0,1,person,1,1,,1.55,0.45,0.3\n"
      "1,1,person,2,1\n",
      "p.csv");
  ASSERT_EQ(positional.size(), 1u);
  EXPECT_DOUBLE_EQ(positional[0].height_m.value_or(0), 1.55);
  EXPECT_DOUBLE_EQ(positional[0].width_m.value_or(0), 0.45);
  EXPECT_DOUBLE_EQ(positional[0].reflectivity.value_or(0), 0.3);
}

TEST(TrajectoryCsv, BadBodyValuesNameFileLineAndColumn) {
  const std::string head = "# c\nt,id,class,x,y,height_m,width_m,reflectivity\n";
  const auto err = [&](const std::string& rows) {
    return error_of([&] { (void)parse_trajectories_csv(head + rows, "b.csv"); });
  };
  std::string e = err("0,1,person,0,0,3.1,,\n");
  EXPECT_NE(e.find("b.csv:3: field 6 (height_m): expected a height (m) in [0.5, 2.5], got '3.1'"),
            std::string::npos)
      << e;
  e = err("0,1,person,0,0,1.8,0.05,\n");
  EXPECT_NE(e.find("b.csv:3: field 7 (width_m): expected a width (m) in [0.2, 1.2]"),
            std::string::npos)
      << e;
  e = err("0,1,person,0,0,,,1.5\n");
  EXPECT_NE(e.find("b.csv:3: field 8 (reflectivity): expected a reflectivity in [0, 1]"),
            std::string::npos)
      << e;
  e = err("0,1,person,0,0,tall,,\n");
  EXPECT_NE(e.find("b.csv:3: field 6 (height_m): expected a number, got 'tall'"), std::string::npos)
      << e;
  e = err("0,2,robot,0,0,1.7,,\n");
  EXPECT_NE(e.find("b.csv:3: field 6 (height_m): a body height (m) applies to people and "
                   "distractors only, not to a robot"),
            std::string::npos)
      << e;
  e = err("0,1,person,0,0,1.7,,\n1,1,person,1,0,1.8,,\n");
  EXPECT_NE(e.find("b.csv:4: field 6 (height_m): id 1 already has 1.7 (line 3)"), std::string::npos)
      << e;
  e = err("0,1,person,0\n");
  EXPECT_NE(e.find("b.csv:3: expected 5-8 fields as the header says (4 fields)"), std::string::npos)
      << e;
  e = err("0,1,person,0,0,1.7,0.5,0.3,9\n");
  EXPECT_NE(e.find("(9 fields)"), std::string::npos) << e;
  e = error_of([] { (void)parse_trajectories_csv("# c\nt,id,class,x,y,heigth_m\n", "b.csv"); });
  EXPECT_NE(e.find("b.csv:2: header: unknown column 'heigth_m'"), std::string::npos) << e;
  e = error_of([] { (void)parse_trajectories_csv("t,id,class,x\n", "b.csv"); });
  EXPECT_NE(e.find("b.csv:1: header: column 'y' is missing"), std::string::npos) << e;
}

TEST(TrajectoryCsv, SegmentThroughACarIsRejectedWithTheFileName) {
  const fs::path dir = temp_dir("segment");
  write(dir / "s.yaml",
        "duration_s: 10\nactors: {trajectories: t.csv}\n"
        "boxes: [{center_m: [10, 0], size_m: [4.5, 1.8, 1.5]}]\n");
  // Both waypoints of id 2 are 3 m from the car; the segment runs through it.
  write(dir / "t.csv",
        "t,id,class,x,y\n0,1,person,6,6\n5,1,person,6,9\n0,2,person,10,3\n4,2,person,10,-3\n");
  const std::string e = error_of([&] { (void)load_scenario_file(dir / "s.yaml"); });
  EXPECT_NE(e.find("s.yaml: trajectory of id 2: segment t=0-4 s from (10, 3) to (10, -3) crosses "
                   "boxes[0]"),
            std::string::npos)
      << e;
  fs::remove_all(dir);
}

TEST(TrajectoryCsv, FormatReadsBackToTheSameActors) {
  const fs::path file =
      fs::path(RINGTRACK_SOURCE_DIR) / "config" / "validation" / "v4-parking.yaml";
  const Scenario s = load_scenario_file(file);
  ASSERT_GT(s.scripted.size(), 10u);
  std::vector<ScriptedActor> actors = s.scripted;
  actors.push_back({77, ObjectClass::kDrone, {{1.0, {2, 3, 4.5}}, {2.0, {3, 3, 5}}}});
  actors.back().reflectivity = 0.25;
  const std::string text = format_trajectories_csv(actors);
  const auto back = parse_trajectories_csv(text, "x.csv");
  EXPECT_EQ(format_trajectories_csv(back), text);
  ASSERT_EQ(back.size(), actors.size());
  EXPECT_EQ(back[3].height_m, actors[3].height_m);
  EXPECT_EQ(back[3].waypoints.back().xyz_m.x(), actors[3].waypoints.back().xyz_m.x());
  EXPECT_DOUBLE_EQ(back.back().waypoints[0].xyz_m.z(), 4.5);
}

TEST(TrajectoryCsv, ScenarioFileDrivesScriptedActors) {
  const fs::path dir = temp_dir("scripted");
  write(dir / "s.yaml",
        "duration_s: 3\nactors: {trajectories: t.csv}\nsensor: {range_noise_m: 0}\n");
  write(dir / "t.csv", "0,4,person,6,-1\n3,4,person,6,2\n");
  const Scenario s = resolve_scenario((dir / "s.yaml").string());
  Simulator sim(s, 1);
  ASSERT_EQ(sim.actors().size(), 1u);
  EXPECT_EQ(sim.actors()[0].id, 4u);
  for (int k = 0; k < 25; ++k) (void)sim.next();
  const auto out = sim.next();  // t = 2.5-2.6 s: y = -1 + t
  EXPECT_NEAR(out.objects.at(0).body_center_m.y(), 1.55, 0.06);
  EXPECT_GT(out.objects.at(0).hit_points, 10);
  fs::remove_all(dir);
}

TEST(ScenarioFile, AListAsKeyIsAnErrorNamingTheEntry) {
  // Found by fuzz_scenario: a flow map whose key is a list escaped as yaml-cpp's own exception
  // (the CLI's "internal error", exit 2) instead of a ConfigError naming the entry.
  EXPECT_EQ(error_of([] {
              (void)parse_scenario_yaml("boxes:\n  - {center_m: [1, 2], [-25, 20]: 3}\n", "a.yaml");
            }),
            "a.yaml:2: boxes[0]: expected a key name, got a list or map as key");
  EXPECT_EQ(error_of([] { (void)parse_scenario_yaml("{a: 1}: 2\n", "b.yaml"); }),
            "b.yaml:1: scenario: expected a key name, got a list or map as key");
}

TEST(ScenarioFile, UpperBoundsNameTheKey) {
  // Issue 16: `duration_s: 1e12` simulated until killed. Each bound is an error naming the key.
  const fs::path dir = temp_dir("bounds");
  const auto error_for = [&](const std::string& yaml) {
    write(dir / "b.yaml", yaml);
    return error_of([&] { (void)load_scenario_file(dir / "b.yaml"); });
  };
  const std::string prefix = (dir / "b.yaml").string() + ": ";
  EXPECT_EQ(error_for("duration_s: 1e12\n"),
            prefix + "scenario: duration_s must be at most 86400 (got 1e+12)");
  EXPECT_EQ(error_for("actors: {people: 5000}\n"),
            prefix + "actors: people must be in [0, 1000] (got 5000)");
  EXPECT_EQ(error_for("actors: {drones: -1}\n"),
            prefix + "actors: drones must be in [0, 1000] (got -1)");
  EXPECT_EQ(error_for("world_radius_m: 1e9\n"),
            prefix + "scenario: world_radius_m must be at most 10000 (got 1e+09)");
  EXPECT_EQ(error_for("area_m: [20000, 10]\n"),
            prefix + "scenario: area_m[0] must be at most 10000 (got 20000)");
  EXPECT_EQ(error_for("sensor: {motion: figure8, max_speed_mps: 300}\n"),
            prefix + "sensor: max_speed_mps must be at most 100 (got 300)");
  // The bounds themselves are accepted.
  EXPECT_EQ(error_for("duration_s: 86400\nactors: {people: 1000, robots: 1000}\n"), "(no error)");
  fs::remove_all(dir);
}

TEST(CliSimulate, EndlessDurationIsAnErrorNamingTheKey) {
  const fs::path cli = RINGTRACK_CLI_PATH;
  if (!fs::exists(cli)) GTEST_SKIP() << "CLI not built: " << cli;
  const fs::path dir = temp_dir("endless");
  const std::string cmd = cli.string() + " simulate 1 --duration 1e12 --out " +
                          (dir / "out").string() + " 2> " + (dir / "err.txt").string();
  const int status = std::system(cmd.c_str());
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << status;
  std::ifstream err(dir / "err.txt");
  std::string line;
  std::getline(err, line);
  EXPECT_NE(line.find("duration_s must be at most 86400 (got 1e+12)"), std::string::npos) << line;
  EXPECT_FALSE(fs::exists(dir / "out" / "sequence.yaml"));
  fs::remove_all(dir);
}

TEST(CliSimulate, SameSeedGivesByteIdenticalFolders) {
  const fs::path cli = RINGTRACK_CLI_PATH;
  if (!fs::exists(cli)) GTEST_SKIP() << "CLI not built: " << cli;
  const fs::path dir = temp_dir("cli");
  const auto run = [&](const std::string& out, const std::string& seed) {
    const std::string cmd = cli.string() + " simulate 4 --moving-sensor --duration 0.5 --seed " +
                            seed + " --out " + (dir / out).string() + " > /dev/null";
    return std::system(cmd.c_str());
  };
  ASSERT_EQ(run("a", "3"), 0);
  ASSERT_EQ(run("b", "3"), 0);
  ASSERT_EQ(run("c", "4"), 0);
  const auto slurp = [](const fs::path& p) {
    std::ifstream f(p, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
  };
  int files = 0;
  bool any_differs = false;
  for (const auto& e : fs::recursive_directory_iterator(dir / "a")) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), dir / "a");
    // run.json records how the folder was made (the command line, the clock), not its data.
    if (rel == "run.json") continue;
    EXPECT_EQ(slurp(e.path()), slurp(dir / "b" / rel)) << rel;
    if (rel.string().find("scans") == 0 && slurp(e.path()) != slurp(dir / "c" / rel))
      any_differs = true;
    ++files;
  }
  EXPECT_GE(files, 9);  // 5 scans + yaml, stamps, poses, objects
  EXPECT_TRUE(any_differs);
  // A scenario with scripted actors: the folder's scenario.yaml (with its trajectories.csv)
  // reads back to the same actors.
  const fs::path v2 =
      fs::path(RINGTRACK_SOURCE_DIR) / "config" / "validation" / "v2-chat-circles.yaml";
  ASSERT_EQ(std::system((cli.string() + " simulate " + v2.string() + " --duration 0.3 --out " +
                         (dir / "v").string() + " > /dev/null")
                            .c_str()),
            0);
  const Scenario again = load_scenario_file(dir / "v" / "scenario.yaml");
  EXPECT_EQ(format_trajectories_csv(again.scripted),
            format_trajectories_csv(load_scenario_file(v2).scripted));
  // Bad arguments fail with one line and exit code 1.
  EXPECT_NE(std::system(
                (cli.string() + " simulate nowhere --out " + (dir / "d").string() + " 2> /dev/null")
                    .c_str()),
            0);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ringtrack::sim
