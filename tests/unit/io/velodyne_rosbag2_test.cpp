// ROS 2 bags (sqlite3, CDR) without ROS 2: the real bag carries the pcap's packets byte for byte
// and gives the same scans; synthetic bags cover topic choice and corrupt data.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/pcap_reader.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"
#include "ringtrack/io/velodyne_rosbag2_source.hpp"
#include "support/velodyne_encoder.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

fs::path data_dir() {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA"))
    return fs::path(env) / "vlp16_indoor_nebula";
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "vlp16_indoor_nebula";
}

class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() /
            ("ringtrack_bag_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
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

// A CDR velodyne_msgs/msg/VelodyneScan, little endian.
std::vector<std::uint8_t> scan_cdr(const std::vector<test::EncodedVelodynePacket>& packets) {
  std::vector<std::uint8_t> b{0, 1, 0, 0};
  const auto align = [&b](std::size_t n) {
    while ((b.size() - 4) % n != 0) b.push_back(0);
  };
  const auto u32 = [&](std::uint32_t v) {
    align(4);
    for (int i = 0; i < 4; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  };
  const auto stamp = [&](std::int64_t ns) {
    u32(static_cast<std::uint32_t>(ns / 1'000'000'000));
    u32(static_cast<std::uint32_t>(ns % 1'000'000'000));
  };
  stamp(packets.empty() ? 0 : packets.front().host_stamp_ns);
  const std::string frame = "velodyne";
  u32(static_cast<std::uint32_t>(frame.size() + 1));
  b.insert(b.end(), frame.begin(), frame.end());
  b.push_back(0);
  u32(static_cast<std::uint32_t>(packets.size()));
  for (const auto& p : packets) {
    stamp(p.host_stamp_ns);
    b.insert(b.end(), p.payload.begin(), p.payload.end());
  }
  return b;
}

struct BagTopic {
  std::string name;
  std::string type;
};

// Writes a rosbag2 sqlite3 file with the given topics and (topic index, blob) messages.
void write_db3(const fs::path& file, const std::vector<BagTopic>& topics,
               const std::vector<std::pair<int, std::vector<std::uint8_t>>>& messages) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.string().c_str(), &db), SQLITE_OK);
  const char* schema =
      "CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,"
      "serialization_format TEXT NOT NULL,offered_qos_profiles TEXT NOT NULL);"
      "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,"
      "timestamp INTEGER NOT NULL, data BLOB NOT NULL);";
  ASSERT_EQ(sqlite3_exec(db, schema, nullptr, nullptr, nullptr), SQLITE_OK);
  for (std::size_t i = 0; i < topics.size(); ++i) {
    const std::string sql = "INSERT INTO topics VALUES(" + std::to_string(i + 1) + ",'" +
                            topics[i].name + "','" + topics[i].type + "','cdr','')";
    ASSERT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
  }
  sqlite3_stmt* insert = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id,timestamp,data) VALUES(?,?,?)",
                               -1, &insert, nullptr),
            SQLITE_OK);
  std::int64_t t = 1;
  for (const auto& [topic, blob] : messages) {
    sqlite3_bind_int(insert, 1, topic + 1);
    sqlite3_bind_int64(insert, 2, t++);
    sqlite3_bind_blob(insert, 3, blob.data(), static_cast<int>(blob.size()), SQLITE_TRANSIENT);
    ASSERT_EQ(sqlite3_step(insert), SQLITE_DONE);
    sqlite3_reset(insert);
  }
  sqlite3_finalize(insert);
  sqlite3_close(db);
}

std::vector<test::EncodedVelodynePacket> packets(double revolutions) {
  test::VelodyneEncoderOptions eo;
  eo.start_azimuth_deg = 90.0;
  const test::VelodyneEncoder enc(eo);
  const double per_rev = 360.0 / (enc.advance_deg() * enc.sequences_per_packet());
  return enc.encode(0, static_cast<long long>(revolutions * per_rev), [](long long s, int laser) {
    return test::VelodyneEchoPair{{static_cast<std::uint16_t>(700 + (s + laser) % 5000), 7}, {}};
  });
}

