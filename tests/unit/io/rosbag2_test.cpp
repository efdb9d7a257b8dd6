// ROS 2 bags through the generic bag source: the real bag carries the pcap's packets byte for
// byte, gives its scans cell for cell and reproduces the reference scan; synthetic bags (test
// support writer) cover both message types, topic choice, the Velodyne source factory, split
// bags and corrupt input.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/pcap_reader.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/rosbag2_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"
#include "support/rosbag_writers.hpp"
#include "support/temp_dir.hpp"
#include "support/velodyne_encoder.hpp"
#include "support/zstd_util.hpp"

namespace ringtrack::io {
namespace {

// Default options, named: a braced temporary trips g++ 12's -Wmaybe-uninitialized.
const ScanSourceOptions kDefaults;

namespace fs = std::filesystem;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

fs::path data_dir() {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA")) {
    return fs::path(env) / "vlp16_indoor_nebula";
  }
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "vlp16_indoor_nebula";
}

#define REQUIRE_REAL_DATA(dir)                                                               \
  if (!fs::exists((dir) / "ros2_bag" / "metadata.yaml") ||                                   \
      !fs::exists((dir) / "vlp16_dual_4scans.pcap") ||                                       \
      !fs::exists((dir) / "reference_last_scan.pcd")) {                                      \
    GTEST_SKIP() << "real VLP-16 test data not found at " << (dir)                           \
                 << " (set RINGTRACK_TEST_DATA to the folder holding vlp16_indoor_nebula/)"; \
  }

// Same cells and azimuths; stamps within a tolerance (a pcap stores receive stamps in us, the
// real bag in ns).
void expect_same_scans(ScanSource& source, const std::vector<core::OrganizedScan>& expected,
                       std::int64_t stamp_tolerance_ns = 0) {
  std::size_t n = 0;
  while (auto s = source.next()) {
    ASSERT_LT(n, expected.size());
    const auto& e = expected[n++];
    ASSERT_EQ(s->statuses(), e.statuses()) << "scan " << n;
    for (std::size_t i = 0; i < e.size(); ++i) {
      if (e.valid(i)) {
        ASSERT_EQ(s->range_m(i), e.range_m(i)) << "scan " << n << " cell " << i;
        ASSERT_EQ(s->intensity(i), e.intensity(i));
        ASSERT_EQ(s->point(i), e.point(i));
      }
    }
    EXPECT_EQ(s->column_azimuth_rad, e.column_azimuth_rad);
    ASSERT_EQ(s->column_stamp_ns.size(), e.column_stamp_ns.size());
    for (std::size_t c = 0; c < e.column_stamp_ns.size(); ++c) {
      ASSERT_LE(std::abs(s->column_stamp_ns[c] - e.column_stamp_ns[c]), stamp_tolerance_ns)
          << "column " << c;
    }
  }
  EXPECT_EQ(n, expected.size());
}

TEST(Rosbag2, RealBagGivesThePcapScansCellForCell) {
  const fs::path dir = data_dir();
  REQUIRE_REAL_DATA(dir);
  for (const auto selection :
       {VelodyneReturnSelection::kLast, VelodyneReturnSelection::kStrongest}) {
    ScanSourceOptions options;
    options.velodyne.decoder.return_selection = selection;
    auto bag = open_source((dir / "ros2_bag").string(), options);
    EXPECT_EQ(guess_scan_input_format((dir / "ros2_bag").string()), ScanInputFormat::kRosbag2);
    VelodynePcapSource pcap(dir / "vlp16_dual_4scans.pcap", {}, options.velodyne.decoder);
    std::vector<core::OrganizedScan> expected;
    while (auto s = pcap.next()) expected.push_back(std::move(*s));
    ASSERT_EQ(expected.size(), 3u);
    expect_same_scans(*bag, expected, 1000);
    EXPECT_EQ(bag->model().name, "VLP-16");
    EXPECT_NE(bag->summary().find("4 messages of /velodyne_packets"), std::string::npos)
        << bag->summary();
  }
}

// The bag was recorded from the same packets as the capture: every packet, in order, byte for
// byte, with its receive stamp (the capture's have us resolution).
TEST(Rosbag2, RealBagCarriesThePcapPacketsByteForByte) {
  const fs::path dir = data_dir();
  REQUIRE_REAL_DATA(dir);
  Rosbag2Reader bag(dir / "ros2_bag");
  ASSERT_EQ(bag.topics().size(), 1u);
  EXPECT_EQ(bag.topics()[0].name, "/velodyne_packets");
  EXPECT_EQ(bag.topics()[0].type, "velodyne_msgs/msg/VelodyneScan");
  EXPECT_EQ(bag.topics()[0].messages, 4u);
  bag.select_topic("/velodyne_packets");
  PcapReader pcap(dir / "vlp16_dual_4scans.pcap");
  UdpDatagram d;
  RosbagMessage m;
  std::vector<VelodyneScanPacket> packets;  // of the current message
  std::size_t used = 0;
  std::size_t n = 0;
  while (pcap.next(d)) {
    while (used == packets.size()) {
      ASSERT_TRUE(bag.next(m)) << "the bag ends after " << n << " packets";
      packets =
          parse_velodyne_scan(m.data, bag.serialization(), "message " + std::to_string(m.index));
      used = 0;
    }
    const VelodyneScanPacket& p = packets[used++];
    ASSERT_TRUE(std::equal(d.payload.begin(), d.payload.end(), p.data.begin(), p.data.end()))
        << "packet " << n;
    EXPECT_LE(std::abs(p.stamp_ns - d.stamp_ns), 1000) << "packet " << n;
    ++n;
  }
  EXPECT_EQ(n, 603u);
  EXPECT_EQ(used, packets.size());
  EXPECT_FALSE(bag.next(m));
  EXPECT_EQ(m.index, 4u);
}

// reference_last_scan.pcd (see the data README): nebula's decoding of the last revolution, dual
// return; with the last return selected, every reference return of the first block of each
// pair (and each identical pair) must be a cell of the bag's last scan, and vice versa.
TEST(Rosbag2, RealBagReproducesTheReferenceScan) {
  const fs::path dir = data_dir();
  REQUIRE_REAL_DATA(dir);
  RosbagSourceOptions options;
  options.decoder.return_selection = VelodyneReturnSelection::kLast;
  RosbagScanSource bag(dir / "ros2_bag", options);
  std::optional<core::OrganizedScan> last;
  while (auto s = bag.next()) last = std::move(s);
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(bag.stats().messages, 4u);
  EXPECT_EQ(bag.stats().packets, 603u);
  const core::OrganizedScan& scan = *last;

  std::ifstream in(dir / "reference_last_scan.pcd", std::ios::binary);
  const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in),
                                        std::istreambuf_iterator<char>()};
  const PcdHeader h = parse_pcd_header(bytes, "reference_last_scan.pcd");
  ASSERT_EQ(h.encoding, PcdEncoding::kBinary);
  ASSERT_EQ(h.points(), 14831u);
  const PcdField* channel = h.find("channel");
  const PcdField* azimuth = h.find("azimuth");
  const PcdField* distance = h.find("distance");
  const PcdField* type = h.find("return_type");
  ASSERT_TRUE(channel && azimuth && distance && type);
  ASSERT_EQ(channel->size, 2);
  ASSERT_EQ(type->size, 1);
  struct Ref {
    int channel;
    double azimuth_deg;  // Velodyne (clockwise) convention
    float distance;
  };
  std::vector<Ref> refs;
  const std::size_t record = h.point_bytes();
  for (std::size_t p = 0; p < h.points(); ++p) {
    const std::uint8_t* r = bytes.data() + h.data_offset + p * record;
    std::uint16_t ch = 0;
    float az = 0;
    float d = 0;
    std::memcpy(&ch, r + channel->offset, 2);
    std::memcpy(&az, r + azimuth->offset, 4);
    std::memcpy(&d, r + distance->offset, 4);
    const std::uint8_t t = r[type->offset];
    // nebula return types: 4 first-weak, 9 first-strongest (the pair's first block = the last
    // return), 6 identical.
    if (t == 4 || t == 9 || t == 6) refs.push_back({ch, az * kRadToDeg, d});
  }
  // Away from both seams (the reference ends at 359 deg, ours at 360).
  const auto in_window = [](double deg) { return deg > 1.5 && deg < 357.5; };
  const auto diff = [](double a, double b) { return std::abs(std::remainder(a - b, 360.0)); };
  std::size_t expected = 0;
  std::size_t matched = 0;
  for (const auto& r : refs) {
    if (!in_window(r.azimuth_deg)) continue;
    ++expected;
    const int center = static_cast<int>(r.azimuth_deg / (360.0 / scan.columns()));
    bool found = false;
    for (int k = center - 6; k <= center + 6 && !found; ++k) {
      const int c = (k + scan.columns()) % scan.columns();
      const double column_deg =
          360.0 - scan.column_azimuth_rad[static_cast<std::size_t>(c)] * kRadToDeg;
      if (diff(column_deg, r.azimuth_deg) > 0.5) continue;
      const std::size_t i = scan.index(r.channel, c);
      found = scan.valid(i) && std::abs(scan.range_m(i) - r.distance) < 1e-3f;
    }
    matched += found ? 1 : 0;
  }
  EXPECT_GT(expected, 14000u);
  EXPECT_EQ(matched, expected);
  std::size_t cells = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    const Eigen::Vector3f xyz = scan.point(i);
    const double deg = std::fmod(-std::atan2(xyz.y(), xyz.x()) * kRadToDeg + 360.0, 360.0);
    cells += in_window(deg) ? 1 : 0;
  }
  EXPECT_NEAR(static_cast<double>(cells), static_cast<double>(expected), 40.0);
}

