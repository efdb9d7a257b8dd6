// ROS 2 bags stored as MCAP: the real VLP-16 bag's messages (sqlite3) rewritten as MCAP by the
// reference TypeScript library (@mcap/core, tests/mcap/write_ros2_mcap.cjs) in every layout
// rosbag2 and other writers produce (zstd, lz4 or no chunk compression, no chunks, no index or
// summary; a .mcap file or a bag folder with metadata.yaml) decode to exactly the scans of the
// sqlite3 bag; a cut-off file gives the scans before the cut and a warning; a corrupt chunk is an
// error naming its offset. Skipped when the real data or node is absent.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "io_test_util.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/mcap_bag_reader.hpp"
#include "ringtrack/io/mcap_writer.hpp"
#include "ringtrack/io/rosbag2_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "support/mcap_check.hpp"
#include "support/rosbag_writers.hpp"
#include "support/run_command.hpp"
#include "support/velodyne_encoder.hpp"
#include "support/zstd_util.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

fs::path data_dir() {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA")) {
    return fs::path(env) / "vlp16_indoor_nebula";
  }
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "vlp16_indoor_nebula";
}

#define REQUIRE_BAG_AND_NODE(dir)                                                            \
  if (!fs::exists((dir) / "ros2_bag" / "metadata.yaml")) {                                   \
    GTEST_SKIP() << "real VLP-16 test data not found at " << (dir)                           \
                 << " (set RINGTRACK_TEST_DATA to the folder holding vlp16_indoor_nebula/)"; \
  }                                                                                          \
  if (const auto why = ringtrack::testing::mcap_check_unavailable(); !why.empty()) {         \
    GTEST_SKIP() << "skipped: " << why;                                                      \
  }

void put_u32(std::ofstream& out, std::uint32_t v) {
  out.write(reinterpret_cast<const char*>(&v), 4);
}

// The sqlite3 bag's messages in the dump format of write_ros2_mcap.cjs.
void dump_bag(const fs::path& bag, const fs::path& dump) {
  Rosbag2Reader reader(bag);
  std::ofstream out(dump, std::ios::binary);
  for (const auto& topic : reader.topics()) {
    Rosbag2Reader r(bag);
    r.select_topic(topic.name);
    RosbagMessage m;
    while (r.next(m)) {
      put_u32(out, static_cast<std::uint32_t>(topic.name.size()));
      out << topic.name;
      put_u32(out, static_cast<std::uint32_t>(topic.type.size()));
      out << topic.type;
      const auto stamp = static_cast<std::uint64_t>(m.stamp_ns);
      out.write(reinterpret_cast<const char*>(&stamp), 8);
      put_u32(out, static_cast<std::uint32_t>(m.data.size()));
      out.write(reinterpret_cast<const char*>(m.data.data()),
                static_cast<std::streamsize>(m.data.size()));
    }
  }
}

void write_mcap(const fs::path& dump, const fs::path& out, const std::string& options) {
  const auto r =
      ringtrack::testing::run_command(ringtrack::testing::mcap_script("write_ros2_mcap.cjs") + " " +
                                      dump.string() + " " + out.string() + " " + options);
  ASSERT_EQ(r.exit_code, 0) << r.err;
}

std::vector<core::OrganizedScan> all_scans(ScanSource& source) {
  std::vector<core::OrganizedScan> out;
  while (auto s = source.next()) out.push_back(std::move(*s));
  return out;
}

void expect_equal_scans(const core::OrganizedScan& a, const core::OrganizedScan& b,
                        const std::string& what) {
  ASSERT_EQ(a.statuses(), b.statuses()) << what;
  EXPECT_EQ(a.ranges().size(), b.ranges().size()) << what;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!a.valid(i)) continue;
    ASSERT_EQ(a.range_m(i), b.range_m(i)) << what << " cell " << i;
    ASSERT_EQ(a.intensity(i), b.intensity(i)) << what << " cell " << i;
    ASSERT_EQ(a.point(i), b.point(i)) << what << " cell " << i;
  }
  EXPECT_EQ(a.column_azimuth_rad, b.column_azimuth_rad) << what;
  EXPECT_EQ(a.column_stamp_ns, b.column_stamp_ns) << what;
  EXPECT_EQ(a.stamp_ns, b.stamp_ns) << what;
}

class McapBag : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = data_dir(); }
  std::vector<core::OrganizedScan> sqlite_scans() {
    const ScanSourceOptions options;
    auto source = open_source((dir_ / "ros2_bag").string(), options);
    return all_scans(*source);
  }
  fs::path dir_;
  const ScanSourceOptions defaults_;
};

