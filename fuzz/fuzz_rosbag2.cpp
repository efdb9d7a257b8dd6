// libFuzzer target: rosbag2 (sqlite3) bags through Rosbag2Reader and RosbagScanSource (CDR
// VelodyneScan or PointCloud2 messages). An input starting with SQLite's magic is a .db3 file
// read alone; any other input is the metadata.yaml of a folder that also holds a valid .db3 (one
// VelodyneScan topic, written once per process), so that the metadata reader is fuzzed too.
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>

#include "fuzz_seeds.hpp"
#include "fuzz_support.hpp"
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

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static constexpr char kMagic[] = "SQLite format 3";  // 16 bytes with the NUL
  if (size >= sizeof kMagic && std::memcmp(data, kMagic, sizeof kMagic) == 0) {
    read_all(fuzz::write_scratch("input.db3", std::span(data, size)));
  } else {
    const auto& folder = valid_bag_folder();
    fuzz::write_scratch("bag2/metadata.yaml", std::span(data, size));
    read_all(folder);
  }
  return 0;
}
