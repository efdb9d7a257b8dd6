// io::open_source, the one way in for every input: each kind of input (hand-made in a temp
// folder: Velodyne, Hesai and Ouster captures, ROS 1 and ROS 2 bags, a sequence folder with
// poses, folders of PCD and of KITTI-style .bin files, a live UDP port) opens as the ScanSource
// for its kind, recognised from its name and contents; bad options and unknown inputs are one
// clear line naming what was expected.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <vector>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/bad_scans.hpp"
#include "ringtrack/io/kitti_bin.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/text.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "support/hesai_encoder.hpp"
#include "support/ouster_encoder.hpp"
#include "support/rosbag_writers.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

// Default options, named: a braced temporary trips g++ 12's -Wmaybe-uninitialized.
const ScanSourceOptions kDefaults;

namespace fs = std::filesystem;
using test::input_error;

constexpr std::int64_t kStart = 1'700'000'000'000'000'000;
constexpr std::int64_t kPeriod = 100'000'000;  // 10 Hz

// About two and a half VLP-16 revolutions of encoded packets.
std::vector<::ringtrack::test::EncodedVelodynePacket> velodyne_packets() {
  ::ringtrack::test::VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 250.0;
  const ::ringtrack::test::VelodyneEncoder enc(eo);
  const double per_rev = 360.0 / (enc.advance_deg() * enc.sequences_per_packet());
  return enc.encode(0, static_cast<long long>(2.5 * per_rev), [](long long s, int laser) {
    const auto d = static_cast<std::uint16_t>((s * 7 + laser * 131) % 9000 + 400);
    return ::ringtrack::test::VelodyneEchoPair{{d, 10}, {d, 1}};
  });
}

void write_velodyne_pcap(const fs::path& path) {
  using ::ringtrack::test::PcapLink;
  ::ringtrack::test::write_pcap(
      path, PcapLink::kEthernet,
      ::ringtrack::test::frame_packets(PcapLink::kEthernet, velodyne_packets()));
}

