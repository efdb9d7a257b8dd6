// `ringtrack convert` on ROS bags: ROS 1 bags (generated fixtures, and the real capture's packets
// repacked into a ROS 1 bag) give the scans of the packets, PointCloud2 topics give one scan per
// cloud, bad bags are one-line errors.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "ringtrack/io/pcap_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"
#include "support/rosbag_writers.hpp"
#include "support/run_command.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack {
namespace {

namespace fs = std::filesystem;
using testing::run_command;

const std::string kCli = RINGTRACK_CLI_PATH;

fs::path data_dir() {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA")) {
    return fs::path(env) / "vlp16_indoor_nebula";
  }
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "vlp16_indoor_nebula";
}

void expect_sequence_is(const std::string& folder, const std::vector<core::OrganizedScan>& scans) {
  io::SequenceReader reader(folder);
  ASSERT_EQ(reader.size(), scans.size());
  io::SequenceScan s;
  for (const auto& e : scans) {
    ASSERT_TRUE(reader.next(s));
    EXPECT_EQ(s.scan.stamp_ns, e.stamp_ns);
    ASSERT_EQ(s.scan.valid_count(), e.valid_count());
    // PCD stores points, not ranges (VLP-16 ranges exclude the beam's vertical offset).
    for (std::size_t i = 0; i < e.size(); ++i) {
      if (e.valid(i)) {
        ASSERT_TRUE(s.scan.valid(i)) << "cell " << i;
        ASSERT_LT((s.scan.point(i) - e.point(i)).norm(), 1e-6f) << "cell " << i;
      }
    }
  }
}

