// `ringtrack convert`: Velodyne captures and ROS 2 bags into sequence folders.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"
#include "support/run_command.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;

fs::path data_dir() {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA"))
    return fs::path(env) / "vlp16_indoor_nebula";
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "vlp16_indoor_nebula";
}

TEST(ConvertCli, SyntheticPcapRoundTripsThroughTheSequenceFolder) {
  const std::string dir = testing::make_temp_dir("ringtrack-convert-");
  test::VelodyneEncoderOptions eo;
  eo.product = 0x28;  // VLP-32C
  eo.start_azimuth_deg = 30.0;
  const test::VelodyneEncoder enc(eo);
  const auto packets = enc.encode(0, 500, [](long long s, int laser) {
    return test::VelodyneEchoPair{{static_cast<std::uint16_t>(900 + (s * 3 + laser) % 4000), 9},
                                  {}};
  });
  const std::string pcap = dir + "/synthetic.pcapng";
  test::write_pcapng(pcap, test::PcapLink::kEthernet,
                     test::frame_packets(test::PcapLink::kEthernet, packets));
  const auto r = run_command(kCli + " convert " + pcap + " --out " + dir + "/seq");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("wrote 2 scans"), std::string::npos) << r.err;

  io::SequenceReader reader(dir + "/seq");
  EXPECT_EQ(reader.meta().sensor, "vlp32c");
  ASSERT_EQ(reader.size(), 2u);
  io::VelodynePcapSource direct(pcap);
  io::SequenceScan s;
  while (reader.next(s)) {
    const auto expected = direct.next();
    ASSERT_TRUE(expected.has_value());
    EXPECT_EQ(s.scan.stamp_ns, expected->stamp_ns);
    EXPECT_EQ(s.scan.valid_count(), expected->valid_count());
    for (std::size_t i = 0; i < expected->size(); ++i) {
      if (expected->valid(i)) {
        // Two float ulps at the VLP-32C's ranges here (up to 20 m in its 4 mm units).
        ASSERT_NEAR(s.scan.range_m(i), expected->range_m(i), 4e-6);
      }
    }
  }
  // Refuses to overwrite, names the format problem of an unknown input.
  const auto again = run_command(kCli + " convert " + pcap + " --out " + dir + "/seq");
  EXPECT_EQ(again.exit_code, 1);
  const auto unknown = run_command(kCli + " convert " + dir + "/nothing.txt --out " + dir + "/x");
  EXPECT_EQ(unknown.exit_code, 1);
  EXPECT_NE(unknown.err.find("nothing.txt"), std::string::npos) << unknown.err;
  EXPECT_EQ(std::count(unknown.err.begin(), unknown.err.end(), '\n'), 1) << unknown.err;
  fs::remove_all(dir);
}

TEST(ConvertCli, RealPcapAndBagGiveTheSameSequence) {
  const fs::path data = data_dir();
  if (!fs::exists(data / "vlp16_dual_4scans.pcap") || !fs::exists(data / "ros2_bag")) {
    GTEST_SKIP() << "real VLP-16 test data not found at " << data
                 << " (set RINGTRACK_TEST_DATA to the folder holding vlp16_indoor_nebula/)";
  }
  const std::string dir = testing::make_temp_dir("ringtrack-convert-");
  const auto a = run_command(kCli + " convert " + (data / "vlp16_dual_4scans.pcap").string() +
                             " --return last --out " + dir + "/a");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto b = run_command(kCli + " convert " + (data / "ros2_bag").string() +
                             " --return last --out " + dir + "/b");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  io::SequenceReader ra(dir + "/a");
  io::SequenceReader rb(dir + "/b");
  EXPECT_EQ(ra.meta().sensor, "vlp16");
  ASSERT_EQ(ra.size(), 3u);
  ASSERT_EQ(rb.size(), 3u);
  for (std::size_t i = 0; i < ra.size(); ++i) {
    const auto sa = ra.read(i);
    const auto sb = rb.read(i);
    EXPECT_EQ(sa.scan.valid_count(), sb.scan.valid_count());
    EXPECT_GT(sa.scan.valid_count(), 14000u);
    EXPECT_LE(std::abs(sa.scan.stamp_ns - sb.scan.stamp_ns), 1000);
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ringtrack