TEST_F(McapBag, EveryLayoutGivesTheScansOfTheSqliteBag) {
  REQUIRE_BAG_AND_NODE(data_dir());
  TempDir tmp;
  dump_bag(dir_ / "ros2_bag", tmp / "bag.dump");
  const auto expected = sqlite_scans();
  ASSERT_EQ(expected.size(), 3u);
  const std::vector<std::pair<std::string, std::string>> layouts = {
      {"zstd", "--compression zstd"},          {"lz4", "--compression lz4 --chunk-size 100000"},
      {"none", "--compression none"},          {"no_index", "--compression zstd --no-index"},
      {"no_chunks", "--no-chunks --no-index"},
  };
  for (const auto& [name, options] : layouts) {
    const fs::path file = tmp / (name + ".mcap");
    write_mcap(tmp / "bag.dump", file, options);
    EXPECT_TRUE(is_mcap_bag(file));
    EXPECT_EQ(guess_scan_input_format(file.string()), ScanInputFormat::kRosbag2);
    auto source = open_source(file.string(), defaults_);
    const auto scans = all_scans(*source);
    ASSERT_EQ(scans.size(), expected.size()) << name;
    for (std::size_t k = 0; k < scans.size(); ++k) {
      expect_equal_scans(scans[k], expected[k], name + " scan " + std::to_string(k));
    }
    EXPECT_NE(source->summary().find("4 messages of /velodyne_packets"), std::string::npos)
        << source->summary();
    EXPECT_TRUE(source->warning().empty()) << source->warning();
  }

  // A bag folder whose metadata.yaml names the mcap storage, as `ros2 bag record` writes it.
  fs::create_directories(tmp / "folder");
  fs::copy_file(tmp / "zstd.mcap", tmp / "folder" / "folder_0.mcap");
  test::write_text(tmp / "folder" / "metadata.yaml",
                   "rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: mcap\n"
                   "  relative_file_paths:\n    - folder_0.mcap\n  compression_format: \"\"\n"
                   "  compression_mode: \"\"\n");
  EXPECT_TRUE(is_mcap_bag(tmp / "folder"));
  auto folder = open_source((tmp / "folder").string(), defaults_);
  EXPECT_EQ(all_scans(*folder).size(), expected.size());

  // A listed path the system refuses to look up (longer than NAME_MAX) is a missing file, not a
  // std::filesystem_error.
  test::write_text(tmp / "folder" / "metadata.yaml",
                   "rosbag2_bagfile_information:\n  storage_identifier: mcap\n"
                   "  relative_file_paths:\n    - " +
                       std::string(5000, 'a') + "\n");
  try {
    McapBagReader reader(tmp / "folder");
    ADD_FAILURE() << "a 5000-character file name was accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("which is missing"), std::string::npos) << e.what();
  }
}

TEST_F(McapBag, ACutOffBagGivesTheScansBeforeTheCutAndAWarning) {
  REQUIRE_BAG_AND_NODE(data_dir());
  TempDir tmp;
  dump_bag(dir_ / "ros2_bag", tmp / "bag.dump");
  const auto expected = sqlite_scans();
  // One message per chunk, then the file cut inside the last chunk.
  write_mcap(tmp / "bag.dump", tmp / "full.mcap", "--compression zstd --chunk-size 1000");
  const auto full = fs::file_size(tmp / "full.mcap");
  fs::copy_file(tmp / "full.mcap", tmp / "cut.mcap");
  fs::resize_file(tmp / "cut.mcap", full * 9 / 10);
  auto source = open_source((tmp / "cut.mcap").string(), defaults_);
  const auto scans = all_scans(*source);
  ASSERT_GE(scans.size(), 1u);
  ASSERT_LT(scans.size(), expected.size());
  for (std::size_t k = 0; k < scans.size(); ++k) {
    expect_equal_scans(scans[k], expected[k], "cut scan " + std::to_string(k));
  }
  EXPECT_NE(source->warning().find("cut.mcap: file cut off at offset "), std::string::npos)
      << source->warning();
  EXPECT_EQ(source->warning().find('\n'), std::string::npos);
}

