// --on-bad-scan: a bag message that cannot be decoded is skipped (kSkip) or stops (kStop).
#include "ringtrack/io/bad_scans.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "support/rosbag_writers.hpp"
#include "support/temp_dir.hpp"

namespace ringtrack::io {
namespace {

// A PointCloud2 of 16 rings of points around the sensor at `stamp_ns`.
std::vector<std::uint8_t> cloud(std::int64_t stamp_ns) {
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
  const auto c = test::make_xyzirt_cloud(points, 1, static_cast<std::uint32_t>(points.size()),
                                         stamp_ns, true, false);
  return test::serialize_pointcloud2(c, test::RosEncoding::kCdr);
}

// Four clouds of which the third (message 2) is cut short.
std::filesystem::path bag_with_a_corrupt_message(const test::TempDir& dir) {
  std::vector<test::TestBagMessage> messages;
  const std::int64_t base = 1'700'000'000'000'000'000;
  for (int m = 0; m < 4; ++m) {
    auto data = cloud(base + m * 100'000'000LL);
    if (m == 2) data.resize(data.size() / 2);
    messages.push_back({0, base + m * 100'000'000LL, std::move(data)});
  }
  const auto bag = dir / "bag";
  test::write_rosbag2(bag, {{"/points", "sensor_msgs/msg/PointCloud2"}}, messages);
  return bag;
}

TEST(ScanReader, SkipPassesOverACorruptMessageKeepingItsNumber) {
  test::TempDir dir;
  RosbagScanSource source(bag_with_a_corrupt_message(dir));
  std::vector<std::uint64_t> skipped;
  std::string error;
  ScanReader reader(source, BadScanPolicy::kSkip, [&](std::uint64_t index, const std::string& e) {
    skipped.push_back(index);
    error = e;
  });
  std::vector<std::uint64_t> read;
  std::uint64_t index = 0;
  while (reader.next(index)) read.push_back(index);
  EXPECT_EQ(read, (std::vector<std::uint64_t>{0, 1, 3}));
  EXPECT_EQ(skipped, (std::vector<std::uint64_t>{2}));
  EXPECT_NE(error.find("message 3"), std::string::npos) << error;  // bags number from 1
  EXPECT_EQ(reader.skipped(), 1u);
  EXPECT_EQ(reader.read(), 4u);
}

TEST(ScanReader, StopRethrowsTheError) {
  test::TempDir dir;
  RosbagScanSource source(bag_with_a_corrupt_message(dir));
  ScanReader reader(source, BadScanPolicy::kStop);
  std::uint64_t index = 0;
  ASSERT_TRUE(reader.next(index));
  ASSERT_TRUE(reader.next(index));
  EXPECT_THROW(reader.next(index), core::InputError);
  EXPECT_EQ(reader.skipped(), 0u);
}

TEST(ScanReader, ParsesThePolicy) {
  EXPECT_EQ(parse_bad_scan_policy("skip"), BadScanPolicy::kSkip);
  EXPECT_EQ(parse_bad_scan_policy("stop"), BadScanPolicy::kStop);
  EXPECT_THROW(parse_bad_scan_policy("ignore"), core::ConfigError);
}

}  // namespace
}  // namespace ringtrack::io