std::vector<test::EncodedVelodynePacket> encode_packets(double revolutions) {
  test::VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 200.0;
  const test::VelodyneEncoder enc(eo);
  const double per_rev = 360.0 / (enc.advance_deg() * enc.sequences_per_packet());
  return enc.encode(0, static_cast<long long>(revolutions * per_rev), [](long long s, int laser) {
    const auto d = static_cast<std::uint16_t>(700 + (s * 11 + laser * 97) % 7000);
    return test::VelodyneEchoPair{{d, static_cast<std::uint8_t>(laser * 3)}, {}};
  });
}

std::vector<test::TestBagMessage> scan_messages(const std::vector<test::EncodedVelodynePacket>& ps,
                                                std::size_t topic) {
  return test::velodyne_scan_messages(ps, topic, test::RosEncoding::kCdr);
}

std::vector<core::OrganizedScan> decode_direct(const std::vector<test::EncodedVelodynePacket>& ps) {
  VelodyneDecoder decoder;
  for (const auto& p : ps) decoder.add_packet(p.payload, p.host_stamp_ns);
  decoder.finish();
  std::vector<core::OrganizedScan> scans;
  while (auto s = decoder.pop_scan()) scans.push_back(std::move(*s));
  return scans;
}

test::TestBagMessage cloud_message(std::size_t topic, int m) {
  const auto model = core::SensorModel::vlp16();
  std::vector<test::TestPoint> pts;
  for (int ring = 0; ring < 16; ++ring) {
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3f p = model.point(ring, 0.3 + 1.5 * k, 2.0 + 0.1 * m + 0.05 * ring);
      pts.push_back({p.x(), p.y(), p.z(), 5.0f, static_cast<std::uint16_t>(ring), 0.0f});
    }
  }
  const std::int64_t stamp = 1'000'000'000LL * (m + 1);
  return {topic, stamp,
          test::serialize_pointcloud2(test::make_xyzirt_cloud(pts, 1, 64, stamp),
                                      test::RosEncoding::kCdr)};
}