// Messages of ~one revolution each, like the ROS driver's.
std::vector<std::pair<int, std::vector<std::uint8_t>>> as_messages(
    const std::vector<test::EncodedVelodynePacket>& ps, int topic) {
  std::vector<std::pair<int, std::vector<std::uint8_t>>> out;
  for (std::size_t i = 0; i < ps.size(); i += 75) {
    const std::vector<test::EncodedVelodynePacket> chunk(
        ps.begin() + static_cast<std::ptrdiff_t>(i),
        ps.begin() + static_cast<std::ptrdiff_t>(std::min(ps.size(), i + 75)));
    out.emplace_back(topic, scan_cdr(chunk));
  }
  return out;
}

TEST(VelodyneRosbag2, RealBagCarriesThePcapPacketsAndGivesItsScans) {
  const fs::path dir = data_dir();
  if (!fs::exists(dir / "ros2_bag" / "metadata.yaml") ||
      !fs::exists(dir / "vlp16_dual_4scans.pcap")) {
    GTEST_SKIP() << "real VLP-16 test data not found at " << dir
                 << " (set RINGTRACK_TEST_DATA to the folder holding vlp16_indoor_nebula/)";
  }
  {
    VelodyneRosbag2Source bag(dir / "ros2_bag");
    EXPECT_EQ(bag.topic().name, "/velodyne_packets");
    PcapReader pcap(dir / "vlp16_dual_4scans.pcap");
    UdpDatagram d;
    std::size_t n = 0;
    while (pcap.next(d)) {
      const auto p = bag.next_packet();
      ASSERT_TRUE(p.has_value()) << "bag ends after " << n << " packets";
      ASSERT_TRUE(std::equal(d.payload.begin(), d.payload.end(), p->data.begin(), p->data.end()))
          << "packet " << n;
      // The pcap's stamps are the packets' receive stamps (us resolution).
      EXPECT_LE(std::abs(p->stamp_ns - d.stamp_ns), 1000) << "packet " << n;
      ++n;
    }
    EXPECT_EQ(n, 603u);
    EXPECT_FALSE(bag.next_packet().has_value());
    EXPECT_EQ(bag.stats().messages, 4u);
    EXPECT_EQ(bag.stats().packets, 603u);
  }
  // Same packets, same scans (so reference_last_scan.pcd is reproduced from the bag too: see
  // velodyne_reference_test.cpp).
  VelodyneRosbag2Source bag(dir / "ros2_bag");
  VelodynePcapSource pcap(dir / "vlp16_dual_4scans.pcap");
  std::size_t scans = 0;
  while (auto a = pcap.next()) {
    const auto b = bag.next();
    ASSERT_TRUE(b.has_value());
    EXPECT_EQ(a->statuses(), b->statuses());
    EXPECT_EQ(a->ranges().size(), b->ranges().size());
    for (std::size_t i = 0; i < a->size(); ++i) {
      if (a->valid(i)) {
        ASSERT_EQ(a->range_m(i), b->range_m(i));
      }
    }
    ++scans;
  }
  EXPECT_FALSE(bag.next().has_value());
  EXPECT_EQ(scans, 3u);
}

TEST(VelodyneRosbag2, SyntheticBagDecodesLikeThePackets) {
  TempDir dir;
  const auto ps = packets(2.8);
  auto messages = as_messages(ps, 0);
  messages.insert(messages.begin() + 1, {1, {0, 1, 0, 0, 42}});  // another topic: ignored
  write_db3(
      dir.path() / "bag_0.db3",
      {{"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"}, {"/imu", "sensor_msgs/msg/Imu"}},
      messages);
  std::ofstream(dir.path() / "metadata.yaml")
      << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
         "  relative_file_paths:\n    - bag_0.db3\n  compression_format: \"\"\n";
  VelodyneRosbag2Source bag(dir.path());
  std::size_t scans = 0;
  while (bag.next()) ++scans;
  EXPECT_EQ(scans, 2u);
  EXPECT_EQ(bag.stats().packets, ps.size());
  EXPECT_EQ(bag.stats().other_messages, 1u);
  EXPECT_EQ(bag.decoder().stats().decoded_packets, ps.size());
  // The .db3 file alone works too.
  VelodyneRosbag2Source file(dir.path() / "bag_0.db3");
  EXPECT_TRUE(file.next().has_value());
}

