// Live UDP: packets replayed to a loopback socket give the same scans as decoding them directly;
// a consumer that falls behind loses whole scans (counted), never parts of one.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <thread>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/pcap_reader.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/io/velodyne_udp_source.hpp"
#include "support/udp_replay.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

using namespace std::chrono_literals;

std::vector<test::EncodedVelodynePacket> packets(double revolutions) {
  test::VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 180.0;
  eo.start_time_us = 2e9;
  const test::VelodyneEncoder enc(eo);
  const double per_rev = 360.0 / (enc.advance_deg() * enc.sequences_per_packet());
  return enc.encode(0, static_cast<long long>(revolutions * per_rev), [](long long s, int laser) {
    const auto d = static_cast<std::uint16_t>(600 + (s * 13 + laser * 71) % 9000);
    return test::VelodyneEchoPair{{d, static_cast<std::uint8_t>(laser * 9)}, {}};
  });
}

// Sends the packets to 127.0.0.1:port (tests/support/udp_replay).
void replay(const std::vector<test::EncodedVelodynePacket>& ps, std::uint16_t port) {
  std::vector<std::vector<std::uint8_t>> payloads;
  for (const auto& p : ps) payloads.push_back(p.payload);
  ASSERT_NO_THROW(test::replay_to_loopback(payloads, port));
}

std::vector<core::OrganizedScan> decode_direct(const std::vector<test::EncodedVelodynePacket>& ps) {
  VelodyneDecoder decoder;
  std::vector<core::OrganizedScan> scans;
  for (const auto& p : ps) decoder.add_packet(p.payload, p.host_stamp_ns);
  decoder.finish();
  while (auto s = decoder.pop_scan()) scans.push_back(std::move(*s));
  return scans;
}

TEST(VelodyneUdp, LoopbackReplayGivesTheFileScans) {
  const auto ps = packets(3.3);
  VelodyneUdpOptions options;
  options.host = "127.0.0.1";
  options.port = 0;
  options.max_queued_scans = 100;
  VelodyneUdpSource source(options);
  ASSERT_NE(source.port(), 0);
  replay(ps, source.port());
  // Wait until every datagram arrived, then stop (flushes the scan in progress).
  for (int i = 0; i < 200 && source.stats().datagrams < ps.size(); ++i)
    std::this_thread::sleep_for(10ms);
  source.stop();
  EXPECT_EQ(source.stats().datagrams, ps.size()) << source.summary();
  std::vector<core::OrganizedScan> scans;
  while (auto s = source.next(0ms)) scans.push_back(std::move(*s));
  const auto expected = decode_direct(ps);
  ASSERT_EQ(expected.size(), 2u);
  ASSERT_EQ(scans.size(), expected.size()) << source.summary();
  for (std::size_t s = 0; s < scans.size(); ++s) {
    EXPECT_EQ(scans[s].statuses(), expected[s].statuses());
    for (std::size_t i = 0; i < scans[s].size(); ++i) {
      if (scans[s].valid(i)) {
        ASSERT_EQ(scans[s].range_m(i), expected[s].range_m(i));
      }
    }
    EXPECT_EQ(scans[s].column_azimuth_rad, expected[s].column_azimuth_rad);
    // Receive stamps (live) are not the encoder's; they must be recent and increasing.
    EXPECT_LT(scans[s].column_stamp_ns.front(), scans[s].column_stamp_ns.back());
  }
  EXPECT_EQ(source.stats().dropped_scans, 0u);
  EXPECT_FALSE(source.next(0ms).has_value());
}

TEST(VelodyneUdp, SlowConsumerLosesWholeScansAndTheyAreCounted) {
  const auto ps = packets(4.3);
  VelodyneUdpOptions options;
  options.host = "127.0.0.1";
  options.port = 0;
  options.max_queued_scans = 1;
  VelodyneUdpSource source(options);
  replay(ps, source.port());  // nobody reads meanwhile
  for (int i = 0; i < 200 && source.stats().datagrams < ps.size(); ++i)
    std::this_thread::sleep_for(10ms);
  source.stop();
  const auto produced = decode_direct(ps).size();
  ASSERT_EQ(produced, 3u);
  EXPECT_EQ(source.stats().dropped_scans, produced - 1) << source.summary();
  auto last = source.next(0ms);
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->valid_count(), decode_direct(ps).back().valid_count());  // the freshest is kept
  EXPECT_NE(source.summary().find("scans dropped"), std::string::npos);
}