TEST(ConvertBagCli, Ros1BagOfPacketsGivesTheirScans) {
  const std::string dir = testing::make_temp_dir("ringtrack-convert-bag-");
  test::VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 300.0;
  const test::VelodyneEncoder enc(eo);
  const auto packets = enc.encode(0, 260, [](long long s, int laser) {
    return test::VelodyneEchoPair{
        {static_cast<std::uint16_t>(1000 + (s * 5 + laser * 3) % 5000), 4}, {}};
  });
  const std::string bag = dir + "/drive.bag";
  test::write_rosbag1(bag, {{"/velodyne_packets", "velodyne_msgs/VelodyneScan"}},
                      test::velodyne_scan_messages(packets, 0, test::RosEncoding::kRos1),
                      {"lz4", 100'000, true});
  const auto r = run_command(kCli + " convert " + bag + " --out " + dir + "/seq");
  ASSERT_EQ(r.exit_code, 0) << r.err;

  io::VelodyneDecoder decoder;
  for (const auto& p : packets) decoder.add_packet(p.payload, p.host_stamp_ns);
  decoder.finish();
  std::vector<core::OrganizedScan> expected;
  while (auto s = decoder.pop_scan()) expected.push_back(std::move(*s));
  ASSERT_EQ(expected.size(), 3u);
  EXPECT_NE(r.err.find("wrote 3 scans"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("/velodyne_packets"), std::string::npos) << r.err;
  expect_sequence_is(dir + "/seq", expected);

  // --format bag on a file named otherwise; a topic that is not there; a corrupt bag.
  fs::copy_file(bag, dir + "/drive.data");
  const auto named = run_command(kCli + " convert " + dir + "/drive.data --format bag --out " +
                                 dir + "/seq2 --quiet");
  EXPECT_EQ(named.exit_code, 0) << named.err;
  EXPECT_TRUE(named.err.empty()) << named.err;
  const auto topic = run_command(kCli + " convert " + bag + " --topic /nope --out " + dir + "/x");
  EXPECT_EQ(topic.exit_code, 1);
  EXPECT_NE(topic.err.find("no topic '/nope'"), std::string::npos) << topic.err;
  fs::resize_file(dir + "/drive.data", fs::file_size(bag) - 100);
  const auto cut = run_command(kCli + " convert " + dir + "/drive.data --out " + dir + "/y");
  EXPECT_EQ(cut.exit_code, 1);
  EXPECT_NE(cut.err.find("drive.data"), std::string::npos) << cut.err;
  EXPECT_EQ(std::count(cut.err.begin(), cut.err.end(), '\n'), 1) << cut.err;
  EXPECT_FALSE(fs::exists(dir + "/y/sequence.yaml"));
  fs::remove_all(dir);
}

// A rosbag2 folder (sqlite3) with an empty packet topic and four PointCloud2 messages of 160
// points each on /velodyne_points.
void write_cloud_bag(const std::string& folder) {
  const auto model = core::SensorModel::vlp16();
  std::vector<test::TestBagMessage> messages;
  for (int m = 0; m < 4; ++m) {
    std::vector<test::TestPoint> pts;
    for (int ring = 0; ring < 16; ++ring) {
      for (int k = 0; k < 10; ++k) {
        const Eigen::Vector3f p = model.point(ring, 0.6 * k + 0.01 * m, 3.0 + 0.1 * ring);
        pts.push_back({p.x(), p.y(), p.z(), 9.0f, static_cast<std::uint16_t>(ring), 0.0f});
      }
    }
    const std::int64_t stamp = 1'000'000'000LL + m * 100'000'000LL;
    messages.push_back({1, stamp,
                        test::serialize_pointcloud2(test::make_xyzirt_cloud(pts, 1, 160, stamp),
                                                    test::RosEncoding::kCdr)});
  }
  test::write_rosbag2(folder,
                      {{"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"},
                       {"/velodyne_points", "sensor_msgs/msg/PointCloud2"}},
                      messages);
}

TEST(ConvertBagCli, PointCloudTopicsGiveOneScanPerCloud) {
  const std::string dir = testing::make_temp_dir("ringtrack-convert-bag-");
  write_cloud_bag(dir + "/bag");
  const auto r =
      run_command(kCli + " convert " + dir + "/bag --topic /velodyne_points --out " + dir + "/seq");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  io::SequenceReader reader(dir + "/seq");
  ASSERT_EQ(reader.size(), 4u);
  EXPECT_EQ(reader.meta().sensor, "vlp16");
  io::SequenceScan s;
  while (reader.next(s)) EXPECT_EQ(s.scan.valid_count(), 160u);
  fs::remove_all(dir);
}

// A rosbag2 folder whose metadata.yaml is gone (a recording cut short before rosbag2 wrote it)
// holds only .db3 files: `run` reads it as a bag, as `convert` does, not as a folder of scans.
TEST(ConvertBagCli, RunReadsABagFolderWithoutMetadata) {
  const std::string dir = testing::make_temp_dir("ringtrack-run-bag-");
  write_cloud_bag(dir + "/bag");
  ASSERT_TRUE(fs::remove(dir + "/bag/metadata.yaml"));
  const auto r = run_command(
      kCli + " run " + dir +
      "/bag --topic /velodyne_points --odometry off --no-plots --quiet --out " + dir + "/out");
  ASSERT_EQ(r.exit_code, 0) << r.err;
  std::ifstream timing(dir + "/out/timing.csv");
  std::string line;
  int rows = -1;  // the header
  while (std::getline(timing, line)) ++rows;
  EXPECT_EQ(rows, 4);
  fs::remove_all(dir);
}

TEST(ConvertBagCli, RealPacketsInARos1BagGiveThePcapSequence) {
  const fs::path data = data_dir();
  if (!fs::exists(data / "vlp16_dual_4scans.pcap")) {
    GTEST_SKIP() << "real VLP-16 test data not found at " << data
                 << " (set RINGTRACK_TEST_DATA to the folder holding vlp16_indoor_nebula/)";
  }
  const std::string dir = testing::make_temp_dir("ringtrack-convert-bag-");
  // The capture's packets, one VelodyneScan per 100 packets, in a bz2 ROS 1 bag.
  io::PcapReader pcap(data / "vlp16_dual_4scans.pcap");
  io::UdpDatagram d;
  std::vector<test::TestBagMessage> messages;
  test::TestVelodyneScan scan;
  const auto flush = [&] {
    if (scan.packets.empty()) return;
    scan.stamp_ns = scan.packets.front().stamp_ns;
    messages.push_back({0, scan.packets.back().stamp_ns,
                        test::serialize_velodyne_scan(scan, test::RosEncoding::kRos1)});
    scan.packets.clear();
  };
  while (pcap.next(d)) {
    scan.packets.push_back({d.stamp_ns, {d.payload.begin(), d.payload.end()}});
    if (scan.packets.size() == 100) flush();
  }
  flush();
  test::write_rosbag1(dir + "/real.bag", {{"/velodyne_packets", "velodyne_msgs/VelodyneScan"}},
                      messages, {"bz2", 500'000, true});
  const std::string pcap_path = (data / "vlp16_dual_4scans.pcap").string();
  const auto a = run_command(kCli + " convert " + pcap_path + " --return last --out " + dir + "/a");
  ASSERT_EQ(a.exit_code, 0) << a.err;
  const auto b =
      run_command(kCli + " convert " + dir + "/real.bag --return last --out " + dir + "/b");
  ASSERT_EQ(b.exit_code, 0) << b.err;
  io::VelodyneDecoderOptions options;
  options.return_selection = io::VelodyneReturnSelection::kLast;
  io::VelodynePcapSource direct(data / "vlp16_dual_4scans.pcap", {}, options);
  std::vector<core::OrganizedScan> expected;
  while (auto s = direct.next()) expected.push_back(std::move(*s));
  ASSERT_EQ(expected.size(), 3u);
  expect_sequence_is(dir + "/a", expected);
  expect_sequence_is(dir + "/b", expected);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace ringtrack
