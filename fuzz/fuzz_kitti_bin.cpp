// libFuzzer target: KITTI-style .bin bytes through decode_kitti_bin, then organized by
// core::CloudOrganizer into a VLP-16 (clockwise, firing delays undone) and into the sensor
// measured on the cloud itself (measure_cloud_sensor), and the same bytes as a folder's only scan
// through SequenceReader. Oracles: the scan's shape, and every point accounted for exactly once
// (organized, dropped or skipped) when the organizer accepts the cloud.
#include <cstdint>
#include <span>

#include "fuzz_support.hpp"
#include "ringtrack/core/cloud_organizer.hpp"
#include "ringtrack/io/kitti_bin.hpp"
#include "ringtrack/io/sequence.hpp"

using namespace ringtrack;

namespace {

void check_organized(const core::OrganizedCloud& o) {
  fuzz::check_scan(o.scan);
  const auto& s = o.stats;
  fuzz::require(s.organized == o.scan.valid_count(), "organized = valid cells");
  // A point that held a cell and lost it later is counted as collided, so the sum is exact.
  fuzz::require(
      s.organized + s.collided + s.between_rings + s.out_of_range + s.non_finite + s.at_origin ==
          s.points,
      "every point accounted for once");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> bytes(data, size);
  fuzz::expect_errors([&] {
    const core::UnorganizedCloud cloud = io::decode_kitti_bin(bytes, "fuzz.bin");
    core::CloudOrganizerOptions options;
    options.clockwise = true;
    options.undo_firing_rotation = true;
    check_organized(core::CloudOrganizer(core::SensorModel::vlp16(), options).organize(cloud));
    fuzz::expect_errors([&] {
      const core::SensorModel measured = core::measure_cloud_sensor(cloud, "fuzz.bin");
      check_organized(core::CloudOrganizer(measured).organize(cloud));
    });
  });
  fuzz::expect_errors([&] {
    const auto folder = fuzz::scratch_dir() / "bin_folder";
    std::filesystem::create_directories(folder);
    fuzz::write_scratch("bin_folder/000000.bin", bytes);
    io::SequenceReader reader(folder);
    io::SequenceScan scan;
    while (reader.next(scan)) fuzz::check_scan(scan.scan);
    (void)reader.summary();
  });
  return 0;
}
