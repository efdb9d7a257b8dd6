// `ringtrack eval` end to end: small hand-made objects.csv / tracks.csv / MOTChallenge files with
// hand-computed metrics, sequence lists, and the error exits.

#include <gtest/gtest.h>

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
const std::string kObjectsHeader =
    "scan,stamp,id,class,points,x,y,z,min_x,min_y,min_z,max_x,max_y,max_z,true_x,true_y,true_z,"
    "moving";
const std::string kTracksHeader =
    "scan,stamp,id,x,y,z,vx,vy,vz,min_x,min_y,min_z,max_x,max_y,max_z,dynamic,ever_dynamic,age,"
    "points";

void write(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  ASSERT_TRUE(out.good()) << path;
}

std::string stamp(int scan) {
  return "0." + std::to_string(scan) + "00000000";
}

std::string object(int scan, int id, const std::string& cls, int points, double x, double y) {
  std::ostringstream s;
  if (points == 0) {
    s << scan << ',' << stamp(scan) << ',' << id << ',' << cls
      << ",0,nan,nan,nan,nan,nan,nan,nan,nan,nan," << x << ',' << y << ",0,1\n";
  } else {
    s << scan << ',' << stamp(scan) << ',' << id << ',' << cls << ',' << points << ',' << x << ','
      << y << ",0," << x - 0.2 << ',' << y - 0.2 << ",0," << x + 0.2 << ',' << y + 0.2 << ",1.8,"
      << x << ',' << y << ",0.9,1\n";
  }
  return s.str();
}

std::string track(int scan, int id, double x, double y, bool ever_dynamic) {
  std::ostringstream s;
  s << scan << ',' << stamp(scan) << ',' << id << ',' << x << ',' << y
    << ",0,0,0,0,nan,nan,nan,nan,nan,nan," << (ever_dynamic ? 1 : 0) << ','
    << (ever_dynamic ? 1 : 0) << ",3,20\n";
  return s.str();
}

class EvalCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::make_temp_dir("ringtrack_eval_cli");
    // Person 1 walks along x (scans 0-3); person 2 stands at x = 5 and is fully occluded in
    // scan 3 (0 points: not ground truth there); a robot is not of the target class.
    std::string objects = kObjectsHeader + "\n";
    std::string tracks = kTracksHeader + "\n";
    for (int s = 0; s < 4; ++s) {
      objects += object(s, 1, "person", 10, 0.2 * s, 0.0);
      objects += object(s, 2, "person", s == 3 ? 0 : 10, 5.0, 0.2 * s);
      objects += object(s, 3, "robot", 10, 10.0, 10.0);
      tracks += track(s, 10, 0.2 * s + 0.1, 0.0, s >= 1);  // dynamic from scan 1 on
      tracks += track(s, 11, 20.0, 0.0, false);            // static clutter, never dynamic
    }
    tracks += track(0, 12, 5.0, 0.05, true);
    tracks += track(1, 12, 5.0, 0.25, true);
    tracks += track(2, 13, 5.0, 0.7, true);  // 0.3 m from person 2: match, an ID switch
    tracks += track(3, 13, 5.0, 0.8, true);  // person 2 hidden: false positive
    write(dir() / "objects.csv", objects);
    write(dir() / "tracks.csv", tracks);
  }
  void TearDown() override { fs::remove_all(dir_); }
  [[nodiscard]] fs::path dir() const { return dir_; }
  [[nodiscard]] std::string quoted(const fs::path& p) const {
    // Appending (not "'" + s + "'") avoids a GCC 12 -Wrestrict false positive at -O3.
    std::string q = "'";
    q += p.string();
    q += '\'';
    return q;
  }

  nlohmann::json run_json(const std::string& args) {
    const auto r = run_command(kCli + " eval " + args + " --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out);
  }

 private:
  fs::path dir_;
};