void expect_input_error(const std::function<void()>& f, const std::vector<std::string>& needles) {
  try {
    f();
    ADD_FAILURE() << "expected an InputError mentioning " << needles.front();
  } catch (const core::InputError& e) {
    for (const auto& n : needles) {
      EXPECT_NE(std::string(e.what()).find(n), std::string::npos) << e.what();
    }
  }
}

const std::vector<test::TestBagTopic> kTopics{
    {"/rosout", "rcl_interfaces/msg/Log"},
    {"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"},
    {"/velodyne_points", "sensor_msgs/msg/PointCloud2"}};

TEST(Rosbag2, BothMessageTypesAndTopicChoice) {
  test::TempDir dir;
  const auto ps = encode_packets(3.3);
  auto messages = scan_messages(ps, 1);
  for (int m = 0; m < 3; ++m) messages.push_back(cloud_message(2, m));
  messages.push_back({0, 5, {0, 1, 0, 0, 1, 2, 3, 4}});
  const fs::path bag = dir.path() / "bag";
  test::write_rosbag2(bag, kTopics, messages);

  {
    RosbagScanSource source(bag);  // the first supported topic
    EXPECT_EQ(source.topic().name, "/velodyne_packets");
    expect_same_scans(source, decode_direct(ps));
    EXPECT_EQ(source.stats().messages, scan_messages(ps, 1).size());
    EXPECT_EQ(source.stats().packets, ps.size());
    EXPECT_EQ(source.decoder().stats().decoded_packets, ps.size());
    EXPECT_EQ(source.reader().other_messages(), 4u);
  }
  RosbagSourceOptions options;
  options.topic = "/velodyne_points";
  RosbagScanSource clouds(bag, options);
  EXPECT_FALSE(clouds.velodyne_packets());
  for (int m = 0; m < 3; ++m) {
    const auto scan = clouds.next();
    ASSERT_TRUE(scan.has_value());
    EXPECT_EQ(scan->valid_count(), 64u);
    EXPECT_EQ(scan->rings(), 16);
  }
  EXPECT_FALSE(clouds.next().has_value());
  EXPECT_EQ(clouds.model().name, "VLP-16");
  EXPECT_NE(clouds.summary().find("3 messages of /velodyne_points"), std::string::npos)
      << clouds.summary();

  options.topic = "/rosout";
  try {
    RosbagScanSource log(bag, options);
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("rcl_interfaces/msg/Log"), std::string::npos) << e.what();
  }
  options.topic = "/missing";
  EXPECT_THROW(RosbagScanSource(bag, options), core::ConfigError);

  // Without metadata.yaml the folder's .db3 files are read; a .db3 file alone too.
  fs::remove(bag / "metadata.yaml");
  EXPECT_EQ(RosbagScanSource(bag).topic().name, "/velodyne_packets");
  EXPECT_EQ(RosbagScanSource(bag / "bag_0.db3").topic().name, "/velodyne_packets");
}

