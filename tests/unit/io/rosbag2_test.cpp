// ROS 2 bags through the generic bag source: the real bag gives the pcap's scans cell for cell
// and reproduces the reference scan; synthetic bags (test support writer) cover both message
// types, topic choice, split bags and corrupt input.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/rosbag2_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"
#include "support/rosbag_writers.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

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

class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            ("ringtrack_ros2_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  [[nodiscard]] const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

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
    auto bag = open_scan_source((dir / "ros2_bag").string(), options);
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
  std::vector<test::TestBagMessage> out;
  for (std::size_t i = 0; i < ps.size(); i += 75) {
    test::TestVelodyneScan s;
    s.stamp_ns = ps[i].host_stamp_ns;
    for (std::size_t k = i; k < std::min(ps.size(), i + 75); ++k) {
      s.packets.push_back({ps[k].host_stamp_ns, ps[k].payload});
    }
    out.push_back({topic, s.packets.back().stamp_ns,
                   test::serialize_velodyne_scan(s, test::RosEncoding::kCdr)});
  }
  return out;
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

const std::vector<test::TestBagTopic> kTopics{
    {"/rosout", "rcl_interfaces/msg/Log"},
    {"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"},
    {"/velodyne_points", "sensor_msgs/msg/PointCloud2"}};

TEST(Rosbag2, BothMessageTypesAndTopicChoice) {
  TempDir dir;
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

TEST(Rosbag2, SplitBagsAreReadFileByFile) {
  TempDir dir;
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

TEST(Rosbag2, CorruptBagsAreClearErrors) {
  TempDir dir;
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
  expect_input_error([&] { RosbagScanSource s(only_log); },
                     {"no velodyne_msgs/VelodyneScan or sensor_msgs/PointCloud2", "/rosout"});

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
  expect_input_error([&] { Rosbag2Reader r(meta); }, {"compressed bags (zstd)"});
  write_meta("rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n");
  expect_input_error([&] { Rosbag2Reader r(meta); }, {"relative_file_paths"});
  write_meta("rosbag2_bagfile_information:\n  relative_file_paths: [gone_0.db3]\n");
  expect_input_error([&] { Rosbag2Reader r(meta); }, {"gone_0.db3", "missing"});

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
  EXPECT_THROW(guess_scan_input_format((dir.path() / "empty").string()), core::InputError);
}

}  // namespace
}  // namespace ringtrack::io
