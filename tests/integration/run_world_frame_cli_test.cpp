// `ringtrack run` and `ringtrack eval` in a georeferenced world (issue 16): a sequence whose poses
// and ground truth are moved to UTM-scale coordinates 100 m up gives the same tracks, in the
// user's frame, as the sequence near the origin; the maps say where their local frame lies.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/io/mot_tables.hpp"
#include "support/run_command.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;
const Eigen::Vector3d kShift{500'000.0, 5'000'000.0, 100.0};

// poses.txt (TUM) with every position moved by kShift.
void shift_poses(const fs::path& path) {
  std::ifstream in(path);
  std::string text;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') {
      text += line + '\n';
      continue;
    }
    std::istringstream fields(line);
    double t = 0, x = 0, y = 0, z = 0, qx = 0, qy = 0, qz = 0, qw = 0;
    fields >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
    char row[256];
    std::snprintf(row, sizeof row, "%.9f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", t, x + kShift.x(),
                  y + kShift.y(), z + kShift.z(), qx, qy, qz, qw);
    text += row;
  }
  in.close();
  std::ofstream(path) << text;
}

// objects.csv (the ground truth) moved by kShift, as a user's georeferenced annotation.
void shift_objects(const fs::path& path) {
  std::vector<io::ObjectRow> rows = io::read_objects_csv(path);
  for (io::ObjectRow& r : rows) {
    r.centroid += kShift;
    r.true_center += kShift;
    if (!r.box.empty()) {
      r.box.min += kShift;
      r.box.max += kShift;
    }
  }
  io::ObjectsCsvWriter out(path);
  for (const io::ObjectRow& r : rows) out.write(r);
  out.close();
}

std::string file_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The PLY header's lines up to end_header, and the binary body.
std::pair<std::string, std::string> split_ply(const fs::path& path) {
  const std::string bytes = file_text(path);
  const std::string end = "end_header\n";
  const std::size_t at = bytes.find(end);
  EXPECT_NE(at, std::string::npos);
  return {bytes.substr(0, at + end.size()), bytes.substr(at + end.size())};
}

class RunCliWorldFrame : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing::make_temp_dir("ringtrack-world-");
    const auto r = run_command(kCli + " simulate 1 --duration 4 --seed 3 --out " + dir_ + "/near");
    ASSERT_EQ(r.exit_code, 0) << r.err;
    fs::copy(dir_ + "/near", dir_ + "/utm", fs::copy_options::recursive);
    shift_poses(dir_ + "/utm/poses.txt");
    shift_objects(dir_ + "/utm/objects.csv");
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string dir_;
};
std::string RunCliWorldFrame::dir_;

TEST_F(RunCliWorldFrame, UtmShiftedPosesGiveTheSameTracksInTheUsersFrame) {
  const auto near =
      run_command(kCli + " run " + dir_ + "/near --out " + dir_ + "/out-near --no-plots");
  ASSERT_EQ(near.exit_code, 0) << near.err;
  const auto utm =
      run_command(kCli + " run " + dir_ + "/utm --out " + dir_ + "/out-utm --no-plots");
  ASSERT_EQ(utm.exit_code, 0) << utm.err;
  EXPECT_EQ(near.out.find("frame  "), std::string::npos) << near.out;
  EXPECT_NE(utm.out.find("local frame at origin (500000.000, 5000000.000, 100.000) m"),
            std::string::npos)
      << utm.out;

  const auto a = io::read_tracks_csv(dir_ + "/out-near/tracks.csv");
  const auto b = io::read_tracks_csv(dir_ + "/out-utm/tracks.csv");
  ASSERT_EQ(a.size(), b.size());
  ASSERT_GT(a.size(), 50u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].scan, b[i].scan);
    EXPECT_EQ(a[i].id, b[i].id);
    EXPECT_EQ(a[i].dynamic, b[i].dynamic);
    EXPECT_LT((b[i].position - kShift - a[i].position).norm(), 1e-3) << "row " << i;
    ASSERT_EQ(a[i].box.empty(), b[i].box.empty());
    if (a[i].box.empty()) continue;
    EXPECT_LT((b[i].box.min - kShift - a[i].box.min).norm(), 1e-3) << "row " << i;
    EXPECT_LT((b[i].box.max - kShift - a[i].box.max).norm(), 1e-3) << "row " << i;
  }

  // The maps: float32 in the local frame, which the header states; the same points.
  const auto [near_header, near_body] = split_ply(dir_ + "/out-near/static_map.ply");
  const auto [utm_header, utm_body] = split_ply(dir_ + "/out-utm/static_map.ply");
  EXPECT_NE(near_header.find("comment origin_m 0.000 0.000 0.000"), std::string::npos);
  EXPECT_NE(utm_header.find("comment origin_m 500000.000 5000000.000 100.000 (world = point + "
                            "origin)\n"),
            std::string::npos)
      << utm_header;
  EXPECT_GT(near_body.size(), 16u * 1000u);
  EXPECT_TRUE(near_body == utm_body);
  EXPECT_NE(file_text(dir_ + "/out-utm/static_map.pcd").find("# origin_m 500000.000"),
            std::string::npos);
  // run.json names the frame too, for programs that read it rather than the map headers.
  EXPECT_EQ(nlohmann::json::parse(file_text(dir_ + "/out-utm/run.json"))["origin_m"],
            nlohmann::json::array({500000.0, 5000000.0, 100.0}));
  EXPECT_EQ(nlohmann::json::parse(file_text(dir_ + "/out-near/run.json"))["origin_m"],
            nlohmann::json::array({0.0, 0.0, 0.0}));
}

// Ground truth in the user's frame scores the tracks in the user's frame as near the origin.
TEST_F(RunCliWorldFrame, EvalInTheUsersFrameScoresAsNearTheOrigin) {
  for (const char* name : {"near", "utm"}) {
    const auto r = run_command(kCli + " run " + dir_ + "/" + name + " --out " + dir_ + "/eval-" +
                               name + " --no-plots --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const auto score = [&](const std::string& name) {
    const auto r = run_command(kCli + " eval --gt " + dir_ + "/" + name + "/objects.csv --tracks " +
                               dir_ + "/eval-" + name + "/tracks.csv --json");
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return nlohmann::json::parse(r.out);
  };
  const auto near = score("near");
  const auto utm = score("utm");
  EXPECT_GT(near["overall"]["mota"].get<double>(), 0.3);
  EXPECT_EQ(near["overall"]["mota"], utm["overall"]["mota"]);
  EXPECT_EQ(near["overall"]["true_positives"], utm["overall"]["true_positives"]);
  EXPECT_NEAR(near["overall"]["motp"].get<double>(), utm["overall"]["motp"].get<double>(), 1e-4);
}

}  // namespace
}  // namespace ringtrack