TEST_F(EvalCli, PaperModeNumbers) {
  const auto j = run_json("--gt " + quoted(dir()) + " --tracks " + quoted(dir() / "tracks.csv"));
  ASSERT_EQ(j["sequences"].size(), 1u);
  const auto& seq = j["sequences"][0];
  EXPECT_EQ(seq["hypotheses_total"], 4);
  EXPECT_EQ(seq["hypotheses_evaluated"], 3);
  EXPECT_EQ(seq["gt_rows_used"], 7);
  EXPECT_EQ(seq["gt_rows_skipped"], 5);
  const auto& m = j["overall"];
  EXPECT_EQ(m["gt_presences"], 7);
  EXPECT_EQ(m["matches"], 6);
  EXPECT_EQ(m["id_switches"], 1);
  EXPECT_EQ(m["true_positives"], 7);
  EXPECT_EQ(m["false_positives"], 1);
  EXPECT_EQ(m["misses"], 0);
  EXPECT_EQ(m["fragmentations"], 0);
  EXPECT_NEAR(m["mota"].get<double>(), 5.0 / 7.0, 1e-9);
  EXPECT_NEAR(m["motp"].get<double>(), 0.8 / 7.0, 1e-9);
  EXPECT_NEAR(m["recall"].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(m["precision"].get<double>(), 7.0 / 8.0, 1e-12);
  EXPECT_EQ(m["mostly_tracked"], 2);
  EXPECT_EQ(m["mostly_lost"], 0);
  EXPECT_EQ(m["gt_objects"], 2);
  EXPECT_EQ(m["hypotheses"], 3);
  // IDTP: person 1 - track 10 (4 scans) + person 2 - track 12 (2 scans) = 6 of 7 GT / 8 hyp.
  EXPECT_EQ(m["id_true_positives"], 6);
  EXPECT_NEAR(m["idf1"].get<double>(), 0.8, 1e-12);
  EXPECT_NEAR(m["idp"].get<double>(), 0.75, 1e-12);
  EXPECT_NEAR(m["idr"].get<double>(), 6.0 / 7.0, 1e-12);
  EXPECT_EQ(j["sequences"][0]["metrics"], m);
}

TEST_F(EvalCli, AllHypothesesClassAndThreshold) {
  const std::string files =
      "--gt " + quoted(dir() / "objects.csv") + " --tracks " + quoted(dir() / "tracks.csv");
  const auto all = run_json(files + " --all-hypotheses")["overall"];
  EXPECT_EQ(all["false_positives"], 5);
  EXPECT_NEAR(all["mota"].get<double>(), 1.0 / 7.0, 1e-9);
  // A 0.25 m threshold drops the 0.3 m pair of scan 2: a miss and a false positive instead of
  // a switch.
  const auto tight = run_json(files + " --threshold 0.25")["overall"];
  EXPECT_EQ(tight["id_switches"], 0);
  EXPECT_EQ(tight["misses"], 1);
  EXPECT_EQ(tight["false_positives"], 2);
  const auto robots = run_json(files + " --class robot")["overall"];
  EXPECT_EQ(robots["gt_presences"], 4);
  EXPECT_EQ(robots["misses"], 4);
  EXPECT_EQ(robots["false_positives"], 8);
  EXPECT_NEAR(robots["mota"].get<double>(), -2.0, 1e-12);
  const auto strict = run_json(files + " --min-points 11")["overall"];
  EXPECT_EQ(strict["gt_presences"], 0);
  EXPECT_TRUE(strict["mota"].is_null());
}

// Person mode (issue 10): the same ground truth, the hypotheses flagged person. Person 2 stands
// (never farther than 0.6 m from where it started); its track is never dynamic.
TEST_F(EvalCli, PersonModeScoresTheStandingPerson) {
  const auto row = [](int scan, int id, double x, double y, bool dynamic, bool person) {
    std::string r = track(scan, id, x, y, dynamic);
    r.pop_back();  // the newline
    return r + (person ? ",1\n" : ",0\n");
  };
  std::string tracks = kTracksHeader + ",person\n";
  for (int s = 0; s < 4; ++s) {
    tracks += row(s, 10, 0.2 * s + 0.1, 0.0, s >= 1, true);
    tracks += row(s, 20, 5.0, 0.2 * s + 0.05, false, s >= 2);  // person 2 hidden in scan 3
  }
  write(dir() / "tracks_person.csv", tracks);
  const std::string files =
      "--gt " + quoted(dir()) + " --tracks " + quoted(dir() / "tracks_person.csv");
  const auto paper = run_json(files);
  EXPECT_EQ(paper["hypotheses"], "dynamic");
  EXPECT_EQ(paper["sequences"][0]["hypotheses_evaluated"], 1);
  EXPECT_EQ(paper["overall"]["gt_presences"], 7);
  EXPECT_EQ(paper["overall"]["matches"], 4);
  EXPECT_EQ(paper["overall"]["misses"], 3);  // the standing person in scans 0-2
  EXPECT_EQ(paper["overall"]["false_positives"], 0);
  const auto person = run_json(files + " --hypotheses person");
  EXPECT_EQ(person["hypotheses"], "person");
  EXPECT_EQ(person["all_hypotheses"], false);
  EXPECT_EQ(person["sequences"][0]["hypotheses_evaluated"], 2);
  EXPECT_EQ(person["overall"]["gt_presences"], 7);
  EXPECT_EQ(person["overall"]["matches"], 7);
  EXPECT_EQ(person["overall"]["misses"], 0);
  EXPECT_EQ(person["overall"]["false_positives"], 1);  // track 20 while person 2 is hidden
  EXPECT_NEAR(person["overall"]["mota"].get<double>(), 6.0 / 7.0, 1e-9);
  const auto text = run_command(kCli + " eval " + files + " --hypotheses person");
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("person mode"), std::string::npos);
  // --all-hypotheses is --hypotheses all; the two together are refused.
  EXPECT_EQ(run_json(files + " --all-hypotheses")["hypotheses"], "all");
  EXPECT_NE(run_command(kCli + " eval " + files + " --all-hypotheses --hypotheses all").exit_code,
            0);
  // A tracks.csv from before the person column: paper mode works, person mode names the column.
  EXPECT_EQ(run_json("--gt " + quoted(dir()) + " --tracks " +
                     quoted(dir() / "tracks.csv"))["overall"]["matches"],
            6);
  const auto old = run_command(kCli + " eval --gt " + quoted(dir()) + " --tracks " +
                               quoted(dir() / "tracks.csv") + " --hypotheses person");
  EXPECT_EQ(old.exit_code, 1);
  EXPECT_NE(old.err.find("no 'person' column"), std::string::npos) << old.err;
}