// An MCAP bag folder that rosbag2 compressed itself (`--compression-format zstd`): per file (the
// .mcap as one zstd stream, "x.mcap.zstd") or per message (each payload one zstd frame) gives the
// scans of the same bag uncompressed. Written by ringtrack's MCAP writer (checked against the
// reference reader in mcap_test.cpp); needs neither node nor the real data.
TEST_F(McapBag, BagsCompressedByRosbag2GiveThePlainScans) {
  TempDir tmp;
  const ringtrack::test::VelodyneEncoder encoder(ringtrack::test::VelodyneEncoderOptions{});
  const auto packets = encoder.encode(0, 754 * 4, [](long long s, int laser) {
    return ringtrack::test::VelodyneEchoPair{
        {static_cast<std::uint16_t>(900 + (s * 13 + laser) % 4000), 7}, {}};
  });
  const auto messages =
      ringtrack::test::velodyne_scan_messages(packets, 0, ringtrack::test::RosEncoding::kCdr);
  const auto write_bag = [&](const fs::path& folder, bool compress_messages,
                             const std::string& mode) {
    fs::create_directories(folder);
    const std::string file = folder.filename().string() + "_0.mcap";
    {
      McapWriterOptions options;
      options.profile = "ros2";
      McapWriter writer(folder / file, options);
      const auto schema = writer.add_schema("velodyne_msgs/msg/VelodyneScan", "ros2msg", {});
      const auto channel = writer.add_channel(schema, "/velodyne_packets", "cdr");
      for (const auto& m : messages) {
        const auto stamp = static_cast<std::uint64_t>(m.stamp_ns);
        writer.write_message(channel, stamp, stamp,
                             compress_messages ? ringtrack::test::zstd_compress(m.data) : m.data);
      }
      writer.close();
    }
    std::string listed = file;
    if (mode == "FILE") {
      ringtrack::test::zstd_compress_file(folder / file, folder / (file + ".zstd"));
      fs::remove(folder / file);
      listed += ".zstd";
    }
    test::write_text(folder / "metadata.yaml",
                     "rosbag2_bagfile_information:\n  version: 8\n  storage_identifier: mcap\n"
                     "  relative_file_paths:\n    - " +
                         listed + "\n  compression_format: " + (mode.empty() ? "\"\"" : "zstd") +
                         "\n  compression_mode: " + (mode.empty() ? "\"\"" : mode) + "\n");
  };
  write_bag(tmp / "plain", false, "");
  write_bag(tmp / "file", false, "FILE");
  write_bag(tmp / "message", true, "MESSAGE");
  auto plain_source = open_source((tmp / "plain").string(), defaults_);
  const auto expected = all_scans(*plain_source);
  ASSERT_GE(expected.size(), 3u);
  for (const std::string name : {"file", "message"}) {
    EXPECT_TRUE(is_mcap_bag(tmp / name)) << name;
    auto source = open_source((tmp / name).string(), defaults_);
    const auto scans = all_scans(*source);
    ASSERT_EQ(scans.size(), expected.size()) << name;
    for (std::size_t k = 0; k < scans.size(); ++k) {
      expect_equal_scans(scans[k], expected[k], name + " scan " + std::to_string(k));
    }
  }

  // A payload that is not zstd in a message-compressed bag names the file and the message.
  test::write_text(tmp / "message" / "metadata.yaml",
                   "rosbag2_bagfile_information:\n  storage_identifier: mcap\n"
                   "  relative_file_paths: [../plain/plain_0.mcap]\n"
                   "  compression_format: zstd\n  compression_mode: MESSAGE\n");
  try {
    auto source = open_source((tmp / "message").string(), defaults_);
    all_scans(*source);
    ADD_FAILURE() << "a plain payload was taken for a zstd frame";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("plain_0.mcap: message 1 of /velodyne_packets: not a zstd frame"),
              std::string::npos)
        << what;
  }
}

TEST_F(McapBag, ACorruptChunkIsAnErrorNamingItsOffset) {
  REQUIRE_BAG_AND_NODE(data_dir());
  TempDir tmp;
  dump_bag(dir_ / "ros2_bag", tmp / "bag.dump");
  write_mcap(tmp / "bag.dump", tmp / "a.mcap", "--compression none --no-index");
  auto bytes = test::read_text(tmp / "a.mcap");
  bytes[bytes.size() / 2] = static_cast<char>(bytes[bytes.size() / 2] ^ 0x10);
  test::write_text(tmp / "bad.mcap", bytes);
  try {
    auto source = open_source((tmp / "bad.mcap").string(), defaults_);
    all_scans(*source);
    ADD_FAILURE() << "no error";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("bad.mcap: Chunk record at offset "), std::string::npos) << what;
    EXPECT_NE(what.find("CRC"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace ringtrack::io