TEST(Rosbag2, SeveralVelodyneTopicsAndTheVelodyneSourceFactory) {
  test::TempDir dir;
  const auto ps = encode_packets(3.3);
  const fs::path bag = dir / "two";
  test::write_rosbag2(
      bag, {{"/a", "velodyne_msgs/msg/VelodyneScan"}, {"/b", "velodyne_msgs/msg/VelodyneScan"}},
      scan_messages(ps, 1));
  const auto expected = decode_direct(ps);
  ASSERT_GE(expected.size(), 2u);
  {
    RosbagScanSource source(bag);  // /a has no messages: the first topic with messages
    EXPECT_EQ(source.topic().name, "/b");
    expect_same_scans(source, expected);
  }
  RosbagSourceOptions options;
  options.topic = "/a";  // chosen, but empty: a clear error, not an empty stream
  expect_input_error(
      [&] {
        RosbagScanSource empty(bag, options);
        empty.next();
      },
      {"two", "no decodable Velodyne data packets on /a"});

  // open_source reads ROS 2 bags through the same bag source, named or guessed.
  EXPECT_EQ(parse_scan_input_format("rosbag2"), ScanInputFormat::kRosbag2);
  EXPECT_EQ(parse_scan_input_format("bag2"), ScanInputFormat::kRosbag2);
  EXPECT_EQ(parse_scan_input_format("ros2"), ScanInputFormat::kRosbag2);
  EXPECT_EQ(guess_scan_input_format(bag.string()), ScanInputFormat::kRosbag2);
  EXPECT_EQ(guess_scan_input_format((bag / "two_0.db3").string()), ScanInputFormat::kRosbag2);
  for (const auto format : {ScanInputFormat::kRosbag2, ScanInputFormat::kAuto}) {
    ScanSourceOptions o;
    o.format = format;
    auto source = open_source(bag.string(), o);
    expect_same_scans(*source, expected);
    EXPECT_EQ(source->model().name, "VLP-16");
    EXPECT_NE(source->summary().find(std::to_string(scan_messages(ps, 1).size()) +
                                     " messages of /b (velodyne_msgs/msg/VelodyneScan), " +
                                     std::to_string(ps.size()) + " data packets decoded, " +
                                     std::to_string(expected.size()) + " scans"),
              std::string::npos)
        << source->summary();
    EXPECT_EQ(source->description(), bag.string() + " (ROS bag, topic /b)");
    EXPECT_FALSE(source->pose());  // bags carry no poses
  }
  ScanSourceOptions o;
  o.format = ScanInputFormat::kRosbag2;
  o.topic = "/a";
  expect_input_error([&] { open_source(bag.string(), o)->next(); },
                     {"no decodable Velodyne data packets on /a"});
  o.topic = "/nope";
  EXPECT_THROW(open_source(bag.string(), o), core::ConfigError);
  o.topic.clear();
  expect_input_error([&] { open_source((dir / "missing.db3").string(), o); }, {"missing.db3"});
}

