// libFuzzer target: ROS 1 bag files (records, connections, index, chunks uncompressed, bz2 and
// lz4; indexed or interrupted) through Rosbag1Reader (every message of the first topic) and
// RosbagScanSource (scans of the first supported topic: VelodyneScan or PointCloud2). The input
// is the file.
#include <cstdint>

#include "fuzz_support.hpp"
#include "ringtrack/io/rosbag1_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"

using namespace ringtrack;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto path = fuzz::write_scratch("input.bag", std::span(data, size));
  fuzz::expect_errors([&] {
    io::Rosbag1Reader reader(path);
    if (reader.topics().empty()) return;
    reader.select_topic(reader.topics().front().name);
    io::RosbagMessage message;
    std::uint64_t bytes = 0;
    while (reader.next(message)) bytes += message.data.size();
    (void)bytes;
  });
  fuzz::expect_errors([&] {
    io::RosbagScanSource source(path);
    fuzz::drain_source(source);
  });
  return 0;
}
