// `ringtrack run` on inputs between "works" and "fails" (issue 16): scans whose stamps go back.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "support/rosbag_writers.hpp"
#include "support/run_command.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;
const std::string kCli = RINGTRACK_CLI_PATH;

// A cloud of one ring of points around the sensor (16 rings, ring field, no time field: the
// scan's stamp is the header stamp).
std::vector<std::uint8_t> cloud_message(std::int64_t stamp_ns) {
  std::vector<test::TestPoint> points;
  for (int ring = 0; ring < 16; ++ring) {
    for (int k = 0; k < 36; ++k) {
      const double a = k * 10.0 * std::numbers::pi / 180.0;
      const double e = (-15.0 + 2.0 * ring) * std::numbers::pi / 180.0;
      points.push_back({static_cast<float>(8.0 * std::cos(e) * std::cos(a)),
                        static_cast<float>(8.0 * std::cos(e) * std::sin(a)),
                        static_cast<float>(8.0 * std::sin(e)), 20.0F,
                        static_cast<std::uint16_t>(ring), 0.0F});
    }
  }
  const auto cloud = test::make_xyzirt_cloud(points, 1, static_cast<std::uint32_t>(points.size()),
                                             stamp_ns, /*with_ring=*/true, /*with_time=*/false);
  return test::serialize_pointcloud2(cloud, test::RosEncoding::kCdr);
}

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(RunRobustnessCli, ScanWhoseStampGoesBackIsSkippedWithAWarningNamingInputAndScan) {
  const std::string dir = testing::make_temp_dir("ringtrack-robust-");
  const fs::path bag = fs::path(dir) / "bag";
  // Header stamps 1.0, 1.1, 1.05 (a clock step back), 1.2 s; record stamps in order.
  const std::int64_t base = 1'700'000'001'000'000'000;
  const std::int64_t header_ns[] = {0, 100'000'000, 50'000'000, 200'000'000};
  std::vector<test::TestBagMessage> messages;
  for (int m = 0; m < 4; ++m) {
    messages.push_back({0, base + m * 100'000'000LL, cloud_message(base + header_ns[m])});
  }
  test::write_rosbag2(bag, {{"/points", "sensor_msgs/msg/PointCloud2"}}, messages);
  const std::string out = dir + "/out";
  // A static sensor (--odometry off): the odometry would add its own warning about these
  // featureless clouds, and the skip is the same with it (Pipeline::process_with_odometry).
  const auto r = run_command(kCli + " run " + bag.string() + " --odometry off --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err, "ringtrack: warning: " + bag.string() +
                       ": scan 2: stamp 1700000001050000000 ns is 0.050000000 s older than the "
                       "previous scan's 1700000001100000000 ns (a clock step or a corrupt stamp); "
                       "skipped\n");
  EXPECT_NE(r.out.find("scans            3 (1 more skipped: stamps older than the scan before)"),
            std::string::npos)
      << r.out;
  // timing.csv: a header and the three processed scans, 0, 1 and 3.
  const auto timing = lines_of(fs::path(out) / "timing.csv");
  ASSERT_EQ(timing.size(), 4u);
  EXPECT_EQ(timing[1].substr(0, 2), "0,");
  EXPECT_EQ(timing[2].substr(0, 2), "1,");
  EXPECT_EQ(timing[3].substr(0, 2), "3,");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ringtrack