// Both serializations carry the same packets; DDS pads CDR payloads to 4 bytes (the real bag's
// messages end with 2 such bytes), ROS 1 messages end with the last packet.
TEST(Rosbag2, VelodyneScanMessagesParseInBothSerializations) {
  test::TestVelodyneScan scan;
  scan.seq = 9;
  scan.stamp_ns = 1'673'400'471'837'873'222;
  for (int k = 0; k < 3; ++k) {
    test::TestVelodynePacket p;
    p.stamp_ns = scan.stamp_ns + 1'327'000LL * k + k;
    for (int i = 0; i < 1206; ++i) p.data.push_back(static_cast<std::uint8_t>((i * 13 + k) % 256));
    scan.packets.push_back(std::move(p));
  }
  for (const auto encoding : {test::RosEncoding::kRos1, test::RosEncoding::kCdr}) {
    const auto serialization =
        encoding == test::RosEncoding::kCdr ? RosSerialization::kCdr : RosSerialization::kRos1;
    auto bytes = test::serialize_velodyne_scan(scan, encoding);
    const auto packets = parse_velodyne_scan(bytes, serialization, "m");
    ASSERT_EQ(packets.size(), 3u);
    for (std::size_t k = 0; k < 3; ++k) {
      EXPECT_EQ(packets[k].stamp_ns, scan.packets[k].stamp_ns);
      EXPECT_TRUE(std::equal(packets[k].data.begin(), packets[k].data.end(),
                             scan.packets[k].data.begin(), scan.packets[k].data.end()));
    }
    bytes.push_back(0);
    bytes.push_back(0);
    if (encoding == test::RosEncoding::kCdr) {
      EXPECT_EQ(parse_velodyne_scan(bytes, serialization, "m").size(), 3u);
    } else {
      expect_input_error([&] { parse_velodyne_scan(bytes, serialization, "m"); },
                         {"m: VelodyneScan", "2 bytes after the last packet"});
    }
  }
}

TEST(Rosbag2, SplitBagsAreReadFileByFile) {
  test::TempDir dir;
  const auto ps = encode_packets(3.3);
  const auto messages = scan_messages(ps, 0);
  ASSERT_GE(messages.size(), 4u);
  const std::vector<test::TestBagMessage> first(messages.begin(), messages.begin() + 2);
  const std::vector<test::TestBagMessage> second(messages.begin() + 2, messages.end());
  // The second file numbers its topics differently.
  test::write_rosbag2(dir.path() / "p1", {{"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"}},
                      first, false);
  test::write_rosbag2(
      dir.path() / "p2",
      {{"/other", "std_msgs/msg/String"}, {"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"}},
      [&] {
        auto m = second;
        for (auto& x : m) x.topic = 1;
        return m;
      }(),
      false);
  const fs::path bag = dir.path() / "split";
  fs::create_directories(bag);
  fs::rename(dir.path() / "p1" / "p1_0.db3", bag / "split_0.db3");
  fs::rename(dir.path() / "p2" / "p2_0.db3", bag / "split_1.db3");
  std::ofstream(bag / "metadata.yaml")
      << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
         "  relative_file_paths:\n    - split_0.db3\n    - split_1.db3\n"
         "  compression_format: \"\"\n";
  Rosbag2Reader reader(bag);
  ASSERT_EQ(reader.files().size(), 2u);
  ASSERT_EQ(reader.topics().size(), 2u);
  EXPECT_EQ(reader.topics()[0].messages, messages.size());
  RosbagScanSource source(bag);
  expect_same_scans(source, decode_direct(ps));
}

