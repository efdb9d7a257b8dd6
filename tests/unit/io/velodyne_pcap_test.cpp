// Captures written by the test-support pcap/pcapng writers: every supported link type, foreign
// traffic, malformed frames and truncated files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/pcap_reader.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;
using test::PcapFrame;
using test::PcapLink;
using test::VelodyneEchoPair;
using test::VelodyneEncoder;
using test::VelodyneEncoderOptions;

class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            ("ringtrack_pcap_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  [[nodiscard]] fs::path file(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

std::vector<test::EncodedVelodynePacket> packets(double revolutions = 2.6,
                                                 std::uint8_t return_mode = 0x37) {
  VelodyneEncoderOptions eo;
  eo.return_mode = return_mode;
  eo.start_azimuth_deg = 250.0;
  eo.start_time_us = 5e8;
  const VelodyneEncoder enc(eo);
  const double per_rev = 360.0 / (enc.advance_deg() * enc.sequences_per_packet());
  return enc.encode(0, static_cast<long long>(revolutions * per_rev), [](long long s, int laser) {
    const auto d =
        static_cast<std::uint16_t>((s * 7 + laser * 131) % 9000 + (laser % 5 == 0 ? 0 : 400));
    return VelodyneEchoPair{{d, static_cast<std::uint8_t>(s + laser)}, {d, 1}};
  });
}

std::vector<core::OrganizedScan> decode_direct(const std::vector<test::EncodedVelodynePacket>& ps,
                                               VelodyneDecoderOptions options = {}) {
  VelodyneDecoder decoder(options);
  std::vector<core::OrganizedScan> scans;
  for (const auto& p : ps) decoder.add_packet(p.payload, p.host_stamp_ns);
  decoder.finish();
  while (auto s = decoder.pop_scan()) scans.push_back(std::move(*s));
  return scans;
}

std::vector<core::OrganizedScan> read_all(VelodynePcapSource& source) {
  std::vector<core::OrganizedScan> scans;
  while (auto s = source.next()) scans.push_back(std::move(*s));
  return scans;
}

// Same cells and (within the file's time resolution) the same stamps.
void expect_same_scans(const std::vector<core::OrganizedScan>& a,
                       const std::vector<core::OrganizedScan>& b, std::int64_t stamp_tolerance_ns) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t s = 0; s < a.size(); ++s) {
    ASSERT_EQ(a[s].size(), b[s].size());
    EXPECT_EQ(a[s].statuses(), b[s].statuses()) << "scan " << s;
    for (std::size_t i = 0; i < a[s].size(); ++i) {
      if (!a[s].valid(i)) continue;
      ASSERT_EQ(a[s].range_m(i), b[s].range_m(i));
      ASSERT_EQ(a[s].intensity(i), b[s].intensity(i));
    }
    for (std::size_t c = 0; c < a[s].column_stamp_ns.size(); ++c) {
      ASSERT_LE(std::abs(a[s].column_stamp_ns[c] - b[s].column_stamp_ns[c]), stamp_tolerance_ns);
      ASSERT_NEAR(a[s].column_azimuth_rad[c], b[s].column_azimuth_rad[c], 1e-12);
    }
  }
}

struct LinkCase {
  PcapLink link;
  int format;  // 0 pcap (us), 1 pcap (ns), 2 pcapng (us)
};

class VelodynePcapLinks : public ::testing::TestWithParam<LinkCase> {};

TEST_P(VelodynePcapLinks, ScansEqualTheDirectDecode) {
  const auto [link, format] = GetParam();
  TempDir dir;
  const auto ps = packets();
  const auto frames = test::frame_packets(link, ps);
  const fs::path path = dir.file(format == 2 ? "cap.pcapng" : "cap.pcap");
  if (format == 2) {
    test::write_pcapng(path, link, frames);
  } else {
    test::write_pcap(path, link, frames, format == 1);
  }
  VelodynePcapSource source(path);
  const auto scans = read_all(source);
  const auto expected = decode_direct(ps);
  ASSERT_EQ(expected.size(), 2u);
  expect_same_scans(scans, expected, format == 1 ? 0 : 1000);
  EXPECT_EQ(source.decoder().stats().decoded_packets, ps.size());
  EXPECT_EQ(source.reader().stats().frames, ps.size());
  EXPECT_FALSE(source.reader().stats().truncated);
  EXPECT_EQ(source.decoder().model().name, "VLP-16");
}

INSTANTIATE_TEST_SUITE_P(
    Links, VelodynePcapLinks,
    ::testing::Values(LinkCase{PcapLink::kEthernet, 0}, LinkCase{PcapLink::kEthernet, 1},
                      LinkCase{PcapLink::kEthernet, 2}, LinkCase{PcapLink::kLinuxSll, 0},
                      LinkCase{PcapLink::kLinuxSll2, 0}, LinkCase{PcapLink::kLinuxSll2, 2},
                      LinkCase{PcapLink::kRawIp, 0}, LinkCase{PcapLink::kRawIp, 2},
                      LinkCase{PcapLink::kNull, 0}));