// A few Hesai PandarXT32 packets to port 2368 and the sensor's angle corrections.
void write_hesai_capture(const fs::path& pcap, const fs::path& calibration) {
  const ::ringtrack::test::HesaiEncoder enc({});
  std::vector<::ringtrack::test::PcapFrame> frames;
  std::int64_t stamp = kStart;
  for (const auto& payload : enc.encode(0, 4, [](long long, int) {
         return std::pair<::ringtrack::test::HesaiEcho, ::ringtrack::test::HesaiEcho>{{1000, 10},
                                                                                      {1000, 10}};
       })) {
    frames.push_back(::ringtrack::test::udp_frame(::ringtrack::test::PcapLink::kEthernet, payload,
                                                  2368, stamp += 50'000));
  }
  ::ringtrack::test::write_pcap(pcap, ::ringtrack::test::PcapLink::kEthernet, frames);
  test::write_text(calibration, ::ringtrack::test::hesai_calibration_csv(enc.channels()));
}

// A few Ouster lidar packets to port 7502 and the sensor's metadata.
void write_ouster_capture(const fs::path& pcap, const fs::path& metadata) {
  const ::ringtrack::test::OusterEncoderOptions eo;
  std::vector<::ringtrack::test::PcapFrame> frames;
  for (int m = 0; m < 4 * eo.columns_per_packet; m += eo.columns_per_packet) {
    const std::int64_t stamp = kStart + m * 97'656LL;
    frames.push_back(::ringtrack::test::udp_frame(
        ::ringtrack::test::PcapLink::kEthernet,
        ::ringtrack::test::encode_ouster_packet(eo, m, stamp,
                                                [](int, int) {
                                                  return ::ringtrack::test::OusterEcho{4000, 0, 10};
                                                }),
        7502, stamp, 7502));
  }
  ::ringtrack::test::write_pcap(pcap, ::ringtrack::test::PcapLink::kEthernet, frames);
  test::write_text(metadata, ::ringtrack::test::ouster_metadata_json(eo));
}

// A three-scan VLP-16 sequence of the demo scene, the sensor moving along +x.
void write_sequence(const fs::path& folder) {
  const auto model = core::SensorModel::vlp16();
  SequenceWriter writer(folder, SequenceMeta::for_sensor(model, model.columns()));
  for (int k = 0; k < 3; ++k) {
    auto rendered = sim::render(model, sim::SimpleScene::demo());
    rendered.scan.set_uniform_columns(model, kStart + k * kPeriod);
    core::Pose pose;
    pose.stamp_ns = rendered.scan.stamp_ns;
    pose.translation = Eigen::Vector3d(0.5 * k, 0, 1.8);
    writer.add_scan(rendered.scan, rendered.labels, pose);
  }
  writer.finish();
}

std::string config_error(const ScanSourceOptions& options, const std::string& uri = "x") {
  try {
    (void)open_source(uri, options);
  } catch (const core::ConfigError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected core::ConfigError, got: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected core::ConfigError, nothing thrown";
  return {};
}

TEST(OpenSource, PacketCapturesOpenAsTheirSensorsSource) {
  test::TempDir dir;
  write_velodyne_pcap(dir / "velodyne.pcap");
  auto velodyne = open_source((dir / "velodyne.pcap").string(), kDefaults);
  EXPECT_EQ(velodyne->description(), (dir / "velodyne.pcap").string() + " (Velodyne pcap)");
  std::size_t scans = 0;
  while (auto scan = velodyne->next()) {
    EXPECT_FALSE(velodyne->pose());  // a capture carries no poses
    ++scans;
  }
  EXPECT_GE(scans, 1u);
  EXPECT_EQ(velodyne->model().name, "VLP-16");
  EXPECT_FALSE(velodyne->live());
  EXPECT_EQ(velodyne->size(), 0u);
  EXPECT_EQ(velodyne->sequence(), nullptr);

  // A capture renamed to .dat is named with format pcap; guessed, it is an unknown file.
  fs::copy_file(dir / "velodyne.pcap", dir / "velodyne.dat");
  EXPECT_NE(input_error([&] {
              (void)open_source((dir / "velodyne.dat").string(), kDefaults);
            }).find("velodyne.dat: cannot tell the input format (expected udp://HOST:PORT"),
            std::string::npos);
  ScanSourceOptions named;
  named.format = parse_scan_input_format("pcapng");
  EXPECT_NE(open_source((dir / "velodyne.dat").string(), named)->description().find("Velodyne"),
            std::string::npos);

  write_hesai_capture(dir / "hesai.pcap", dir / "hesai.csv");
  EXPECT_EQ(input_error([&] { (void)open_source((dir / "hesai.pcap").string(), kDefaults); }),
            (dir / "hesai.pcap").string() +
                ": Hesai packets; give the sensor's angle-correction file with --calibration FILE");
  ScanSourceOptions hesai;
  hesai.calibration = (dir / "hesai.csv").string();
  EXPECT_EQ(open_source((dir / "hesai.pcap").string(), hesai)->description(),
            (dir / "hesai.pcap").string() + " (Hesai pcap)");

  write_ouster_capture(dir / "ouster.pcap", dir / "ouster.json");
  EXPECT_EQ(input_error([&] { (void)open_source((dir / "ouster.pcap").string(), kDefaults); }),
            (dir / "ouster.pcap").string() +
                ": Ouster lidar packets (port 7502); give the sensor's metadata JSON with "
                "--metadata FILE");
  ScanSourceOptions ouster;
  ouster.metadata = (dir / "ouster.json").string();
  auto os = open_source((dir / "ouster.pcap").string(), ouster);
  EXPECT_EQ(os->description(), (dir / "ouster.pcap").string() + " (Ouster pcap)");
  EXPECT_EQ(os->model().rings(), 16);
}

TEST(OpenSource, BagsOfEitherRosVersionOpenAsTheBagSource) {
  test::TempDir dir;
  const auto packets = velodyne_packets();
  ::ringtrack::test::write_rosbag1(
      dir / "ros1.bag", {{"/velodyne_packets", "velodyne_msgs/VelodyneScan"}},
      ::ringtrack::test::velodyne_scan_messages(packets, 0, ::ringtrack::test::RosEncoding::kRos1));
  ::ringtrack::test::write_rosbag2(
      dir / "ros2", {{"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"}},
      ::ringtrack::test::velodyne_scan_messages(packets, 0, ::ringtrack::test::RosEncoding::kCdr));
  // A ROS 1 bag is recognised by its header whatever its name.
  fs::copy_file(dir / "ros1.bag", dir / "renamed.data");
  for (const std::string name : {"ros1.bag", "renamed.data", "ros2"}) {
    SCOPED_TRACE(name);
    const std::string uri = (dir / name).string();
    EXPECT_EQ(guess_scan_input_format(uri),
              name == "ros2" ? ScanInputFormat::kRosbag2 : ScanInputFormat::kRosbag1);
    auto source = open_source(uri, kDefaults);
    EXPECT_EQ(source->description(), uri + " (ROS bag, topic /velodyne_packets)");
    std::size_t scans = 0;
    while (source->next()) ++scans;
    EXPECT_GE(scans, 1u);
    EXPECT_TRUE(source->items_taken().has_value());  // bad messages can be read past
    EXPECT_EQ(source->model().name, "VLP-16");
  }
  ScanSourceOptions topic;
  topic.topic = "/nope";
  EXPECT_THROW((void)open_source((dir / "ros1.bag").string(), topic), core::ConfigError);
}

TEST(OpenSource, ASequenceFolderYieldsItsPoses) {
  test::TempDir dir;
  write_sequence(dir / "seq");
  const SequenceReader reader(dir / "seq");
  EXPECT_EQ(guess_scan_input_format((dir / "seq").string()), ScanInputFormat::kFolder);
  auto source = open_source((dir / "seq").string(), kDefaults);
  EXPECT_EQ(source->description(), (dir / "seq").string() + " (sequence folder)");
  EXPECT_EQ(source->size(), 3u);
  const SequenceReader* folder = source->sequence();
  ASSERT_NE(folder, nullptr);
  EXPECT_TRUE(folder->has_poses());
  EXPECT_FALSE(source->pose());  // nothing read yet
  for (std::size_t k = 0; k < 3; ++k) {
    auto scan = source->next();
    ASSERT_TRUE(scan);
    EXPECT_EQ(scan->stamp_ns, kStart + static_cast<std::int64_t>(k) * kPeriod);
    ASSERT_TRUE(source->pose());
    EXPECT_EQ(source->pose()->stamp_ns, scan->stamp_ns);
    EXPECT_DOUBLE_EQ(source->pose()->translation.x(), 0.5 * static_cast<double>(k));
    EXPECT_DOUBLE_EQ(source->pose()->translation.z(), 1.8);
    EXPECT_EQ(source->items_taken(), k + 1);
  }
  EXPECT_FALSE(source->next());
  EXPECT_FALSE(source->pose());

  // A poses file given in place of poses.txt (TUM: t x y z qx qy qz qw).
  std::string tum;
  for (int k = 0; k < 3; ++k) {
    tum += format_stamp(kStart + k * kPeriod) + " 0 " + std::to_string(k) + " 0 0 0 0 1\n";
  }
  test::write_text(dir / "other.txt", tum);
  ScanSourceOptions options;
  options.poses = dir / "other.txt";
  auto replaced = open_source((dir / "seq").string(), options);
  ASSERT_TRUE(replaced->next());
  ASSERT_TRUE(replaced->next());
  ASSERT_TRUE(replaced->pose());
  EXPECT_DOUBLE_EQ(replaced->pose()->translation.x(), 0.0);
  EXPECT_DOUBLE_EQ(replaced->pose()->translation.y(), 1.0);

  // Recordings carry no poses: a poses file for one is an error, not ignored.
  write_velodyne_pcap(dir / "v.pcap");
  EXPECT_EQ(config_error(options, (dir / "v.pcap").string()),
            "poses " + (dir / "other.txt").string() + ": " + (dir / "v.pcap").string() +
                " is not a folder; recordings carry no poses (match a TUM trajectory to their "
                "stamps)");
}

TEST(OpenSource, FoldersOfPcdOrBinFilesOpenWithoutPoses) {
  test::TempDir dir;
  const auto model = core::SensorModel::vlp16();
  fs::create_directories(dir / "pcd");
  fs::create_directories(dir / "bin");
  for (int k = 0; k < 2; ++k) {
    auto rendered = sim::render(model, sim::SimpleScene::demo());
    rendered.scan.set_uniform_columns(model, kStart + k * kPeriod);
    write_pcd(dir / "pcd" / (std::to_string(k) + ".pcd"), rendered.scan, {});
    write_kitti_bin(dir / "bin" / (std::to_string(k) + ".bin"), core::flatten_scan(rendered.scan));
  }
  for (const std::string name : {"pcd", "bin"}) {
    SCOPED_TRACE(name);
    ScanSourceOptions options;
    options.velodyne.decoder.model = "vlp16";
    auto source = open_source((dir / name).string(), options);
    EXPECT_EQ(source->description(), (dir / name).string() + " (folder of scan files)");
    EXPECT_EQ(source->size(), 2u);
    EXPECT_EQ(source->model().name, "VLP-16");
    ASSERT_TRUE(source->next());
    EXPECT_FALSE(source->pose());  // no poses.txt: the front end decides (a static sensor)
    ASSERT_TRUE(source->next());
    EXPECT_FALSE(source->next());
  }
}

TEST(OpenSource, AFolderSkipsABadFileUnderTheSkipPolicy) {
  test::TempDir dir;
  write_sequence(dir / "seq");
  test::write_text(dir / "seq" / "scans" / "000001.pcd", "not a pcd file\n");
  auto source = open_source((dir / "seq").string(), kDefaults);
  std::vector<std::uint64_t> skipped;
  ScanReader reader(*source, BadScanPolicy::kSkip,
                    [&](std::uint64_t index, const std::string&) { skipped.push_back(index); });
  std::uint64_t index = 0;
  std::vector<std::uint64_t> read;
  while (reader.next(index)) read.push_back(index);
  EXPECT_EQ(read, (std::vector<std::uint64_t>{0, 2}));
  EXPECT_EQ(skipped, (std::vector<std::uint64_t>{1}));

  auto again = open_source((dir / "seq").string(), kDefaults);
  ScanReader stop(*again, BadScanPolicy::kStop);
  ASSERT_TRUE(stop.next(index));
  EXPECT_NE(input_error([&] { (void)stop.next(index); }).find("000001.pcd"), std::string::npos);
}

TEST(OpenSource, UdpUrlsOpenALiveSource) {
  EXPECT_EQ(guess_scan_input_format("udp://127.0.0.1:0"), ScanInputFormat::kUdp);
  auto source = open_source("udp://127.0.0.1:0", kDefaults);
  EXPECT_TRUE(source->live());
  EXPECT_EQ(source->description(), "udp://127.0.0.1:0 (live Velodyne UDP)");
}

TEST(OpenSource, BadOptionsAndUnknownInputsAreOneLine) {
  // Each case changes one field of the defaults.
  const auto error_with = [](const std::function<void(ScanSourceOptions&)>& change) {
    ScanSourceOptions o;
    change(o);
    return config_error(o);
  };
  EXPECT_EQ(error_with([](auto& o) { o.velodyne.decoder.scan_rate_hz = 0.0; }),
            "scan rate 0.000000 Hz: expected a positive number of revolutions per second");
  EXPECT_EQ(error_with([](auto& o) { o.velodyne.pcap.data_port = 0; }),
            "data port 0: expected 1..65535");
  EXPECT_EQ(error_with([](auto& o) { o.velodyne.udp_max_queued_scans = 0; }),
            "udp_max_queued_scans 0: expected at least one queued scan");
  EXPECT_EQ(error_with([](auto& o) { o.ring_field.clear(); }),
            "ring field '': expected the name of a PointCloud2 field (ring)");
  EXPECT_EQ(error_with([](auto& o) {
              o.calibration = "a.csv";
              o.metadata = "b.json";
            }),
            "calibration (Hesai) and metadata (Ouster) given together: expected the one file of "
            "the sensor that recorded the input");
  try {
    (void)parse_scan_input_format("tape");
    ADD_FAILURE() << "no error";
  } catch (const core::ConfigError& e) {
    EXPECT_STREQ(e.what(),
                 "input format 'tape': expected auto, pcap, udp, bag (ROS 1), rosbag2, mcap or "
                 "folder");
  }

  test::TempDir dir;
  EXPECT_EQ(input_error([&] { (void)open_source((dir / "missing.pcap").string(), kDefaults); }),
            (dir / "missing.pcap").string() + ": no such file or folder");
  test::write_text(dir / "notes.txt", "hello\n");
  const std::string e =
      input_error([&] { (void)open_source((dir / "notes.txt").string(), kDefaults); });
  EXPECT_NE(e.find("notes.txt: cannot tell the input format"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  fs::create_directories(dir / "empty");
  EXPECT_NE(input_error([&] {
              (void)open_source((dir / "empty").string(), kDefaults);
            }).find("no sequence.yaml, no .pcd and no .bin files"),
            std::string::npos);
}

}  // namespace
}  // namespace ringtrack::io