TEST_F(EvalCli, SequenceListIsSummed) {
  const std::string pair = " --gt " + quoted(dir()) + " --tracks " + quoted(dir() / "tracks.csv");
  const auto j = run_json(pair + pair);
  ASSERT_EQ(j["sequences"].size(), 2u);
  const auto& m = j["overall"];
  EXPECT_EQ(m["gt_presences"], 14);
  EXPECT_EQ(m["id_switches"], 2);
  EXPECT_EQ(m["gt_objects"], 4);
  EXPECT_NEAR(m["mota"].get<double>(), 5.0 / 7.0, 1e-9);
}

TEST_F(EvalCli, TextTable) {
  const auto r = run_command(kCli + " eval --gt " + quoted(dir()) + " --tracks " +
                             quoted(dir() / "tracks.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("paper mode"), std::string::npos);
  EXPECT_NE(r.out.find("3 of 4 hypotheses evaluated"), std::string::npos);
  for (const char* row : {"MOTA", "MOTP (m)", "IDSW", "MT ratio", "IDF1", "GT objects"}) {
    EXPECT_NE(r.out.find(row), std::string::npos) << row;
  }
  EXPECT_NE(r.out.find("0.7143"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0.1143"), std::string::npos) << r.out;
}

TEST_F(EvalCli, HorizontalMotpAndVerticalErrorInFixture) {
  // Centroids and tracks all lie at z = 0: the horizontal MOTP is the MOTP, no height bias.
  const auto m =
      run_json("--gt " + quoted(dir()) + " --tracks " + quoted(dir() / "tracks.csv"))["overall"];
  EXPECT_NEAR(m["motp_horizontal"].get<double>(), 0.8 / 7.0, 1e-9);
  EXPECT_NEAR(m["mean_vertical_error"].get<double>(), 0.0, 1e-12);
}

// Four scans. Person 1 walks x = 0, 0.5, 1, 1.5 (moves); person 2 stands at (5, 0). Centroids at
// z = 1. Track 10 on person 1, offset (0.3, 0, +0.2); track 11 on person 2, offset
// (0, 0.1, -0.2); track 13 is clutter.
class EvalCliMoving : public EvalCli {
 protected:
  void SetUp() override {
    EvalCli::SetUp();
    std::string objects = kObjectsHeader + "\n";
    std::string tracks = kTracksHeader + "\n";
    const auto obj = [](int s, int id, double x, double y) {
      std::ostringstream o;
      o << s << ',' << stamp(s) << ',' << id << ",person,10," << x << ',' << y << ",1," << x - 0.2
        << ',' << y - 0.2 << ",0," << x + 0.2 << ',' << y + 0.2 << ",1.8," << x << ',' << y
        << ",0.9," << (id == 1 ? 1 : 0) << "\n";
      return o.str();
    };
    const auto trk = [](int s, int id, double x, double y, double z) {
      std::ostringstream o;
      o << s << ',' << stamp(s) << ',' << id << ',' << x << ',' << y << ',' << z
        << ",0,0,0,nan,nan,nan,nan,nan,nan,1,1,3,20\n";
      return o.str();
    };
    for (int s = 0; s < 4; ++s) {
      objects += obj(s, 1, 0.5 * s, 0.0);
      objects += obj(s, 2, 5.0, 0.0);
      tracks += trk(s, 10, 0.5 * s + 0.3, 0.0, 1.2);
      tracks += trk(s, 11, 5.0, 0.1, 0.8);
      tracks += trk(s, 13, 20.0, 0.0, 1.0);
    }
    fs::create_directories(dir() / "moving");
    write(dir() / "moving" / "objects.csv", objects);
    write(dir() / "moving" / "tracks.csv", tracks);
  }
  [[nodiscard]] std::string args() const {
    return "--gt " + quoted(dir() / "moving") + " --tracks " +
           quoted(dir() / "moving" / "tracks.csv");
  }
};

TEST_F(EvalCliMoving, JsonFullAndMovingOnlyFigures) {
  const auto j = run_json(args());
  EXPECT_EQ(j["moving_radius_m"].get<double>(), 1.0);
  const auto& full = j["overall"];
  EXPECT_EQ(full["gt_presences"], 8);
  EXPECT_EQ(full["true_positives"], 8);
  EXPECT_EQ(full["false_positives"], 4);
  EXPECT_NEAR(full["mota"].get<double>(), 0.5, 1e-12);
  EXPECT_NEAR(full["motp"].get<double>(), (std::sqrt(0.13) + std::sqrt(0.05)) / 2.0, 1e-9);
  EXPECT_NEAR(full["motp_horizontal"].get<double>(), 0.2, 1e-9);
  EXPECT_NEAR(full["mean_vertical_error"].get<double>(), 0.0, 1e-9);

  // Person 2 never moves: don't-care. Track 11 on it is neither a TP nor an FP.
  const auto& seq = j["sequences"][0]["moving_only"];
  EXPECT_EQ(seq["moving_objects"], 1);
  EXPECT_EQ(seq["never_moving_objects"], 1);
  const auto& m = seq["metrics"];
  EXPECT_EQ(m["gt_presences"], 4);
  EXPECT_EQ(m["true_positives"], 4);
  EXPECT_EQ(m["false_positives"], 4);
  EXPECT_EQ(m["misses"], 0);
  EXPECT_EQ(m["hypothesis_presences"], 8);
  EXPECT_EQ(m["gt_objects"], 1);
  EXPECT_NEAR(m["mota"].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(m["motp"].get<double>(), std::sqrt(0.13), 1e-9);
  EXPECT_NEAR(m["motp_horizontal"].get<double>(), 0.3, 1e-9);
  EXPECT_NEAR(m["mean_vertical_error"].get<double>(), 0.2, 1e-9);
  EXPECT_EQ(j["overall_moving_only"]["metrics"], m);
  EXPECT_EQ(j["overall_moving_only"]["moving_objects"], 1);

  // Person 1 moves 1.5 m: within a 2 m disc it never moves either; nothing is left to track and
  // only the clutter counts.
  const auto wide = run_json(args() + " --moving-radius 2")["overall_moving_only"];
  EXPECT_EQ(wide["moving_objects"], 0);
  EXPECT_EQ(wide["never_moving_objects"], 2);
  EXPECT_EQ(wide["metrics"]["gt_presences"], 0);
  EXPECT_EQ(wide["metrics"]["false_positives"], 4);
  EXPECT_TRUE(wide["metrics"]["mota"].is_null());
  EXPECT_TRUE(wide["metrics"]["motp_horizontal"].is_null());

  const auto bad = run_command(kCli + " eval " + args() + " --moving-radius -1");
  EXPECT_NE(bad.exit_code, 0);
}

TEST_F(EvalCliMoving, TextHasASecondBlock) {
  const auto r = run_command(kCli + " eval " + args());
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto second = r.out.find("moving objects only");
  ASSERT_NE(second, std::string::npos) << r.out;
  EXPECT_NE(r.out.find("1 moving, 1 never-moving (don't-care) objects", second), std::string::npos)
      << r.out;
  for (const char* row : {"MOTP x-y (m)", "z bias (m)"}) {
    const auto first = r.out.find(row);
    ASSERT_NE(first, std::string::npos) << row;
    EXPECT_LT(first, second) << row;
    EXPECT_NE(r.out.find(row, second), std::string::npos) << row;
  }
  EXPECT_NE(r.out.find("0.2000", second), std::string::npos) << r.out;  // z bias of person 1
  EXPECT_NE(r.out.find("0.3000", second), std::string::npos) << r.out;  // its x-y MOTP
}

TEST_F(EvalCli, MotChallengeBoxes) {
  fs::create_directories(dir() / "MOT-01" / "gt");
  write(dir() / "MOT-01" / "gt" / "gt.txt",
        "1,1,0,0,10,10,1,1,1\n"
        "1,2,50,50,10,10,0,7,1\n"  // ignored (flag 0)
        "2,1,0,0,10,10,1,1,1\n"
        "3,1,0,0,10,10,1,1,1\n");
  write(dir() / "res.txt",
        "1,7,0,0,10,5,0.9,-1,-1,-1\n"     // IoU 0.5: match
        "1,8,50,50,10,10,0.9,-1,-1,-1\n"  // on the ignored box: false positive
        "2,7,5,0,10,10,0.9,-1,-1,-1\n"    // IoU 1/3: miss + FP
        "3,7,1,0,10,10,0.9,-1,-1,-1\n");  // IoU 9/11: match
  const auto j = run_json("--format motchallenge --gt " + quoted(dir() / "MOT-01") + " --tracks " +
                          quoted(dir() / "res.txt"));
  EXPECT_EQ(j["sequences"][0]["name"], "MOT-01");
  const auto& m = j["overall"];
  EXPECT_EQ(m["matches"], 2);
  EXPECT_EQ(m["misses"], 1);
  EXPECT_EQ(m["false_positives"], 2);
  EXPECT_EQ(m["fragmentations"], 1);
  EXPECT_NEAR(m["mota"].get<double>(), 0.0, 1e-12);
  EXPECT_NEAR(m["motp"].get<double>(), (0.5 + 2.0 / 11.0) / 2.0, 1e-12);
  EXPECT_TRUE(m["motp_horizontal"].is_null());  // boxes have no x-y distance
  EXPECT_FALSE(j.contains("overall_moving_only"));
}

TEST_F(EvalCli, MissingColumnExitsOneNamingIt) {
  write(dir() / "bad_objects.csv", "scan,stamp,id,class,points,x,y,z\n0,0.0,1,person,3,0,0,0\n");
  const auto r = run_command(kCli + " eval --gt " + quoted(dir() / "bad_objects.csv") +
                             " --tracks " + quoted(dir() / "tracks.csv"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad_objects.csv:1"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("missing column 'min_x'"), std::string::npos) << r.err;
}

TEST_F(EvalCli, BadNumberExitsOneNamingFileAndLine) {
  write(dir() / "bad_tracks.csv",
        kTracksHeader + "\n" + track(0, 1, 0, 0, true) +
            "1,0.100000000,1,abc,0,0,0,0,0,nan,nan,nan,nan,nan,nan,1,1,3,20\n");
  const auto r = run_command(kCli + " eval --gt " + quoted(dir()) + " --tracks " +
                             quoted(dir() / "bad_tracks.csv"));
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad_tracks.csv:3: column 'x'"), std::string::npos) << r.err;
}

TEST_F(EvalCli, ShiftedScanIndicesExitOne) {
  // Track rows numbered one scan late: same stamps under other scan indices.
  write(dir() / "shifted.csv",
        kTracksHeader + "\n" + "1,0.000000000,1,0,0,0,0,0,0,nan,nan,nan,nan,nan,nan,1,1,3,20\n");
  const std::string args =
      " eval --gt " + quoted(dir()) + " --tracks " + quoted(dir() / "shifted.csv");
  const auto r = run_command(kCli + args);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("scan indices do not match: scan 1"), std::string::npos) << r.err;
  EXPECT_EQ(run_command(kCli + args + " --ignore-stamps").exit_code, 0);
}

TEST_F(EvalCli, OtherErrorsExitOne) {
  const auto unpaired = run_command(kCli + " eval --gt " + quoted(dir()) + " --gt " +
                                    quoted(dir()) + " --tracks " + quoted(dir() / "tracks.csv"));
  EXPECT_EQ(unpaired.exit_code, 1);
  EXPECT_NE(unpaired.err.find("--gt given 2 times but --tracks 1"), std::string::npos);
  const auto missing =
      run_command(kCli + " eval --gt " + quoted(dir()) + " --tracks " + quoted(dir() / "nope.csv"));
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("nope.csv"), std::string::npos) << missing.err;
  fs::create_directories(dir() / "empty_seq");
  const auto no_gt = run_command(kCli + " eval --gt " + quoted(dir() / "empty_seq") + " --tracks " +
                                 quoted(dir() / "tracks.csv"));
  EXPECT_EQ(no_gt.exit_code, 1);
  EXPECT_NE(no_gt.err.find("without objects.csv"), std::string::npos) << no_gt.err;
}

}  // namespace
}  // namespace ringtrack