TEST(VelodynePcap, ForeignTrafficIsIgnoredAndCounted) {
  TempDir dir;
  const auto ps = packets();
  std::vector<PcapFrame> frames;
  const std::vector<std::uint8_t> position(512, 0x24);
  const std::vector<std::uint8_t> odd_sizes[] = {std::vector<std::uint8_t>(100, 1),
                                                 std::vector<std::uint8_t>(1207, 1)};
  std::size_t fragments = 0;
  std::size_t shorts = 0;
  for (std::size_t i = 0; i < ps.size(); ++i) {
    const std::int64_t t = ps[i].host_stamp_ns;
    frames.push_back(test::udp_frame(PcapLink::kEthernet, ps[i].payload, 2368, t));
    if (i % 50 == 0) frames.push_back(test::udp_frame(PcapLink::kEthernet, position, 8308, t));
    if (i % 70 == 1) frames.push_back(test::arp_frame(t));
    if (i % 80 == 2) frames.push_back(test::ipv6_udp_frame(ps[i].payload, 2368, t));
    if (i % 90 == 3) frames.push_back(test::tcp_frame(PcapLink::kEthernet, t));
    if (i % 60 == 4) frames.push_back(test::udp_frame(PcapLink::kEthernet, ps[i].payload, 9999, t));
    if (i % 100 == 5) {  // wrong payload sizes on the data port: counted, skipped
      frames.push_back(test::udp_frame(PcapLink::kEthernet, odd_sizes[0], 2368, t));
      frames.push_back(test::udp_frame(PcapLink::kEthernet, odd_sizes[1], 2368, t));
    }
    if (i % 110 == 6) {  // a first fragment (more-fragments flag set)
      auto f = test::udp_frame(PcapLink::kEthernet, ps[i].payload, 2368, t);
      f.bytes[14 + 6] |= 0x20;
      frames.push_back(f);
      ++fragments;
    }
    if (i % 120 == 7) {  // cut by a small snap length: IP claims more than was captured
      auto f = test::udp_frame(PcapLink::kEthernet, ps[i].payload, 2368, t);
      f.bytes.resize(300);
      frames.push_back(f);
      ++shorts;
    }
  }
  const fs::path path = dir.file("mixed.pcap");
  test::write_pcap(path, PcapLink::kEthernet, frames);
  VelodynePcapSource source(path);
  const auto scans = read_all(source);
  expect_same_scans(scans, decode_direct(ps), 1000);
  const auto n = ps.size();
  auto count = [n](std::size_t every, std::size_t offset) {
    std::size_t c = 0;
    for (std::size_t i = 0; i < n; ++i) c += i % every == offset;
    return c;
  };
  EXPECT_EQ(source.stats().position_datagrams, count(50, 0));
  EXPECT_EQ(source.stats().other_datagrams, count(60, 4));
  EXPECT_EQ(source.reader().stats().non_ipv4, count(70, 1) + count(80, 2));
  EXPECT_EQ(source.reader().stats().non_udp, count(90, 3));
  EXPECT_EQ(source.reader().stats().fragments, fragments);
  EXPECT_EQ(source.reader().stats().short_frames, shorts);
  EXPECT_EQ(source.decoder().stats().wrong_size, 2 * count(100, 5));
  EXPECT_EQ(source.reader().stats().frames, frames.size());
  EXPECT_NE(source.summary().find("position packets ignored"), std::string::npos);
}

TEST(VelodynePcap, TruncatedFileEndsTheStreamOrThrows) {
  TempDir dir;
  const auto ps = packets();
  const fs::path path = dir.file("cut.pcap");
  test::write_pcap(path, PcapLink::kEthernet, test::frame_packets(PcapLink::kEthernet, ps));
  const auto full = fs::file_size(path);
  fs::resize_file(path, full - 700);  // inside the last record
  {
    VelodynePcapSource source(path);
    const auto scans = read_all(source);
    EXPECT_TRUE(source.reader().stats().truncated);
    EXPECT_FALSE(source.reader().stats().truncation_message.empty());
    EXPECT_EQ(source.decoder().stats().decoded_packets, ps.size() - 1);
    std::vector<test::EncodedVelodynePacket> all_but_last(ps.begin(), ps.end() - 1);
    expect_same_scans(scans, decode_direct(all_but_last), 1000);
    EXPECT_NE(source.summary().find("file truncated"), std::string::npos);
  }
  {
    VelodynePcapOptions strict;
    strict.allow_truncated = false;
    VelodynePcapSource source(path, strict);
    try {
      read_all(source);
      FAIL() << "expected an error";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    }
  }
  fs::resize_file(path, 30);  // header plus part of a record header
  {
    VelodynePcapOptions strict;
    strict.allow_truncated = false;
    VelodynePcapSource source(path, strict);
    EXPECT_THROW(read_all(source), core::InputError);
  }
  fs::resize_file(path, 10);  // not even a file header
  EXPECT_THROW(VelodynePcapSource{path}, core::InputError);
}