// metadata.yaml as `ros2 bag record --compression-format zstd --compression-mode <mode>`
// writes it (rosbag2 appends ".zstd" to each storage file it compresses whole).
void write_compressed_metadata(const fs::path& bag, const std::string& file,
                               const std::string& mode) {
  std::ofstream(bag / "metadata.yaml")
      << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
         "  relative_file_paths:\n    - "
      << file << "\n  compression_format: zstd\n  compression_mode: " << mode << "\n";
}

// A bag of the test packets compressed by file (the .db3 as one zstd stream) or by message
// (each message's data one zstd frame) gives exactly the scans of the packets; the expanded
// copy of a file-compressed bag lives in the temporary directory only while the reader does.
TEST(Rosbag2, BagsCompressedByRosbag2GiveThePlainScans) {
  test::TempDir dir;
  const auto ps = encode_packets(4.3);
  const auto messages = scan_messages(ps, 1);
  const auto expected = decode_direct(ps);
  ASSERT_GE(expected.size(), 3u);

  const fs::path file_bag = dir.path() / "file";
  test::write_rosbag2(file_bag, kTopics, messages);
  test::zstd_compress_file(file_bag / "file_0.db3", file_bag / "file_0.db3.zstd");
  fs::remove(file_bag / "file_0.db3");
  write_compressed_metadata(file_bag, "file_0.db3.zstd", "FILE");
  const fs::path tmp = dir.path() / "tmp";
  fs::create_directories(tmp);
  const std::string old_tmpdir = std::getenv("TMPDIR") != nullptr ? std::getenv("TMPDIR") : "";
  ::setenv("TMPDIR", tmp.c_str(), 1);
  {
    RosbagScanSource source(file_bag);
    EXPECT_FALSE(fs::is_empty(tmp));  // the expanded .db3
    expect_same_scans(source, expected);
    Rosbag2Reader reader(file_bag);
    EXPECT_EQ(reader.files().front(), file_bag / "file_0.db3.zstd");
  }
  EXPECT_TRUE(fs::is_empty(tmp));
  if (old_tmpdir.empty()) {
    ::unsetenv("TMPDIR");
  } else {
    ::setenv("TMPDIR", old_tmpdir.c_str(), 1);
  }

  const fs::path message_bag = dir.path() / "message";
  auto packed = messages;
  for (auto& m : packed) m.data = test::zstd_compress(m.data);
  test::write_rosbag2(message_bag, kTopics, packed);
  write_compressed_metadata(message_bag, "message_0.db3", "MESSAGE");
  RosbagScanSource source(message_bag);
  expect_same_scans(source, expected);
}

