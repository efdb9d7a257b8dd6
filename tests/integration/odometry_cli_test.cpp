// `ringtrack run --odometry on` on a simulated flight and `ringtrack eval-trajectory` end to end:
// the estimated poses.txt against the sequence's ground truth, odometry.csv, and bad input.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "support/run_command.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;

TEST(OdometryCli, FlightPosesMatchTheGroundTruthAndEveryScanIsReliable) {
  const fs::path dir = testing::make_temp_dir("ringtrack-odometry-cli-");
  const std::string seq = (dir / "seq").string();
  ASSERT_EQ(run_command(kCli + " simulate 4 --moving-sensor --duration 3 --seed 2 --out " + seq)
                .exit_code,
            0);
  const std::string out = (dir / "out").string();
  const auto r = run_command(kCli + " run " + seq + " --odometry on --odometry-start " + seq +
                             "/poses.txt --quiet --no-plots --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("poses            odometry (--odometry on)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("odometry         0 of 30 scans flagged unreliable"), std::string::npos)
      << r.out;
  std::ifstream csv(out + "/odometry.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("scan,stamp,x,y,z,qx,qy,qz,qw,registered,degenerate,", 0), 0u) << header;

  const auto t = run_command(kCli + " eval-trajectory " + out + "/poses.txt --reference " + seq +
                             "/poses.txt --json");
  ASSERT_EQ(t.exit_code, 0) << t.err;
  const auto j = nlohmann::json::parse(t.out);
  EXPECT_EQ(j["matched_poses"].get<int>(), 30);
  // 3 s of the figure 8 (about 11 m): centimetres (docs/odometry.md has the 100 s figures).
  EXPECT_LT(j["ate_rmse_m"].get<double>(), 0.05);
  EXPECT_LT(j["final_drift_m"].get<double>(), 0.1);
  fs::remove_all(dir);
}

TEST(OdometryCli, EvalTrajectoryErrorsAreOneLine) {
  const fs::path dir = testing::make_temp_dir("ringtrack-eval-trajectory-");
  std::ofstream(dir / "a.txt") << "0 0 0 0 0 0 0 1\n1 1 0 0 0 0 0 1\n";
  std::ofstream(dir / "late.txt") << "5 0 0 0 0 0 0 1\n6 1 0 0 0 0 0 1\n";
  std::ofstream(dir / "bad.txt") << "0 0 0 0 0 0 0 1\n1 1 0 zero 0 0 0 1\n";
  const auto ok = run_command(kCli + " eval-trajectory " + (dir / "a.txt").string() +
                              " --reference " + (dir / "a.txt").string());
  EXPECT_EQ(ok.exit_code, 0) << ok.err;
  EXPECT_NE(ok.out.find("ATE              RMSE 0.0000 m"), std::string::npos) << ok.out;
  const auto late = run_command(kCli + " eval-trajectory " + (dir / "late.txt").string() +
                                " --reference " + (dir / "a.txt").string());
  EXPECT_EQ(late.exit_code, 1);
  EXPECT_NE(late.err.find("0 estimated poses lie within the reference's time span"),
            std::string::npos)
      << late.err;
  const auto bad = run_command(kCli + " eval-trajectory " + (dir / "a.txt").string() +
                               " --reference " + (dir / "bad.txt").string());
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_NE(bad.err.find("bad.txt"), std::string::npos) << bad.err;
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ringtrack