TEST(VelodynePcap, NotACaptureOrMissingIsAClearError) {
  TempDir dir;
  const fs::path text = dir.file("notes.pcap");
  std::ofstream(text) << "this is not a capture file, just some text that is long enough\n";
  try {
    VelodynePcapSource source(text);
    FAIL() << "expected an error";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("notes.pcap"), std::string::npos) << e.what();
  }
  EXPECT_THROW(VelodynePcapSource{dir.file("missing.pcap")}, core::InputError);
}

TEST(VelodynePcap, UnsupportedLinkTypeIsAnError) {
  TempDir dir;
  const fs::path path = dir.file("wifi.pcap");
  test::write_pcap(path, PcapLink::kEthernet, {});
  {  // patch the link type to 105 (IEEE 802.11)
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(20);
    const char linktype[4] = {105, 0, 0, 0};
    f.write(linktype, 4);
  }
  try {
    VelodynePcapSource source(path);
    FAIL() << "expected an error";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("link type 105"), std::string::npos) << e.what();
  }
}

TEST(VelodynePcap, DataPortIsConfigurableAndNoDataIsAnError) {
  TempDir dir;
  const auto ps = packets(1.2);
  const fs::path path = dir.file("port.pcap");
  test::write_pcap(path, PcapLink::kEthernet, test::frame_packets(PcapLink::kEthernet, ps, 2370));
  {
    VelodynePcapSource source(path);
    try {
      read_all(source);
      FAIL() << "expected an error";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("no Velodyne data packets"), std::string::npos);
    }
    EXPECT_EQ(source.stats().other_datagrams, ps.size());
  }
  VelodynePcapOptions options;
  options.data_port = 2370;
  VelodyneDecoderOptions keep;
  keep.keep_partial_scans = true;
  VelodynePcapSource source(path, options, keep);
  EXPECT_EQ(read_all(source).size(), 2u);
}

TEST(VelodynePcap, BadBlockFlagsAreSkippedAndCounted) {
  TempDir dir;
  auto ps = packets();
  ps[40].payload[0] = 0xAA;
  ps[41].payload[1100] = 0x00;  // block 11 flag
  const fs::path path = dir.file("flags.pcap");
  test::write_pcap(path, PcapLink::kEthernet, test::frame_packets(PcapLink::kEthernet, ps));
  VelodynePcapSource source(path);
  const auto scans = read_all(source);
  EXPECT_EQ(source.decoder().stats().bad_block_flag, 2u);
  EXPECT_EQ(source.decoder().stats().lost_sequences, 48u);
  EXPECT_EQ(scans.size(), 2u);
}

TEST(VelodynePcap, ProductContradictingTheNamedModelNamesTheFrame) {
  TempDir dir;
  const auto ps = packets(0.2);
  const fs::path path = dir.file("model.pcap");
  auto frames = test::frame_packets(PcapLink::kEthernet, ps);
  frames.insert(frames.begin(), test::arp_frame(0));
  test::write_pcap(path, PcapLink::kEthernet, frames);
  VelodyneDecoderOptions options;
  options.model = "hdl32e";
  VelodynePcapSource source(path, {}, options);
  try {
    read_all(source);
    FAIL() << "expected an error";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("(frame 2)"), std::string::npos) << what;
    EXPECT_NE(what.find("VLP-16"), std::string::npos) << what;
    EXPECT_NE(what.find("HDL-32E"), std::string::npos) << what;
  }
}

TEST(PcapReader, ParsesIpv4UdpAndRejectsTheRest) {
  const std::vector<std::uint8_t> payload{1, 2, 3};
  auto frame = test::udp_frame(PcapLink::kRawIp, payload, 2368, 0, 1234);
  UdpDatagram d;
  const char* why = "";
  ASSERT_TRUE(parse_ipv4_udp(frame.bytes.data(), frame.bytes.size(), d, why));
  EXPECT_EQ(d.src_port, 1234);
  EXPECT_EQ(d.dst_port, 2368);
  EXPECT_EQ(d.src_ip, 0xC0A801C9u);  // 192.168.1.201
  ASSERT_EQ(d.payload.size(), 3u);
  EXPECT_EQ(d.payload[2], 3);
  EXPECT_FALSE(parse_ipv4_udp(frame.bytes.data(), 19, d, why));
  EXPECT_STREQ(why, "short");
  auto bad_udp_length = frame.bytes;
  bad_udp_length[20 + 5] = 200;  // UDP length beyond the IP payload
  EXPECT_FALSE(parse_ipv4_udp(bad_udp_length.data(), bad_udp_length.size(), d, why));
  EXPECT_STREQ(why, "short");
  auto offset = frame.bytes;
  offset[7] = 0x10;  // fragment offset
  EXPECT_FALSE(parse_ipv4_udp(offset.data(), offset.size(), d, why));
  EXPECT_STREQ(why, "fragment");
  auto ipv6 = frame.bytes;
  ipv6[0] = 0x60;
  EXPECT_FALSE(parse_ipv4_udp(ipv6.data(), ipv6.size(), d, why));
  EXPECT_STREQ(why, "non-ipv4");
  auto bad_ihl = frame.bytes;
  bad_ihl[0] = 0x44;
  EXPECT_FALSE(parse_ipv4_udp(bad_ihl.data(), bad_ihl.size(), d, why));
}

}  // namespace
}  // namespace ringtrack::io