TEST(Rosbag2, CorruptCompressedBagsAreClearErrors) {
  test::TempDir dir;
  const auto ps = encode_packets(2.2);
  const auto messages = scan_messages(ps, 1);
  const fs::path bag = dir.path() / "bag";
  test::write_rosbag2(bag, kTopics, messages);
  const fs::path db = bag / "bag_0.db3";

  // Formats and modes rosbag2 does not write.
  std::ofstream(bag / "metadata.yaml")
      << "rosbag2_bagfile_information:\n  relative_file_paths: [bag_0.db3]\n"
         "  compression_format: lz4\n  compression_mode: FILE\n";
  expect_input_error([&] { Rosbag2Reader r(bag); },
                     {"metadata.yaml", "compression_format 'lz4'", "expected zstd"});
  std::ofstream(bag / "metadata.yaml")
      << "rosbag2_bagfile_information:\n  relative_file_paths: [bag_0.db3]\n"
         "  compression_format: zstd\n  compression_mode: chunk\n";
  expect_input_error([&] { Rosbag2Reader r(bag); },
                     {"metadata.yaml", "compression_mode 'chunk'", "FILE or MESSAGE"});

  // A file-compressed bag cut in half, and one that is not zstd at all.
  test::zstd_compress_file(db, bag / "bag_0.db3.zstd");
  const auto full = fs::file_size(bag / "bag_0.db3.zstd");
  fs::resize_file(bag / "bag_0.db3.zstd", full / 2);
  write_compressed_metadata(bag, "bag_0.db3.zstd", "FILE");
  expect_input_error([&] { Rosbag2Reader r(bag); },
                     {"bag_0.db3.zstd", "offset " + std::to_string(full / 2), "ends inside"});
  fs::copy_file(db, bag / "bag_0.db3.zstd", fs::copy_options::overwrite_existing);
  expect_input_error([&] { Rosbag2Reader r(bag); },
                     {"bag_0.db3.zstd", "offset", "not a valid zstd stream"});
  std::ofstream(bag / "bag_0.db3.zstd", std::ios::trunc).flush();
  expect_input_error([&] { Rosbag2Reader r(bag); }, {"bag_0.db3.zstd", "empty"});

  // A message-compressed bag whose second message is not zstd, and one whose second frame is
  // cut: the scan source stops at that message with its number.
  for (const bool cut : {false, true}) {
    auto packed = messages;
    for (auto& m : packed) m.data = test::zstd_compress(m.data);
    if (cut) {
      packed[1].data.resize(packed[1].data.size() / 2);
    } else {
      packed[1].data = messages[1].data;
    }
    const fs::path mbag = dir.path() / (cut ? "cut" : "plain");
    test::write_rosbag2(mbag, kTopics, packed);
    write_compressed_metadata(mbag, mbag.filename().string() + "_0.db3", "MESSAGE");
    Rosbag2Reader reader(mbag);
    reader.select_topic("/velodyne_packets");
    RosbagMessage m;
    ASSERT_TRUE(reader.next(m));
    EXPECT_EQ(std::vector<std::uint8_t>(m.data.begin(), m.data.end()), messages[0].data);
    expect_input_error([&] { reader.next(m); },
                       {mbag.filename().string() + "_0.db3", "message 2 of /velodyne_packets",
                        cut ? "zstd frame" : "not a zstd frame"});
  }
}