TEST(VelodyneRosbag2, TopicChoice) {
  TempDir dir;
  const auto ps = packets(0.3);
  write_db3(dir.path() / "two.db3",
            {{"/a", "velodyne_msgs/msg/VelodyneScan"},
             {"/b", "velodyne_msgs/msg/VelodyneScan"},
             {"/points", "sensor_msgs/msg/PointCloud2"}},
            as_messages(ps, 1));
  EXPECT_THROW(VelodyneRosbag2Source{dir.path() / "two.db3"}, core::InputError);  // ambiguous
  VelodyneRosbag2Source b(dir.path() / "two.db3", "/b");
  EXPECT_EQ(b.topic().name, "/b");
  EXPECT_TRUE(b.next_packet().has_value());
  VelodyneRosbag2Source a(dir.path() / "two.db3", "/a");
  EXPECT_FALSE(a.next_packet().has_value());  // no messages on /a
  EXPECT_THROW(VelodyneRosbag2Source(dir.path() / "two.db3", "/nope"), core::ConfigError);
  try {
    VelodyneRosbag2Source points(dir.path() / "two.db3", "/points");
    FAIL() << "expected an error";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("PointCloud2"), std::string::npos) << e.what();
  }
}

TEST(VelodyneRosbag2, CorruptBagsAreClearErrors) {
  TempDir dir;
  const auto ps = packets(0.3);
  auto good = scan_cdr(ps);
  const BagTopic topic{"/velodyne_packets", "velodyne_msgs/msg/VelodyneScan"};
  const auto expect_error = [&](const std::vector<std::uint8_t>& blob, const std::string& needle) {
    const fs::path file = dir.path() / ("bad" + std::to_string(blob.size()) + ".db3");
    fs::remove(file);
    write_db3(file, {topic}, {{0, good}, {0, blob}});
    VelodyneRosbag2Source bag(file);
    try {
      while (bag.next_packet()) {
      }
      FAIL() << "expected an error for " << needle;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("message 2"), std::string::npos) << e.what();
    }
  };
  expect_error(std::vector<std::uint8_t>(good.begin(), good.begin() + 3000), "claims 22 packets");
  auto many = good;
  many[28] = 0xFF;  // packet count (after stamp, frame_id "velodyne" and padding)
  expect_error(many, "claims");
  auto be = good;
  be[1] = 7;
  expect_error(be, "encapsulation");
  expect_error({0, 1, 0, 0}, "truncated");

  const fs::path text = dir.path() / "text.db3";
  std::ofstream(text) << "not a database at all, just text\n";
  EXPECT_THROW(VelodyneRosbag2Source{text}, core::InputError);
  EXPECT_THROW(VelodyneRosbag2Source{dir.path() / "missing.db3"}, core::InputError);
  const fs::path compressed = dir.path() / "zbag";
  fs::create_directories(compressed);
  std::ofstream(compressed / "metadata.yaml")
      << "rosbag2_bagfile_information:\n  storage_identifier: sqlite3\n  compression_format: zstd\n"
         "  relative_file_paths: [a.db3.zstd]\n";
  EXPECT_THROW(VelodyneRosbag2Source{compressed}, core::InputError);
  const fs::path empty = dir.path() / "empty";
  fs::create_directories(empty);
  EXPECT_THROW(VelodyneRosbag2Source{empty}, core::InputError);
}

}  // namespace
}  // namespace ringtrack::io
