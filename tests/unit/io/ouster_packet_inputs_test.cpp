// Ouster packets from outside a capture, against the capture of the same hand-encoded packets
// (tests/support/ouster_encoder; the decoder takes the packets' own column stamps, so even the
// stamps agree).
// Live UDP: packets sent to a loopback socket give exactly the capture's scans; a consumer that
// falls behind loses whole scans (counted); the interrupt flag (Ctrl-C) ends the stream with the
// scans received; a packet of another format and a return the profile cannot give are one-line
// errors.
// ROS bags (ROS 1 and rosbag2, ouster-ros's PacketMsg, tests/support/rosbag_writers): the
// lidar-packet topic gives the capture's scans, the IMU topic of the same type is not chosen;
// no metadata, packets of another sensor and a cut message are one-line errors.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/ouster_pcap_source.hpp"
#include "ringtrack/io/ouster_udp_source.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "support/ouster_encoder.hpp"
#include "support/rosbag_writers.hpp"
#include "support/udp_replay.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;
namespace rt = ::ringtrack::test;  // the encoders, writers and senders of tests/support
using namespace std::chrono_literals;
using Packets = std::vector<std::vector<std::uint8_t>>;
using Scans = std::vector<core::OrganizedScan>;
using sensors::ouster::OusterDecoderOptions;
using sensors::ouster::OusterMetadata;
using sensors::ouster::OusterReturn;
using sensors::ouster::parse_ouster_metadata;

constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;

rt::OusterEcho echo_of(int m, int beam) {
  if ((m + beam) % 9 == 0) return {};
  const auto r = static_cast<std::uint32_t>(1000 + 8 * ((m * 7 + beam * 13) % 5000));
  const auto r2 = (m + beam) % 5 == 0
                      ? 0u
                      : static_cast<std::uint32_t>(1000 + 8 * ((m * 5 + beam * 11) % 5000));
  return {r, r2, static_cast<std::uint8_t>((m + beam) % 256),
          static_cast<std::uint8_t>((m * 3 + beam) % 256)};
}

