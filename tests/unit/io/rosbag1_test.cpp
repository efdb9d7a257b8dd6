// ROS 1 bags: fixtures written by ROS's own rosbag (fixtures/make_ros1_bags.py) are the oracle
// for the reader; the test support writer makes Velodyne and point cloud bags for the scan
// source; corrupt and truncated bags are errors, never crashes.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/rosbag1_reader.hpp"
#include "ringtrack/io/rosbag2_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "support/peak_memory.hpp"
#include "support/rosbag_writers.hpp"
#include "support/temp_dir.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

const fs::path kFixtures = fs::path(RINGTRACK_SOURCE_DIR) / "tests" / "unit" / "io" / "fixtures";
constexpr std::int64_t kBaseNs = 1'700'000'000'000'000'000;

std::vector<std::uint8_t> read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_file(const fs::path& p, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// The messages make_ros1_bags.py writes (same formulas).
std::vector<std::uint8_t> fixture_scan(int m) {
  test::TestVelodyneScan s;
  s.seq = static_cast<std::uint32_t>(m);
  s.stamp_ns = kBaseNs + m * 1'000'000'000LL + 1000LL * m;
  for (int k = 0; k < 2; ++k) {
    test::TestVelodynePacket p;
    p.stamp_ns = kBaseNs + m * 1'000'000'000LL + 500000 + k;
    for (int i = 0; i < 1206; ++i)
      p.data.push_back(static_cast<std::uint8_t>((m * 31 + k * 7 + i) % 251));
    s.packets.push_back(std::move(p));
  }
  return test::serialize_velodyne_scan(s, test::RosEncoding::kRos1);
}

std::vector<std::uint8_t> fixture_cloud(int m) {
  std::vector<test::TestPoint> pts;
  for (int i = 0; i < 5; ++i) {
    pts.push_back({1.0f + static_cast<float>(i + m), 0.5f * static_cast<float>(i),
                   -0.25f * static_cast<float>(m), 10.0f * static_cast<float>(i),
                   static_cast<std::uint16_t>(i * 3), static_cast<float>(1e-4 * i)});
  }
  auto c = test::make_xyzirt_cloud(pts, 1, 5, kBaseNs + m * 1'000'000'000LL + 250000);
  c.seq = static_cast<std::uint32_t>(m);
  c.is_dense = true;
  return test::serialize_pointcloud2(c, test::RosEncoding::kRos1);
}

std::int64_t fixture_time(int i) {
  return kBaseNs + i * 1'000'000'000LL + 100'000'000;
}

TEST(Rosbag1, ReadsBagsWrittenByRosbag) {
  for (const std::string compression : {"none", "bz2", "lz4"}) {
    SCOPED_TRACE(compression);
    const fs::path path = kFixtures / ("ros1_" + compression + ".bag");
    ASSERT_TRUE(fs::exists(path)) << path;
    {
      Rosbag1Reader bag(path);
      EXPECT_TRUE(bag.indexed());
      ASSERT_EQ(bag.topics().size(), 3u);
      EXPECT_EQ(bag.topics()[0].name, "/chatter");
      EXPECT_EQ(bag.topics()[0].type, "std_msgs/String");
      EXPECT_EQ(bag.topics()[0].messages, 4u);
      EXPECT_EQ(bag.topics()[1].name, "/velodyne_packets");
      EXPECT_EQ(bag.topics()[1].type, "velodyne_msgs/VelodyneScan");
      EXPECT_EQ(bag.topics()[1].messages, 4u);
      EXPECT_EQ(bag.topics()[2].name, "/points");
      EXPECT_EQ(bag.topics()[2].type, "sensor_msgs/PointCloud2");
      EXPECT_EQ(bag.topics()[2].messages, 2u);
      bag.select_topic("/velodyne_packets");
      RosbagMessage m;
      for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(bag.next(m)) << i;
        EXPECT_EQ(m.index, static_cast<std::uint64_t>(i + 1));
        EXPECT_EQ(m.stamp_ns, fixture_time(i) + 1000);
        const auto expected = fixture_scan(i);
        ASSERT_TRUE(std::equal(m.data.begin(), m.data.end(), expected.begin(), expected.end()))
            << "message " << i;
        const auto packets = parse_velodyne_scan(m.data, RosSerialization::kRos1, "t");
        ASSERT_EQ(packets.size(), 2u);
        EXPECT_EQ(packets[1].stamp_ns, kBaseNs + i * 1'000'000'000LL + 500001);
        EXPECT_EQ(packets[1].data[0], (i * 31 + 7) % 251);
      }
      EXPECT_FALSE(bag.next(m));
      EXPECT_EQ(bag.other_messages(), 6u);
      EXPECT_GE(bag.stats().chunks, 3u);  // chunk_threshold 3000 bytes
    }
    {
      Rosbag1Reader bag(path);
      bag.select_topic("/points");
      RosbagMessage m;
      for (int i = 0; i < 2; ++i) {
        ASSERT_TRUE(bag.next(m));
        EXPECT_EQ(m.stamp_ns, fixture_time(i) + 2000);
        const auto expected = fixture_cloud(i);
        ASSERT_TRUE(std::equal(m.data.begin(), m.data.end(), expected.begin(), expected.end()));
        const PointCloud2 c = parse_pointcloud2(m.data, RosSerialization::kRos1, "t");
        EXPECT_EQ(c.width, 5u);
        EXPECT_EQ(c.value(*c.find("ring"), 0, 4), 12.0);
      }
      EXPECT_FALSE(bag.next(m));
    }
    {
      Rosbag1Reader bag(path);
      bag.select_topic("/chatter");
      RosbagMessage m;
      for (int i = 0; i < 4; ++i) {
        ASSERT_TRUE(bag.next(m));
        EXPECT_EQ(m.stamp_ns, fixture_time(i));
        const auto expected =
            test::serialize_string("hello " + std::to_string(i), test::RosEncoding::kRos1);
        ASSERT_TRUE(std::equal(m.data.begin(), m.data.end(), expected.begin(), expected.end()));
      }
    }
  }
}

TEST(Rosbag1, TheSupportWriterMatchesRosbag) {
  // The writer the other tests use lays out bags like rosbag: same messages, same reads.
  test::TempDir dir;
  const std::vector<test::TestBagTopic> topics{{"/chatter", "std_msgs/String"},
                                               {"/velodyne_packets", "velodyne_msgs/VelodyneScan"},
                                               {"/points", "sensor_msgs/PointCloud2"}};
  std::vector<test::TestBagMessage> messages;
  for (int i = 0; i < 4; ++i) {
    messages.push_back(
        {0, fixture_time(i),
         test::serialize_string("hello " + std::to_string(i), test::RosEncoding::kRos1)});
    messages.push_back({1, fixture_time(i) + 1000, fixture_scan(i)});
    if (i < 2) messages.push_back({2, fixture_time(i) + 2000, fixture_cloud(i)});
  }
  for (const std::string compression : {"none", "bz2", "lz4"}) {
    const fs::path ours = dir.path() / ("ours_" + compression + ".bag");
    test::write_rosbag1(ours, topics, messages, {compression, 3000, true});
    for (const std::string topic : {"/chatter", "/velodyne_packets", "/points"}) {
      Rosbag1Reader a(ours);
      Rosbag1Reader b(kFixtures / ("ros1_" + compression + ".bag"));
      a.select_topic(topic);
      b.select_topic(topic);
      RosbagMessage ma;
      RosbagMessage mb;
      std::size_t n = 0;
      while (b.next(mb)) {
        ASSERT_TRUE(a.next(ma));
        EXPECT_EQ(ma.stamp_ns, mb.stamp_ns);
        ASSERT_TRUE(std::equal(ma.data.begin(), ma.data.end(), mb.data.begin(), mb.data.end()));
        ++n;
      }
      EXPECT_FALSE(a.next(ma));
      EXPECT_GT(n, 0u);
      EXPECT_EQ(a.topics().size(), b.topics().size());
    }
  }
}

std::vector<test::EncodedVelodynePacket> encode_packets(double revolutions) {
  test::VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 120.0;
  const test::VelodyneEncoder enc(eo);
  const double per_rev = 360.0 / (enc.advance_deg() * enc.sequences_per_packet());
  return enc.encode(0, static_cast<long long>(revolutions * per_rev), [](long long s, int laser) {
    const auto d = static_cast<std::uint16_t>(800 + (s * 7 + laser * 131) % 6000);
    return test::VelodyneEchoPair{{d, static_cast<std::uint8_t>(laser * 5)}, {}};
  });
}

std::vector<core::OrganizedScan> decode_direct(const std::vector<test::EncodedVelodynePacket>& ps) {
  VelodyneDecoder decoder;
  for (const auto& p : ps) decoder.add_packet(p.payload, p.host_stamp_ns);
  decoder.finish();
  std::vector<core::OrganizedScan> scans;
  while (auto s = decoder.pop_scan()) scans.push_back(std::move(*s));
  return scans;
}

void expect_same_scans(ScanSource& source, const std::vector<core::OrganizedScan>& expected) {
  std::size_t n = 0;
  while (auto s = source.next()) {
    ASSERT_LT(n, expected.size());
    const auto& e = expected[n++];
    ASSERT_EQ(s->statuses(), e.statuses());
    for (std::size_t i = 0; i < e.size(); ++i) {
      if (e.valid(i)) {
        ASSERT_EQ(s->range_m(i), e.range_m(i));
      }
    }
    EXPECT_EQ(s->column_azimuth_rad, e.column_azimuth_rad);
    EXPECT_EQ(s->column_stamp_ns, e.column_stamp_ns);
  }
  EXPECT_EQ(n, expected.size());
}

TEST(Rosbag1, VelodyneScanBagsDecodeLikeThePackets) {
  test::TempDir dir;
  const auto ps = encode_packets(3.4);
  const auto expected = decode_direct(ps);
  ASSERT_EQ(expected.size(), 2u);
  auto messages = test::velodyne_scan_messages(ps, 1, test::RosEncoding::kRos1);
  // Another topic in between: ignored and counted.
  messages.insert(messages.begin() + 1, {0, messages.front().stamp_ns,
                                         test::serialize_string("x", test::RosEncoding::kRos1)});
  const std::vector<test::TestBagTopic> topics{{"/diagnostics", "std_msgs/String"},
                                               {"/velodyne_packets", "velodyne_msgs/VelodyneScan"}};
  for (const std::string compression : {"none", "lz4", "bz2"}) {
    for (const bool indexed : {true, false}) {
      SCOPED_TRACE(compression + (indexed ? " indexed" : " unindexed"));
      const fs::path path = dir.path() / ("v_" + compression + (indexed ? "_i" : "_u") + ".bag");
      test::write_rosbag1(path, topics, messages, {compression, 200'000, indexed});
      RosbagScanSource source(path);  // the first supported topic
      EXPECT_EQ(source.topic().name, "/velodyne_packets");
      EXPECT_TRUE(source.velodyne_packets());
      expect_same_scans(source, expected);
      EXPECT_EQ(source.stats().packets, ps.size());
      EXPECT_EQ(source.reader().other_messages(), 1u);
      EXPECT_NE(source.summary().find("1 messages of other topics ignored"), std::string::npos)
          << source.summary();
      EXPECT_EQ(source.model().name, "VLP-16");
    }
  }
  // open_source guesses the format from the contents, whatever the name.
  const fs::path renamed = dir.path() / "recording.data";
  fs::copy_file(dir.path() / "v_lz4_i.bag", renamed);
  EXPECT_EQ(guess_scan_input_format(renamed.string()), ScanInputFormat::kRosbag1);
  const ScanSourceOptions defaults;
  auto source = open_source(renamed.string(), defaults);
  expect_same_scans(*source, expected);
}

TEST(Rosbag1, PointCloudTopicsGiveOneScanPerCloud) {
  test::TempDir dir;
  const auto model = core::SensorModel::vlp16();
  std::vector<test::TestBagMessage> messages;
  for (int m = 0; m < 3; ++m) {
    std::vector<test::TestPoint> pts;
    for (int ring = 0; ring < 16; ++ring) {
      const Eigen::Vector3f p = model.point(ring, 0.5 + 0.1 * m, 4.0 + ring * 0.25);
      pts.push_back({p.x(), p.y(), p.z(), 1.0f, static_cast<std::uint16_t>(ring), 0.0f});
    }
    const auto cloud = test::make_xyzirt_cloud(pts, 1, 16, kBaseNs + m * 100'000'000LL);
    messages.push_back({1, kBaseNs + m * 100'000'000LL,
                        test::serialize_pointcloud2(cloud, test::RosEncoding::kRos1)});
  }
  const fs::path path = dir.path() / "points.bag";
  test::write_rosbag1(path,
                      {{"/velodyne_packets", "velodyne_msgs/VelodyneScan"},
                       {"/velodyne_points", "sensor_msgs/PointCloud2"}},
                      messages, {"lz4", 4096, true});
  // The packets topic has no messages: the first supported topic with messages is chosen.
  RosbagScanSource source(path);
  EXPECT_EQ(source.topic().name, "/velodyne_points");
  std::size_t n = 0;
  while (auto scan = source.next()) {
    EXPECT_EQ(scan->valid_count(), 16u);
    for (int ring = 0; ring < 16; ++ring) {
      bool found = false;
      for (int c = 0; c < scan->columns() && !found; ++c) {
        const auto i = scan->index(ring, c);
        found = scan->valid(i) &&
                std::abs(scan->range_m(i) - (4.0f + static_cast<float>(ring) * 0.25f)) < 1e-4f;
      }
      EXPECT_TRUE(found) << "ring " << ring;
    }
    ++n;
  }
  EXPECT_EQ(n, 3u);
  EXPECT_NE(source.summary().find("3 scans"), std::string::npos) << source.summary();
  // Choosing the empty packets topic: a clear error at the end.
  RosbagSourceOptions options;
  options.topic = "/velodyne_packets";
  RosbagScanSource empty(path, options);
  EXPECT_THROW(empty.next(), core::InputError);
}

TEST(Rosbag1, TopicChoiceAndUnsupportedTypes) {
  test::TempDir dir;
  const fs::path path = dir.path() / "t.bag";
  test::write_rosbag1(path, {{"/imu", "sensor_msgs/Imu"}, {"/chatter", "std_msgs/String"}},
                      {{0, kBaseNs, {1, 2, 3}},
                       {1, kBaseNs, test::serialize_string("a", test::RosEncoding::kRos1)}});
  try {
    RosbagScanSource source(path);
    FAIL();
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(
        what.find(
            "no velodyne_msgs/VelodyneScan, pandar_msgs/PandarScan or sensor_msgs/PointCloud2"),
        std::string::npos)
        << what;
    EXPECT_NE(what.find("/imu (sensor_msgs/Imu)"), std::string::npos) << what;
  }
  RosbagSourceOptions options;
  options.topic = "/imu";
  try {
    RosbagScanSource source(path, options);
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("topic /imu has type sensor_msgs/Imu"), std::string::npos)
        << e.what();
  }
  options.topic = "/nope";
  EXPECT_THROW(RosbagScanSource(path, options), core::ConfigError);
}

// Feeds a (corrupt) bag through the reader: true when it read to the end, false on an
// InputError. With `strict`, every message read must be the expected one (a truncated bag can
// lose messages but never change one; flipped bytes inside uncompressed data can).
bool read_all(const fs::path& path, const std::string& topic,
              const std::vector<std::vector<std::uint8_t>>& expected, bool strict = true) {
  try {
    Rosbag1Reader bag(path);
    bag.select_topic(topic);
    RosbagMessage m;
    while (bag.next(m)) {
      if (m.index > expected.size()) return false;
      const auto& e = expected[m.index - 1];
      if (strict && !std::equal(m.data.begin(), m.data.end(), e.begin(), e.end())) {
        ADD_FAILURE() << path << ": message " << m.index << " differs without an error";
      }
    }
    return true;
  } catch (const core::InputError&) {
    return false;
  } catch (const core::ConfigError&) {  // the topic vanished with the index
    return false;
  }
}

TEST(Rosbag1, TruncatedBagsAreErrors) {
  test::TempDir dir;
  std::vector<std::vector<std::uint8_t>> expected;
  for (int i = 0; i < 4; ++i) expected.push_back(fixture_scan(i));
  for (const std::string compression : {"none", "lz4", "bz2"}) {
    const auto bytes = read_file(kFixtures / ("ros1_" + compression + ".bag"));
    const fs::path cut = dir.path() / "cut.bag";
    std::size_t errors = 0;
    std::size_t tried = 0;
    for (std::size_t n = 0; n < bytes.size(); n += 37) {
      write_file(cut,
                 std::vector<std::uint8_t>(bytes.begin(), bytes.begin() + static_cast<long>(n)));
      errors += read_all(cut, "/velodyne_packets", expected) ? 0 : 1;
      ++tried;
    }
    // An indexed bag cut anywhere misses its index: always an error.
    EXPECT_EQ(errors, tried) << compression;
  }
  // The message names the file and offset.
  const auto bytes = read_file(kFixtures / "ros1_lz4.bag");
  const fs::path cut = dir.path() / "named.bag";
  write_file(cut, std::vector<std::uint8_t>(bytes.begin(), bytes.end() - 10));
  try {
    Rosbag1Reader bag(cut);
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("named.bag"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("offset"), std::string::npos) << e.what();
  }
}

TEST(Rosbag1, InterruptedRecordingsKeepTheirCompleteMessages) {
  // No index (the recorder died): the bag is scanned; a last chunk cut off by the end of the
  // file ends the data, and everything before it is read.
  test::TempDir dir;
  const auto ps = encode_packets(4.5);
  const auto messages = test::velodyne_scan_messages(ps, 0, test::RosEncoding::kRos1);
  ASSERT_GE(messages.size(), 4u);
  const fs::path full = dir.path() / "full.bag";
  test::write_rosbag1(full, {{"/velodyne_packets", "velodyne_msgs/VelodyneScan"}}, messages,
                      {"lz4", 1, false});  // one message per chunk
  const auto bytes = read_file(full);
  const fs::path cut = dir.path() / "cut.bag";
  write_file(cut, std::vector<std::uint8_t>(bytes.begin(), bytes.end() - 5000));
  Rosbag1Reader bag(cut);
  EXPECT_FALSE(bag.indexed());
  EXPECT_GT(bag.stats().truncated_at, 0u);
  bag.select_topic("/velodyne_packets");
  RosbagMessage m;
  std::size_t n = 0;
  while (bag.next(m)) {
    ASSERT_TRUE(
        std::equal(m.data.begin(), m.data.end(), messages[n].data.begin(), messages[n].data.end()));
    ++n;
  }
  EXPECT_EQ(n, messages.size() - 1);
}

TEST(Rosbag1, CorruptBytesNeverCrash) {
  test::TempDir dir;
  std::vector<std::vector<std::uint8_t>> expected;
  for (int i = 0; i < 4; ++i) expected.push_back(fixture_scan(i));
  const auto bytes = read_file(kFixtures / "ros1_lz4.bag");
  const fs::path bad = dir.path() / "bad.bag";
  std::mt19937 rng(42);
  std::size_t errors = 0;
  for (int trial = 0; trial < 400; ++trial) {
    auto b = bytes;
    for (int k = 0; k < 3; ++k) {
      b[std::uniform_int_distribution<std::size_t>(0, b.size() - 1)(rng)] =
          static_cast<std::uint8_t>(rng());
    }
    write_file(bad, b);
    errors += read_all(bad, "/velodyne_packets", expected, false) ? 0 : 1;
  }
  EXPECT_GT(errors, 0u);
}

TEST(Rosbag1, MalformedHeadersAreClearErrors) {
  test::TempDir dir;
  const auto expect_error = [&](const std::vector<std::uint8_t>& b, const std::string& needle) {
    const fs::path p = dir.path() / "m.bag";
    write_file(p, b);
    try {
      Rosbag1Reader bag(p);
      bag.select_topic(bag.topics().at(0).name);
      RosbagMessage m;
      while (bag.next(m)) {
      }
      FAIL() << "expected an error about " << needle;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  const std::string v12 = "#ROSBAG V1.2\n";
  expect_error({v12.begin(), v12.end()}, "format 1.2 is not supported");
  const std::string text = "hello, this is not a bag at all\n";
  expect_error({text.begin(), text.end()}, "not a ROS 1 bag");
  expect_error({}, "not a ROS 1 bag");

  // Unknown compression, and an lz4 chunk whose data is damaged.
  const std::vector<test::TestBagTopic> topics{{"/s", "std_msgs/String"}};
  const std::vector<test::TestBagMessage> msgs{
      {0, kBaseNs, test::serialize_string(std::string(3000, 'a'), test::RosEncoding::kRos1)}};
  const fs::path p = dir.path() / "ok.bag";
  test::write_rosbag1(p, topics, msgs, {"lz4", 4096, true});
  auto b = read_file(p);
  const std::string lz4 = "compression=lz4";
  auto at = std::search(b.begin(), b.end(), lz4.begin(), lz4.end());
  ASSERT_NE(at, b.end());
  auto zz = b;
  std::copy_n(std::string("compression=zz4").begin(), lz4.size(), zz.begin() + (at - b.begin()));
  expect_error(zz, "compression 'zz4' is not supported");
  // Damage the lz4 frame magic (the chunk's data starts 4 bytes after its header).
  auto damaged = b;
  const std::string size_field = "size=";
  auto s = std::search(at, b.end(), size_field.begin(), size_field.end());
  const auto data_at = static_cast<std::size_t>(s - b.begin()) + size_field.size() + 4 + 4;
  damaged[data_at] ^= 0xFF;
  expect_error(damaged, "corrupt lz4 data");
  // A bz2 chunk with damaged data.
  test::write_rosbag1(p, topics, msgs, {"bz2", 4096, true});
  b = read_file(p);
  const std::string bz = "BZh";
  at = std::search(b.begin(), b.end(), bz.begin(), bz.end());
  ASSERT_NE(at, b.end());
  b[static_cast<std::size_t>(at - b.begin()) + 12] ^= 0x55;
  expect_error(b, "corrupt bz2 data");
  EXPECT_THROW(Rosbag1Reader{dir.path() / "missing.bag"}, core::InputError);
}

TEST(Rosbag1, ChunkClaimingHugeSizeCostsOnlyWhatItsDataHolds) {
  // Issue 16: a chunk whose size field claims 512 MiB (the largest accepted) made the reader
  // allocate all of it for a file of kilobytes. Output now grows with what the stream produces.
  test::TempDir dir;
  const std::vector<test::TestBagTopic> topics{{"/s", "std_msgs/String"}};
  const std::vector<test::TestBagMessage> msgs{
      {0, kBaseNs, test::serialize_string(std::string(3000, 'a'), test::RosEncoding::kRos1)}};
  for (const std::string compression : {"lz4", "bz2"}) {
    const fs::path p = dir.path() / (compression + ".bag");
    test::write_rosbag1(p, topics, msgs, {compression, 4096, true});
    auto b = read_file(p);
    const std::string field = "compression=" + compression;
    const auto chunk = std::search(b.begin(), b.end(), field.begin(), field.end());
    const std::string size_field = "size=";
    const auto s = std::search(chunk, b.end(), size_field.begin(), size_field.end());
    ASSERT_NE(s, b.end());
    const std::uint32_t claimed = 512u << 20;
    std::memcpy(&*(s + 5), &claimed, 4);
    write_file(p, b);
    const std::size_t peak_before = ringtrack::test::peak_rss_bytes();
    try {
      Rosbag1Reader reader(p);
      reader.select_topic("/s");
      RosbagMessage m;
      while (reader.next(m)) {
      }
      ADD_FAILURE() << compression << ": expected an error";
    } catch (const core::InputError& e) {
      // The frame decodes completely: 3,000 characters and their record headers, not 512 MiB.
      EXPECT_NE(std::string(e.what()).find(": corrupt " + compression + " data ("),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find(" of 536870912 bytes)"), std::string::npos) << e.what();
    }
    EXPECT_LT(ringtrack::test::peak_rss_bytes() - peak_before, 64u << 20) << compression;
  }
}

TEST(Rosbag1, SameScansAsTheRos2BagOfTheSamePackets) {
  test::TempDir dir;
  const auto ps = encode_packets(3.2);
  test::write_rosbag1(dir.path() / "a.bag", {{"/velodyne_packets", "velodyne_msgs/VelodyneScan"}},
                      test::velodyne_scan_messages(ps, 0, test::RosEncoding::kRos1),
                      {"none", 100'000, true});
  test::write_rosbag2(dir.path() / "b", {{"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"}},
                      test::velodyne_scan_messages(ps, 0, test::RosEncoding::kCdr));
  const ScanSourceOptions defaults;
  auto a = open_source((dir.path() / "a.bag").string(), defaults);
  std::vector<core::OrganizedScan> from_ros2;
  auto b = open_source((dir.path() / "b").string(), defaults);
  while (auto s = b->next()) from_ros2.push_back(std::move(*s));
  ASSERT_EQ(from_ros2.size(), 2u);
  expect_same_scans(*a, from_ros2);
}

}  // namespace
}  // namespace ringtrack::io
