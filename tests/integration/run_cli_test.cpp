// `ringtrack run` end to end: outputs and their schemas, and bad input as one-line errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "ringtrack/io/csv_writers.hpp"
#include "support/run_command.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;

std::string first_line(const fs::path& p) {
  std::ifstream in(p);
  std::string line;
  std::getline(in, line);
  return line;
}

std::size_t line_count(const fs::path& p) {
  std::ifstream in(p);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

class RunCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = testing::make_temp_dir("ringtrack-run-");
    const auto r = run_command(kCli + " simulate 1 --duration 3 --seed 3 --out " + dir_ + "/seq");
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  static void TearDownTestSuite() { fs::remove_all(dir_); }
  static std::string dir_;
};
std::string RunCli::dir_;

TEST_F(RunCli, WritesEveryOutputWithItsSchema) {
  const std::string out = dir_ + "/out";
  const auto r = run_command(kCli + " run " + dir_ + "/seq --out " + out +
                             " --filtered-scans --set mapping.voxel_size_m=0.2");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("scans            30"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("ms per scan"), std::string::npos);
  EXPECT_EQ(first_line(out + "/tracks.csv"), io::kTracksCsvHeader);
  EXPECT_GT(line_count(out + "/tracks.csv"), 30u);
  EXPECT_EQ(first_line(out + "/timing.csv")
                .rfind("scan,stamp,segmentation_ms,detection_ms,tracking_ms,mapping_ms", 0),
            0u)
      << first_line(out + "/timing.csv");
  EXPECT_EQ(line_count(out + "/timing.csv"), 31u);
  EXPECT_EQ(first_line(out + "/static_map.ply"), "ply");
  EXPECT_TRUE(fs::exists(out + "/filtered/000029.pcd"));
  std::ifstream config(out + "/config.yaml");
  std::stringstream text;
  text << config.rdbuf();
  EXPECT_NE(text.str().find("voxel_size_m: 0.2"), std::string::npos);
}

TEST_F(RunCli, FilteredScansGiveMapMetricsInEval) {
  const std::string out = dir_ + "/out-map";
  ASSERT_EQ(run_command(kCli + " run " + dir_ + "/seq --out " + out + " --filtered-scans --quiet")
                .exit_code,
            0);
  const auto r = run_command(kCli + " eval --json --gt " + dir_ + "/seq --tracks " + out +
                             "/tracks.csv --filtered " + out + "/filtered");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* key : {"\"overall_map\"", "\"preservation_rate\"", "\"rejection_rate\"",
                          "\"static_points\"", "\"dynamic_points\""}) {
    EXPECT_NE(r.out.find(key), std::string::npos) << key << "\n" << r.out;
  }
  // Most static points survive the filter (people walk in an empty field).
  const auto at = r.out.find("\"preservation_rate\": ");
  ASSERT_NE(at, std::string::npos);
  EXPECT_GT(std::stod(r.out.substr(at + 21)), 0.99);
  // A missing filtered scan is an error naming the file.
  fs::remove(out + "/filtered/000005.pcd");
  const auto bad = run_command(kCli + " eval --gt " + dir_ + "/seq --tracks " + out +
                               "/tracks.csv --filtered " + out + "/filtered");
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("000005.pcd"), std::string::npos) << bad.err;
}

TEST_F(RunCli, MissingInputIsOneLineError) {
  const auto r = run_command(kCli + " run " + dir_ + "/nothing-here --out " + dir_ + "/o2");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("nothing-here"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST_F(RunCli, MalformedPosesFileIsOneLineErrorNamingTheLine) {
  { std::ofstream(dir_ + "/bad_poses.txt") << "0 0 0 0 0 0 0 1\n0.1 1 2 nan 0 0 0 1\n"; }
  const auto r = run_command(kCli + " run " + dir_ + "/seq --out " + dir_ + "/o3 --poses " + dir_ +
                             "/bad_poses.txt");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("bad_poses.txt"), std::string::npos) << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
}

TEST_F(RunCli, UnorganizedPcdFolderIsRejected) {
  const std::string folder = dir_ + "/plain";
  fs::create_directories(folder);
  {
    std::ofstream(folder + "/a.pcd")
        << "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
           "WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
           "1 2 3\n4 5 6\n";
  }
  const auto r = run_command(kCli + " run " + folder + " --out " + dir_ + "/o4");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("a.pcd"), std::string::npos) << r.err;
}

TEST_F(RunCli, UnknownConfigKeyFailsBeforeAnyOutput) {
  const auto r =
      run_command(kCli + " run " + dir_ + "/seq --out " + dir_ + "/o5 --set tracking.nope=1");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("tracking.nope"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(dir_ + "/o5/tracks.csv"));
}

}  // namespace
}  // namespace ringtrack
