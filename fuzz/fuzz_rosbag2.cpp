// libFuzzer target: rosbag2 (sqlite3) bags through Rosbag2Reader and RosbagScanSource (CDR
// VelodyneScan or PointCloud2 messages). An input starting with SQLite's magic is a .db3 file
// read alone; one starting with zstd's frame magic is both one compressed message and the
// .db3.zstd of a bag rosbag2 compressed per file; any other input is the metadata.yaml of a
// folder that also holds a valid .db3 (one VelodyneScan topic, written once per process), so
// that the metadata reader is fuzzed too.
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "fuzz_seeds.hpp"
#include "fuzz_support.hpp"
#include "ringtrack/io/rosbag2_metadata.hpp"
#include "ringtrack/io/rosbag2_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"

using namespace ringtrack;

namespace {

// The folder bag2/ with bag2_0.db3 and metadata.yaml from the test bag writer.
const std::filesystem::path& valid_bag_folder() {
  static const std::filesystem::path folder = [] {
    const auto f = fuzz::scratch_dir() / "bag2";
    fuzz::write_small_rosbag2(f);
    return f;
  }();
  return folder;
}

void read_all(const std::filesystem::path& path) {
  fuzz::expect_errors([&] {
    io::Rosbag2Reader reader(path);
    if (reader.topics().empty()) return;
    reader.select_topic(reader.topics().front().name);
    io::RosbagMessage message;
    while (reader.next(message)) {
    }
  });
  fuzz::expect_errors([&] {
    io::RosbagScanSource source(path);
    fuzz::drain_source(source);
  });
}

// The folder bag2z/ whose metadata.yaml lists bag2z_0.db3.zstd, compressed per file.
const std::filesystem::path& compressed_bag_folder() {
  static const std::filesystem::path folder = [] {
    const auto f = fuzz::scratch_dir() / "bag2z";
    std::filesystem::create_directories(f);
    fuzz::write_scratch("bag2z/metadata.yaml",
                        std::string_view("rosbag2_bagfile_information:\n  storage_identifier: "
                                         "sqlite3\n  relative_file_paths: [bag2z_0.db3.zstd]\n"
                                         "  compression_format: zstd\n  compression_mode: FILE\n"));
    return f;
  }();
  return folder;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static constexpr char kMagic[] = "SQLite format 3";  // 16 bytes with the NUL
  static constexpr std::uint8_t kZstdMagic[] = {0x28, 0xB5, 0x2F, 0xFD};
  if (size >= sizeof kMagic && std::memcmp(data, kMagic, sizeof kMagic) == 0) {
    read_all(fuzz::write_scratch("input.db3", std::span(data, size)));
  } else if (size >= sizeof kZstdMagic && std::memcmp(data, kZstdMagic, sizeof kZstdMagic) == 0) {
    fuzz::expect_errors([&] {
      std::vector<std::uint8_t> out;
      io::decompress_zstd_message(std::span(data, size), out, "fuzz message");
    });
    const auto& folder = compressed_bag_folder();
    fuzz::write_scratch("bag2z/bag2z_0.db3.zstd", std::span(data, size));
    read_all(folder);
  } else {
    const auto& folder = valid_bag_folder();
    fuzz::write_scratch("bag2/metadata.yaml", std::span(data, size));
    read_all(folder);
  }
  return 0;
}