// A lossy, reordering network: every tenth datagram lost and every 25th pair swapped. The live
// source keeps going and gives exactly what the decoder makes of the same datagrams offline
// (loopback keeps their order), with the loss and the reordering counted and named.
TEST(VelodyneUdp, LossAndReorderingAreCountedAndTheStreamGoesOn) {
  const auto all = packets(5.3);
  std::vector<test::EncodedVelodynePacket> ps;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i % 10 != 9) ps.push_back(all[i]);
  }
  for (std::size_t i = 20; i + 1 < ps.size(); i += 25) std::swap(ps[i], ps[i + 1]);
  VelodyneUdpOptions options;
  options.host = "127.0.0.1";
  options.port = 0;
  options.max_queued_scans = 100;
  VelodyneUdpSource source(options);
  replay(ps, source.port());
  for (int i = 0; i < 200 && source.stats().datagrams < ps.size(); ++i)
    std::this_thread::sleep_for(10ms);
  source.stop();
  EXPECT_EQ(source.stats().datagrams, ps.size()) << source.summary();

  VelodyneDecoder offline;
  for (const auto& p : ps) offline.add_packet(p.payload, p.host_stamp_ns);
  offline.finish();
  std::vector<core::OrganizedScan> expected;
  while (auto s = offline.pop_scan()) expected.push_back(std::move(*s));
  std::vector<core::OrganizedScan> scans;
  while (auto s = source.next(0ms)) scans.push_back(std::move(*s));
  ASSERT_GE(expected.size(), 4u) << "the stream must go on past the losses";
  ASSERT_EQ(scans.size(), expected.size()) << source.summary();
  for (std::size_t s = 0; s < scans.size(); ++s) {
    EXPECT_EQ(scans[s].statuses(), expected[s].statuses()) << "scan " << s;
  }
  const auto live = source.decoder_stats();
  const auto& direct = offline.stats();
  EXPECT_GT(direct.lost_sequences, 0u);
  EXPECT_GT(direct.out_of_order, 0u);
  EXPECT_EQ(live.lost_sequences, direct.lost_sequences);
  EXPECT_EQ(live.out_of_order, direct.out_of_order);
  EXPECT_EQ(live.decoded_packets, direct.decoded_packets);
  EXPECT_NE(source.summary().find("lost firing sequences"), std::string::npos) << source.summary();
  EXPECT_NE(source.summary().find("skipped packets"), std::string::npos) << source.summary();
}

// The real VLP-16 capture (dual return, 0.4 s, ../shared/data) sent over loopback three ways: at
// the rate it was recorded at (each datagram at its capture time after the first), as fast as
// the receive buffer allows (a 2 ms pause per 20 datagrams: 13 times the sensor's rate), and that
// fast over a lossy, reordering network (every tenth datagram lost, every 25th pair swapped). The
// live source gives exactly the scans the decoder makes of the same datagrams offline, nothing
// dropped, with the loss and the reordering counted.
enum class Pacing { kRecorded, kFast, kLossyFast };

class VelodyneUdpRealCapture : public ::testing::TestWithParam<Pacing> {};