TEST(Rosbag2, CorruptBagsAreClearErrors) {
  test::TempDir dir;
  const auto ps = encode_packets(0.5);
  auto messages = scan_messages(ps, 1);
  ASSERT_EQ(messages.size(), 1u);
  const auto good = messages.front().data;
  // A truncated VelodyneScan as the second message: the error names file, topic and index.
  messages.push_back({1, messages.front().stamp_ns + 1,
                      std::vector<std::uint8_t>(good.begin(), good.begin() + 5000)});
  const fs::path cut = dir.path() / "cut";
  test::write_rosbag2(cut, kTopics, messages);
  expect_input_error(
      [&] {
        RosbagScanSource s(cut);
        while (s.next()) {
        }
      },
      {"cut_0.db3", "topic /velodyne_packets, message 2", "claims"});
  // Broken VelodyneScan messages (after a good one): a packet count beyond the message, an
  // encapsulation other than plain CDR, a header alone.
  auto many = good;
  many[28] = 0xFF;  // the packet count (after stamp, frame_id "velodyne" and padding)
  auto big_endian_xcdr2 = good;
  big_endian_xcdr2[1] = 7;
  const std::vector<std::pair<std::vector<std::uint8_t>, std::string>> broken{
      {many, "packets: claims 255 elements"},
      {big_endian_xcdr2, "unsupported CDR encapsulation 0,7"},
      {{0, 1, 0, 0}, "truncated"}};
  for (std::size_t k = 0; k < broken.size(); ++k) {
    const fs::path path = dir / ("broken" + std::to_string(k));
    test::write_rosbag2(path, {kTopics[1]}, {{0, 1, good}, {0, 2, broken[k].first}});
    expect_input_error(
        [&] {
          RosbagScanSource s(path);
          while (s.next()) {
          }
        },
        {"broken" + std::to_string(k) + "_0.db3", "topic /velodyne_packets, message 2",
         broken[k].second, "(at byte "});
  }
  // A cloud cut short.
  auto cloud = cloud_message(2, 1);
  cloud.data.resize(cloud.data.size() - 100);
  const fs::path bad_cloud = dir.path() / "bad_cloud";
  test::write_rosbag2(bad_cloud, kTopics, {cloud_message(2, 0), cloud});
  expect_input_error(
      [&] {
        RosbagScanSource s(bad_cloud);
        while (s.next()) {
        }
      },
      {"topic /velodyne_points, message 2", "PointCloud2"});
  // An unknown message type only.
  const fs::path only_log = dir.path() / "only_log";
  test::write_rosbag2(only_log, {kTopics[0]}, {{0, 1, {0, 1, 0, 0}}});
  expect_input_error(
      [&] { RosbagScanSource s(only_log); },
      {"no velodyne_msgs/VelodyneScan, pandar_msgs/PandarScan or sensor_msgs/PointCloud2",
       "/rosout"});

  // Metadata problems.
  const fs::path meta = dir.path() / "meta";
  test::write_rosbag2(meta, kTopics, messages);
  const auto write_meta = [&](const std::string& text) {
    std::ofstream(meta / "metadata.yaml") << text;
  };
  write_meta("rosbag2_bagfile_information: [unclosed\n");
  expect_input_error([&] { Rosbag2Reader r(meta); }, {"metadata.yaml", "not valid YAML"});
  write_meta("something_else: 1\n");
  expect_input_error([&] { Rosbag2Reader r(meta); },
                     {"metadata.yaml", "rosbag2_bagfile_information"});
  write_meta(
      "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths: "
      "[a.mcap]\n");
  expect_input_error([&] { Rosbag2Reader r(meta); }, {"storage 'mcap'"});
  write_meta(
      "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  compression_format: zstd\n"
      "  relative_file_paths: [meta_0.db3.zstd]\n");
  expect_input_error([&] { Rosbag2Reader r(meta); }, {"meta_0.db3.zstd", "missing"});
  write_meta("rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n");
  expect_input_error([&] { Rosbag2Reader r(meta); }, {"relative_file_paths"});
  write_meta("rosbag2_bagfile_information:\n  relative_file_paths: [gone_0.db3]\n");
  expect_input_error([&] { Rosbag2Reader r(meta); }, {"gone_0.db3", "missing"});
  // A listed path the system refuses to look up (longer than NAME_MAX) is missing too, not a
  // std::filesystem_error (found by fuzz_rosbag2).
  write_meta("rosbag2_bagfile_information:\n  relative_file_paths: [" + std::string(5000, 'a') +
             "]\n");
  expect_input_error([&] { Rosbag2Reader r(meta); }, {"aaaa", "missing"});

  // Not a database; a database without rosbag2 tables; nothing at all.
  const fs::path text = dir.path() / "text.db3";
  std::ofstream(text) << "not a database at all, just text\n";
  expect_input_error([&] { Rosbag2Reader r(text); }, {"text.db3"});
  const fs::path other_db = dir.path() / "other.db3";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(other_db.string().c_str(), &db), SQLITE_OK);
  sqlite3_exec(db, "CREATE TABLE t(x INTEGER);", nullptr, nullptr, nullptr);
  sqlite3_close(db);
  expect_input_error([&] { Rosbag2Reader r(other_db); }, {"other.db3", "not a rosbag2"});
  fs::create_directories(dir.path() / "empty");
  expect_input_error([&] { Rosbag2Reader r(dir.path() / "empty"); }, {"not a rosbag2 folder"});
  expect_input_error([&] { Rosbag2Reader r(dir.path() / "nothing_here"); }, {"nothing_here"});
  // Any other folder is read as a folder of scan files, whose reader says what it lacks.
  EXPECT_EQ(guess_scan_input_format((dir.path() / "empty").string()), ScanInputFormat::kFolder);
  expect_input_error([&] { open_source((dir.path() / "empty").string(), kDefaults); },
                     {"empty", "no sequence.yaml, no .pcd and no .bin files"});
}

}  // namespace
}  // namespace ringtrack::io
