// Live Hesai packets (udp://HOST:2368 with --calibration): hand-encoded PandarXT32 packets sent
// over the loopback interface give the cells a capture of the same packets gives.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/hesai_pcap_source.hpp"
#include "ringtrack/io/hesai_udp_source.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/sensors/hesai/hesai_calibration.hpp"
#include "support/hesai_encoder.hpp"
#include "support/udp_replay.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;
namespace rt = ::ringtrack::test;
using Packets = std::vector<std::vector<std::uint8_t>>;
using Scans = std::vector<core::OrganizedScan>;

constexpr std::int64_t kT0 = 1'700'000'000'000'000'000;
constexpr std::uint16_t kPort = 2368;

// `revolutions` revolutions of a PandarXT32 at 10 Hz; ranges and reflectivities vary with the
// firing and channel, and some channels return nothing.
Packets hesai_packets(const rt::HesaiEncoder& enc, double revolutions) {
  const int per_revolution = enc.firings_per_revolution() / enc.firings_per_packet();
  return enc.encode(0, static_cast<int>(revolutions * per_revolution), [](long long f, int ch) {
    if ((f + ch) % 11 == 0) return std::pair<rt::HesaiEcho, rt::HesaiEcho>{};
    const rt::HesaiEcho e{static_cast<std::uint16_t>(500 + (f * 7 + ch * 13) % 3000),
                          static_cast<std::uint8_t>((f + 3 * ch) % 256)};
    return std::pair{e, e};
  });
}

// The packets as a capture to the data port, 0.4 ms apart (250 packets per revolution).
fs::path write_capture(const Packets& ps, const fs::path& path) {
  std::vector<rt::PcapFrame> frames;
  for (std::size_t k = 0; k < ps.size(); ++k) {
    frames.push_back(rt::udp_frame(rt::PcapLink::kEthernet, ps[k], kPort,
                                   kT0 + static_cast<std::int64_t>(k) * 400'000));
  }
  rt::write_pcap(path, rt::PcapLink::kEthernet, frames);
  return path;
}

sensors::hesai::HesaiDecoderOptions decoder_options(int channels) {
  sensors::hesai::HesaiDecoderOptions o;
  o.calibration =
      sensors::hesai::parse_hesai_calibration(rt::hesai_calibration_csv(channels), "test.csv");
  return o;
}

Scans capture_scans(const fs::path& pcap, const sensors::hesai::HesaiDecoderOptions& o) {
  HesaiPcapSource source(pcap, kPort, o);
  Scans scans;
  while (auto s = source.next()) scans.push_back(std::move(*s));
  return scans;
}

TEST(HesaiUdp, LoopbackGivesTheCaptureCells) {
  test::TempDir tmp;
  const rt::HesaiEncoder enc({});
  const Packets ps = hesai_packets(enc, 2.5);
  const auto options = decoder_options(enc.channels());
  const Scans expected = capture_scans(write_capture(ps, tmp.path() / "h.pcap"), options);
  ASSERT_GE(expected.size(), 2u);
  ASSERT_GT(expected[0].valid_count(), 10'000u);

  HesaiUdpSource source(test::loopback_udp(100), options);
  const auto now_ns = [] {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
  };
  const std::int64_t before_ns = now_ns();
  const Scans scans = test::receive_replayed(source, ps);
  const std::int64_t after_ns = now_ns();
  EXPECT_EQ(source.stats().datagrams, ps.size()) << source.summary();
  ASSERT_EQ(scans.size(), expected.size()) << source.summary();
  for (std::size_t s = 0; s < scans.size(); ++s) {
    test::expect_same_decoded_cells(scans[s], expected[s]);  // stamps: receive times, below
    // Stamped from the kernel's receive times (less the packet's firings, at most a millisecond
    // before it arrived): within the replay. Not necessarily ascending: the replay sends in
    // bursts, a sensor evenly.
    for (const std::int64_t t : scans[s].column_stamp_ns) {
      if (t == 0) continue;  // a column no packet filled
      ASSERT_GE(t, before_ns - 1'000'000);
      ASSERT_LE(t, after_ns);
    }
  }
  EXPECT_EQ(source.stats().dropped_scans, 0u);
  EXPECT_EQ(source.decoder_stats().decoded_packets, ps.size());
  EXPECT_NE(source.summary().find(std::to_string(ps.size()) + " datagrams, " +
                                  std::to_string(ps.size()) + " Hesai packets decoded, " +
                                  std::to_string(expected.size()) + " scans"),
            std::string::npos)
      << source.summary();
}

// Damaged datagrams on a live network are counted, not fatal: the scans around them still come.
TEST(HesaiUdp, WrongSizeDatagramsAreCountedNotFatal) {
  const rt::HesaiEncoder enc({});
  Packets ps = hesai_packets(enc, 2.5);
  ps.insert(ps.begin() + 100, std::vector<std::uint8_t>(77, 0xEE));
  ps.insert(ps.begin() + 300, std::vector<std::uint8_t>(ps[0].begin(), ps[0].end() - 9));
  HesaiUdpSource source(test::loopback_udp(100), decoder_options(enc.channels()));
  const Scans scans = test::receive_replayed(source, ps);
  EXPECT_GE(scans.size(), 2u) << source.summary();
  EXPECT_EQ(source.decoder_stats().skipped_packets(), 2u) << source.summary();
  EXPECT_NE(source.summary().find("2 wrong-size"), std::string::npos) << source.summary();
}

// Through io::open_source as `ringtrack run udp://... --calibration FILE` opens it, and the
// one-line error when a Hesai model is named without its angle corrections.
TEST(HesaiUdp, OpenSourceWithTheCalibrationAndOneLineErrorWithout) {
  test::TempDir tmp;
  const rt::HesaiEncoder enc({});
  const fs::path csv = tmp.path() / "xt32.csv";
  test::write_text(csv, rt::hesai_calibration_csv(enc.channels()));
  const std::uint16_t port = rt::free_udp_port();
  const std::string url = "udp://127.0.0.1:" + std::to_string(port);
  std::atomic<bool> interrupt{false};
  ScanSourceOptions options;
  options.calibration = csv.string();
  options.velodyne.interrupt = &interrupt;
  options.velodyne.udp_max_queued_scans = 10;
  {
    const auto source = open_source(url, options);
    EXPECT_TRUE(source->live());
    EXPECT_EQ(source->description(), url + " (live Hesai UDP)");
    rt::replay_to_loopback(hesai_packets(enc, 1.5), port);
    auto scan = source->next();
    ASSERT_TRUE(scan.has_value());
    EXPECT_EQ(scan->rings(), 32);
    EXPECT_EQ(source->model().rings(), 32);
    interrupt = true;
    while (source->next()) {
    }
  }
  ScanSourceOptions named;
  named.velodyne.decoder.model = "PandarXT32";
  try {
    (void)open_source(url, named);
    FAIL() << "expected an error";
  } catch (const core::InputError& e) {
    EXPECT_EQ(std::string(e.what()), url +
                                         ": Hesai PandarXT32 packets; give the sensor's "
                                         "angle-correction file with --calibration FILE");
  }
}

}  // namespace
}  // namespace ringtrack::io