TEST_P(VelodyneUdpRealCapture, GivesTheOfflineScansOfTheSameDatagrams) {
  const char* env = std::getenv("RINGTRACK_TEST_DATA");
  const std::filesystem::path pcap =
      (env != nullptr ? std::filesystem::path(env)
                      : std::filesystem::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data") /
      "vlp16_indoor_nebula" / "vlp16_dual_4scans.pcap";
  if (!std::filesystem::exists(pcap)) GTEST_SKIP() << pcap << " is absent";
  std::vector<std::vector<std::uint8_t>> payloads;
  std::vector<std::int64_t> stamps;
  {
    PcapReader reader(pcap);
    UdpDatagram d;
    while (reader.next(d)) {
      if (d.dst_port != 2368) continue;
      if (GetParam() == Pacing::kLossyFast && stamps.size() % 10 == 9) {
        stamps.push_back(d.stamp_ns);  // lost: keeps the count, not sent
        payloads.emplace_back();
        continue;
      }
      payloads.emplace_back(d.payload.begin(), d.payload.end());
      stamps.push_back(d.stamp_ns);
    }
  }
  for (std::size_t i = payloads.size(); i-- > 0;) {
    if (payloads[i].empty()) {
      payloads.erase(payloads.begin() + static_cast<std::ptrdiff_t>(i));
      stamps.erase(stamps.begin() + static_cast<std::ptrdiff_t>(i));
    }
  }
  if (GetParam() == Pacing::kLossyFast) {
    for (std::size_t i = 20; i + 1 < payloads.size(); i += 25)
      std::swap(payloads[i], payloads[i + 1]);
  }
  VelodyneDecoder offline;
  for (std::size_t i = 0; i < payloads.size(); ++i) offline.add_packet(payloads[i], stamps[i]);
  offline.finish();
  std::vector<core::OrganizedScan> expected;
  while (auto s = offline.pop_scan()) expected.push_back(std::move(*s));
  ASSERT_EQ(expected.size(), 3u);  // as `convert` makes of the file

  VelodyneUdpOptions options;
  options.host = "127.0.0.1";
  options.port = 0;
  options.max_queued_scans = 100;
  VelodyneUdpSource source(options);
  const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(source.port());
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < payloads.size(); ++i) {
    if (GetParam() == Pacing::kRecorded) {
      std::this_thread::sleep_until(start + std::chrono::nanoseconds(stamps[i] - stamps.front()));
    } else if (i % 20 == 19) {
      std::this_thread::sleep_for(2ms);
    }
    ASSERT_EQ(::sendto(fd, payloads[i].data(), payloads[i].size(), 0,
                       reinterpret_cast<const sockaddr*>(&to), sizeof to),
              static_cast<ssize_t>(payloads[i].size()));
  }
  ::close(fd);
  if (GetParam() == Pacing::kRecorded) {
    EXPECT_GE(std::chrono::steady_clock::now() - start,
              std::chrono::nanoseconds(stamps.back() - stamps.front()));
  }
  for (int i = 0; i < 200 && source.stats().datagrams < payloads.size(); ++i)
    std::this_thread::sleep_for(10ms);
  source.stop();
  EXPECT_EQ(source.stats().datagrams, payloads.size()) << source.summary();
  EXPECT_EQ(source.stats().dropped_scans, 0u);
  std::vector<core::OrganizedScan> scans;
  while (auto s = source.next(0ms)) scans.push_back(std::move(*s));
  ASSERT_EQ(scans.size(), expected.size()) << source.summary();
  for (std::size_t s = 0; s < scans.size(); ++s) {
    EXPECT_EQ(scans[s].statuses(), expected[s].statuses()) << "scan " << s;
    for (std::size_t i = 0; i < scans[s].size(); ++i) {
      if (scans[s].valid(i)) {
        ASSERT_EQ(scans[s].range_m(i), expected[s].range_m(i)) << "scan " << s << ", point " << i;
      }
    }
    EXPECT_EQ(scans[s].column_azimuth_rad, expected[s].column_azimuth_rad) << "scan " << s;
  }
  const auto live = source.decoder_stats();
  EXPECT_EQ(live.decoded_packets, offline.stats().decoded_packets);
  EXPECT_EQ(live.lost_sequences, offline.stats().lost_sequences);
  EXPECT_EQ(live.out_of_order, offline.stats().out_of_order);
  if (GetParam() == Pacing::kLossyFast) {
    EXPECT_GT(live.lost_sequences, 0u);
    EXPECT_GT(live.out_of_order, 0u);
  }
}

INSTANTIATE_TEST_SUITE_P(Pacings, VelodyneUdpRealCapture,
                         ::testing::Values(Pacing::kRecorded, Pacing::kFast, Pacing::kLossyFast),
                         [](const ::testing::TestParamInfo<Pacing>& param_info) {
                           switch (param_info.param) {
                             case Pacing::kRecorded:
                               return std::string("RecordedRate");
                             case Pacing::kFast:
                               return std::string("AsFastAsTheBufferAllows");
                             case Pacing::kLossyFast:
                               return std::string("LossyAndReordered");
                           }
                           return std::string();
                         });

TEST(VelodyneUdp, ErrorsOfTheReceiverReachTheConsumer) {
  VelodyneUdpOptions options;
  options.host = "127.0.0.1";
  options.port = 0;
  VelodyneDecoderOptions decoder;
  decoder.model = "vlp32c";  // the packets say VLP-16
  VelodyneUdpSource source(options, decoder);
  replay(packets(0.1), source.port());
  bool thrown = false;
  for (int i = 0; i < 100 && !thrown; ++i) {
    try {
      source.next(20ms);
    } catch (const core::InputError&) {
      thrown = true;
    }
  }
  EXPECT_TRUE(thrown);
}

TEST(VelodyneUdp, UrlsAndBindErrors) {
  EXPECT_EQ(parse_udp_url("udp://:2369").port, 2369);
  EXPECT_EQ(parse_udp_url("udp://*:2369").host, "0.0.0.0");
  EXPECT_EQ(parse_udp_url("udp://192.168.1.77").port, 2368);
  EXPECT_EQ(parse_udp_url("udp://127.0.0.1:0").host, "127.0.0.1");
  EXPECT_THROW(parse_udp_url("tcp://1.2.3.4:5"), core::ConfigError);
  EXPECT_THROW(parse_udp_url("udp://host.example:5"), core::ConfigError);
  EXPECT_THROW(parse_udp_url("udp://1.2.3.4:70000"), core::ConfigError);
  VelodyneUdpOptions options;
  options.host = "127.0.0.1";
  options.port = 0;
  options.reuse_address = false;
  VelodyneUdpSource first(options);
  VelodyneUdpOptions same = options;
  same.port = first.port();
  EXPECT_THROW(VelodyneUdpSource{same}, core::InputError);  // already bound
  options.host = "203.0.113.7";                             // not a local address
  EXPECT_THROW(VelodyneUdpSource{options}, core::InputError);
}

}  // namespace
}  // namespace ringtrack::io