// `frames` frames of 1024 columns from frame id 7; a fraction makes the last one partial.
Packets ouster_packets(rt::OusterEncoderOptions eo, double frames) {
  const int per_frame = 1024 / eo.columns_per_packet;
  const auto n = static_cast<int>(frames * per_frame);
  const int first_frame = eo.frame_id;
  Packets ps;
  for (int k = 0; k < n; ++k) {
    eo.frame_id = first_frame + k / per_frame;
    const int m = (k % per_frame) * eo.columns_per_packet;
    ps.push_back(rt::encode_ouster_packet(
        eo, m, kT0 + static_cast<std::int64_t>(k) * eo.columns_per_packet * 97'656, echo_of));
  }
  return ps;
}

// The packets as a capture (UDP to port 7502).
fs::path write_capture(const Packets& ps, const fs::path& path) {
  std::vector<rt::PcapFrame> frames;
  for (std::size_t k = 0; k < ps.size(); ++k) {
    frames.push_back(rt::udp_frame(rt::PcapLink::kEthernet, ps[k], 7502,
                                   kT0 + static_cast<std::int64_t>(k) * 1'562'500, 7502));
  }
  rt::write_pcap(path, rt::PcapLink::kEthernet, frames, true);
  return path;
}

Scans capture_scans(const fs::path& pcap, const OusterMetadata& meta, OusterDecoderOptions o) {
  OusterPcapSource source(pcap, meta, o);
  Scans scans;
  while (auto s = source.next()) scans.push_back(std::move(*s));
  return scans;
}

void expect_same_scan(const core::OrganizedScan& got, const core::OrganizedScan& want) {
  test::expect_same_decoded_cells(got, want);
  EXPECT_EQ(got.column_stamp_ns, want.column_stamp_ns);
  EXPECT_EQ(got.stamp_ns, want.stamp_ns);
}

class OusterUdpProfiles : public ::testing::TestWithParam<std::tuple<const char*, OusterReturn>> {};

TEST_P(OusterUdpProfiles, LoopbackGivesTheCaptureScans) {
  rt::TempDir tmp;
  rt::OusterEncoderOptions eo;
  eo.profile = std::get<0>(GetParam());
  OusterDecoderOptions o;
  o.return_selection = std::get<1>(GetParam());
  const OusterMetadata meta = parse_ouster_metadata(rt::ouster_metadata_json(eo), "test.json");
  const Packets ps = ouster_packets(eo, 2.5);
  const Scans expected = capture_scans(write_capture(ps, tmp.path() / "o.pcap"), meta, o);
  ASSERT_EQ(expected.size(), 2u);  // frames 7 and 8; frame 9 is partial
  ASSERT_GT(expected[0].valid_count(), 10'000u);

  OusterUdpSource source(test::loopback_udp(100), meta, o);
  const Scans scans = test::receive_replayed(source, ps);
  EXPECT_EQ(source.stats().datagrams, ps.size()) << source.summary();
  ASSERT_EQ(scans.size(), expected.size()) << source.summary();
  for (std::size_t s = 0; s < scans.size(); ++s) expect_same_scan(scans[s], expected[s]);
  EXPECT_EQ(source.stats().dropped_scans, 0u);
  EXPECT_EQ(source.decoder_stats().partial_scans_dropped, 1u);
  EXPECT_NE(
      source.summary().find(std::to_string(ps.size()) + " datagrams, " + std::to_string(ps.size()) +
                            " Ouster lidar packets decoded (" + eo.profile + "), 2 scans"),
      std::string::npos)
      << source.summary();
}

INSTANTIATE_TEST_SUITE_P(
    Profiles, OusterUdpProfiles,
    ::testing::Values(std::tuple{"LEGACY", OusterReturn::kStrongest},
                      std::tuple{"RNG19_RFL8_SIG16_NIR16", OusterReturn::kStrongest},
                      std::tuple{"RNG15_RFL8_NIR8", OusterReturn::kStrongest},
                      std::tuple{"RNG19_RFL8_SIG16_NIR16_DUAL", OusterReturn::kStrongest},
                      std::tuple{"RNG19_RFL8_SIG16_NIR16_DUAL", OusterReturn::kSecond},
                      std::tuple{"RNG19_RFL8_SIG16_NIR16_DUAL", OusterReturn::kLast}),
    [](const auto& param_info) {
      return std::string(std::get<0>(param_info.param)) + "_" +
             sensors::ouster::to_string(std::get<1>(param_info.param));
    });

TEST(OusterUdp, SlowConsumerLosesWholeScansAndTheyAreCounted) {
  rt::TempDir tmp;
  const rt::OusterEncoderOptions eo;
  const OusterMetadata meta = parse_ouster_metadata(rt::ouster_metadata_json(eo), "test.json");
  const Packets ps = ouster_packets(eo, 3.5);
  const Scans expected = capture_scans(write_capture(ps, tmp.path() / "o.pcap"), meta, {});
  ASSERT_EQ(expected.size(), 3u);
  OusterUdpSource source(test::loopback_udp(1), meta);
  const Scans scans = test::receive_replayed(source, ps);  // nobody reads meanwhile
  EXPECT_EQ(source.stats().dropped_scans, 2u) << source.summary();
  ASSERT_EQ(scans.size(), 1u);
  expect_same_scan(scans[0], expected.back());  // the freshest is kept
  EXPECT_NE(source.summary().find("2 scans dropped (consumer behind)"), std::string::npos)
      << source.summary();
}

// Through io::open_source as `ringtrack run udp://... --metadata FILE` opens it: the interrupt
// flag ends the stream after the scans received, the partial frame in progress is dropped.
TEST(OusterUdp, OpenSourceAndInterrupt) {
  rt::TempDir tmp;
  const rt::OusterEncoderOptions eo;
  const fs::path json = tmp.path() / "os.json";
  test::write_text(json, rt::ouster_metadata_json(eo));
  const Packets ps = ouster_packets(eo, 2.5);
  const Scans expected =
      capture_scans(write_capture(ps, tmp.path() / "o.pcap"),
                    parse_ouster_metadata(rt::ouster_metadata_json(eo), "x"), {});
  const std::uint16_t port = rt::free_udp_port();
  const std::string url = "udp://127.0.0.1:" + std::to_string(port);
  std::atomic<bool> interrupt{false};
  ScanSourceOptions options;
  options.metadata = json.string();
  options.velodyne.interrupt = &interrupt;
  options.velodyne.udp_max_queued_scans = 10;
  const auto source = open_source(url, options);
  EXPECT_TRUE(source->live());
  EXPECT_EQ(source->description(), url + " (live Ouster UDP)");
  EXPECT_EQ(source->model().rings(), 16);  // known from the metadata before any packet
  rt::replay_to_loopback(ps, port);
  Scans scans;
  for (int i = 0; i < 2; ++i) {
    auto scan = source->next();
    ASSERT_TRUE(scan.has_value());
    scans.push_back(std::move(*scan));
  }
  interrupt = true;
  EXPECT_FALSE(source->next().has_value());
  ASSERT_EQ(scans.size(), expected.size());
  for (std::size_t s = 0; s < scans.size(); ++s) expect_same_scan(scans[s], expected[s]);
  const std::string summary = source->summary();
  EXPECT_EQ(summary.rfind(url + ": ", 0), 0u) << summary;
  EXPECT_NE(summary.find("2 scans"), std::string::npos) << summary;
  EXPECT_NE(summary.find("1 partial scans dropped"), std::string::npos) << summary;
}

TEST(OusterUdp, TheLidarPortIsTheDefault) {
  EXPECT_EQ(parse_udp_url("udp://127.0.0.1", kOusterLidarPort).port, 7502);
  EXPECT_EQ(parse_udp_url("udp://127.0.0.1").port, 2368);
  EXPECT_EQ(parse_udp_url("udp://127.0.0.1:7512", kOusterLidarPort).port, 7512);
}

TEST(OusterUdp, BadInputIsOneLineError) {
  rt::OusterEncoderOptions eo;
  const OusterMetadata meta = parse_ouster_metadata(rt::ouster_metadata_json(eo), "os.json");
  // Packets of another sensor (32 beams where the metadata says 16): the receiver's error
  // reaches the consumer.
  {
    OusterUdpSource source(test::loopback_udp(2), meta);
    rt::OusterEncoderOptions other = eo;
    other.pixels_per_column = 32;
    rt::replay_to_loopback(ouster_packets(other, 0.1), source.port());
    std::string error;
    try {
      for (int i = 0; i < 100 && error.empty(); ++i) (void)source.next(20ms);
    } catch (const core::InputError& e) {
      error = e.what();
    }
    EXPECT_NE(
        error.find(
            "udp://127.0.0.1:0: ouster packet 1: 6400 bytes, but the metadata (os.json) describes "
            "RNG19_RFL8_SIG16_NIR16 packets of 16 columns x 16 pixels = 3328 bytes"),
        std::string::npos)
        << error;
    EXPECT_EQ(error.find('\n'), std::string::npos);
    EXPECT_TRUE(source.stopped());
  }
  // The second return of a single-return profile: refused before the socket is bound.
  OusterDecoderOptions second;
  second.return_selection = OusterReturn::kSecond;
  try {
    OusterUdpSource source(test::loopback_udp(2), meta, second);
    ADD_FAILURE() << "no error";
  } catch (const core::InputError& e) {
    EXPECT_STREQ(e.what(),
                 "os.json: the second return needs the RNG19_RFL8_SIG16_NIR16_DUAL profile, but "
                 "the sensor sends RNG19_RFL8_SIG16_NIR16 (one return per pixel: the strongest)");
  }
}

// ---- ROS bags of ouster-ros packets ----

// A bag as ouster-ros records it: IMU packets (48 bytes) first on their own topic of the same
// type, then one message per lidar packet on /ouster/lidar_packets.
void write_ouster_bag(const fs::path& path, const Packets& ps, rt::RosEncoding encoding,
                      bool ros1) {
  const std::string type = ros1 ? "ouster_ros/PacketMsg" : "ouster_sensor_msgs/msg/PacketMsg";
  const std::vector<rt::TestBagTopic> topics{{"/ouster/imu_packets", type},
                                             {"/ouster/lidar_packets", type}};
  std::vector<rt::TestBagMessage> messages;
  for (std::size_t k = 0; k < ps.size(); ++k) {
    const std::int64_t stamp = kT0 + static_cast<std::int64_t>(k) * 1'562'500;
    if (k % 8 == 0) {
      messages.push_back(
          {0, stamp, rt::serialize_ouster_packet(std::vector<std::uint8_t>(48, 3), encoding)});
    }
    messages.push_back({1, stamp, rt::serialize_ouster_packet(ps[k], encoding)});
  }
  if (ros1) {
    rt::write_rosbag1(path, topics, messages);
  } else {
    rt::write_rosbag2(path, topics, messages);
  }
}

Scans read_all(ScanSource& source) {
  Scans scans;
  while (auto s = source.next()) scans.push_back(std::move(*s));
  return scans;
}

class OusterBags : public ::testing::TestWithParam<bool> {};  // ROS 1 or rosbag2

TEST_P(OusterBags, LidarPacketsGiveTheCaptureScans) {
  const bool ros1 = GetParam();
  rt::TempDir tmp;
  rt::OusterEncoderOptions eo;
  eo.profile = "RNG19_RFL8_SIG16_NIR16_DUAL";
  const fs::path json = tmp.path() / "os.json";
  test::write_text(json, rt::ouster_metadata_json(eo));
  const Packets ps = ouster_packets(eo, 2.5);
  const fs::path pcap = write_capture(ps, tmp.path() / "o.pcap");
  const fs::path bag = tmp.path() / (ros1 ? "o.bag" : "o_bag");
  write_ouster_bag(bag, ps, ros1 ? rt::RosEncoding::kRos1 : rt::RosEncoding::kCdr, ros1);
  for (const std::string selection : {"auto", "last"}) {
    ScanSourceOptions options;
    options.metadata = json.string();
    options.velodyne.decoder.return_selection = parse_velodyne_return_selection(selection);
    const auto from_capture = open_source(pcap.string(), options);
    const Scans expected = read_all(*from_capture);
    ASSERT_EQ(expected.size(), 2u);
    const auto from_bag = open_source(bag.string(), options);
    const Scans scans = read_all(*from_bag);
    ASSERT_EQ(scans.size(), expected.size()) << from_bag->summary();
    for (std::size_t s = 0; s < scans.size(); ++s) expect_same_scan(scans[s], expected[s]);
    EXPECT_EQ(from_bag->model().rings(), 16);
    EXPECT_NE(from_bag->description().find("topic /ouster/lidar_packets"), std::string::npos);
    EXPECT_NE(
        from_bag->summary().find(std::to_string(ps.size()) + " messages of /ouster/lidar_packets"),
        std::string::npos)
        << from_bag->summary();
    EXPECT_NE(from_bag->summary().find(
                  std::to_string(ps.size()) +
                  " Ouster lidar packets decoded (RNG19_RFL8_SIG16_NIR16_DUAL), 2 scans"),
              std::string::npos)
        << from_bag->summary();
  }
}

TEST_P(OusterBags, BadInputIsOneLineError) {
  const bool ros1 = GetParam();
  const auto encoding = ros1 ? rt::RosEncoding::kRos1 : rt::RosEncoding::kCdr;
  rt::TempDir tmp;
  const rt::OusterEncoderOptions eo;
  const fs::path json = tmp.path() / "os.json";
  test::write_text(json, rt::ouster_metadata_json(eo));
  const fs::path bag = tmp.path() / (ros1 ? "o.bag" : "o_bag");
  write_ouster_bag(bag, ouster_packets(eo, 1.2), encoding, ros1);
  const auto error_of = [](const std::string& input, const ScanSourceOptions& options) {
    try {
      const auto source = open_source(input, options);
      while (source->next()) {
      }
    } catch (const core::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  ScanSourceOptions none;
  EXPECT_NE(error_of(bag.string(), none)
                .find("topic /ouster/lidar_packets holds Ouster packets; give the sensor's "
                      "metadata JSON with --metadata FILE"),
            std::string::npos);
  // Metadata of another sensor (32 beams): the first packet names the message.
  rt::OusterEncoderOptions other = eo;
  other.pixels_per_column = 32;
  const fs::path json32 = tmp.path() / "os32.json";
  test::write_text(json32, rt::ouster_metadata_json(other));
  ScanSourceOptions wrong;
  wrong.metadata = json32.string();
  std::string e = error_of(bag.string(), wrong);
  EXPECT_NE(e.find("(topic /ouster/lidar_packets, message 1): ouster packet 1: 3328 bytes, but "
                   "the metadata (" +
                   json32.string() + ") describes RNG19_RFL8_SIG16_NIR16 packets"),
            std::string::npos)
      << e;
  EXPECT_EQ(e.find('\n'), std::string::npos);
  // The IMU topic named: its 48-byte packets are not lidar packets.
  ScanSourceOptions imu;
  imu.metadata = json.string();
  imu.topic = "/ouster/imu_packets";
  e = error_of(bag.string(), imu);
  EXPECT_NE(e.find("(topic /ouster/imu_packets, message 1): ouster packet 1: 48 bytes"),
            std::string::npos)
      << e;
  // The second return of a single-return profile.
  ScanSourceOptions second;
  second.metadata = json.string();
  second.velodyne.decoder.return_selection = VelodyneReturnSelection::kSecond;
  EXPECT_NE(error_of(bag.string(), second)
                .find("the second return needs the RNG19_RFL8_SIG16_NIR16_DUAL profile"),
            std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(Formats, OusterBags, ::testing::Values(true, false),
                         [](const auto& param_info) {
                           return param_info.param ? "Ros1" : "Rosbag2";
                         });

TEST(OusterBags, APacketMessageCutShortIsOneLineError) {
  const std::vector<std::uint8_t> packet(100, 1);
  for (const auto encoding : {rt::RosEncoding::kRos1, rt::RosEncoding::kCdr}) {
    auto message = rt::serialize_ouster_packet(packet, encoding);
    const auto serialization =
        encoding == rt::RosEncoding::kRos1 ? RosSerialization::kRos1 : RosSerialization::kCdr;
    EXPECT_EQ(parse_ouster_packet_msg(message, serialization, "b.bag").size(), 100u);
    message.resize(message.size() - 1);
    try {
      (void)parse_ouster_packet_msg(message, serialization, "b.bag");
      ADD_FAILURE() << "no error";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("b.bag: PacketMsg: buf bytes: claims 100 elements"),
                std::string::npos)
          << e.what();
    }
  }
}

}  // namespace
}  // namespace ringtrack::io
