// Validation against a real VLP-32C capture: ../shared/data/vlp32c_nebula (see its README).
// reference_scan_1713492677464078412.pcd is one scan decoded by tier4/nebula with a single
// strongest return, scan phase 180 deg, ranges 0.4..50 m and the azimuth window 270..90 deg.
// The sensor itself only sends that window (a field-of-view setting: packets jump from 90 to
// 270 deg), so every scan covers the front half. Skips when the data is absent.
//
// Firing times: the manual fires the 32 lasers in 16 pairs, 2.304 us apart (55.296 us per
// sequence with the recharge), and so does ringtrack; the reference interpolates azimuths as if
// laser n fired at n x 2.304 us (up to 71 us, past the next sequence), so its azimuths run ahead
// of ours by up to 0.13 deg for the last lasers. That, not the ranges, is the residual below.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <vector>

#include "ringtrack/io/rosbag_source.hpp"
#include "support/nearest_distances.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

fs::path data_dir() {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA")) return fs::path(env) / "vlp32c_nebula";
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "vlp32c_nebula";
}

TEST(Vlp32cReference, ReproducesTheReferenceScan) {
  const fs::path dir = data_dir();
  const fs::path reference = dir / "reference_scan_1713492677464078412.pcd";
  if (!fs::exists(dir / "ros2_bag") || !fs::exists(reference)) {
    GTEST_SKIP() << "real VLP-32C test data not found at " << dir
                 << " (set RINGTRACK_TEST_DATA to the folder holding vlp32c_nebula/)";
  }
  const auto ref = test::read_pcd_xyz(reference.string());
  ASSERT_EQ(ref.size(), 26216u);

  RosbagSourceOptions options;
  options.decoder.return_selection = VelodyneReturnSelection::kStrongest;
  options.decoder.cut_azimuth_deg = 180.0;
  options.decoder.keep_partial_scans = true;  // the sensor sends the front half only
  RosbagScanSource source(dir / "ros2_bag", options);
  std::vector<core::OrganizedScan> scans;
  while (auto s = source.next()) scans.push_back(std::move(*s));
  ASSERT_GE(scans.size(), 1u) << source.summary();
  EXPECT_EQ(source.decoder().model().name, "VLP-32C");
  EXPECT_EQ(source.decoder().stats().skipped_packets(), 0u);

  // The reference is the bag's first revolution (its name is the first message's stamp).
  const core::OrganizedScan& scan = scans.front();
  std::vector<Eigen::Vector3d> ours;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    const double range = scan.range_m(i);
    if (range < 0.4 || range > 50.0) continue;
    // No window beyond the sensor's own: it sends blocks from 270.1 to 90.95 deg only, and the
    // reference keeps all of them (its points reach 94.3 and 266.0 deg with the laser offsets).
    // A window on each point's azimuth would drop 359 points here (-1.4 %), one on the block
    // azimuths the blocks past 90 deg (-0.5 %).
    ours.push_back(scan.point(i).cast<double>());
  }
  const auto to_ours = test::nearest_distances(ours, ref);
  const double median = test::quantile(to_ours, 0.5);
  const double p95 = test::quantile(to_ours, 0.95);
  const double count_ratio = static_cast<double>(ours.size()) / static_cast<double>(ref.size());
  RecordProperty("points", static_cast<int>(ours.size()));
  RecordProperty("median_mm", std::to_string(median * 1e3));
  RecordProperty("p95_mm", std::to_string(p95 * 1e3));
  std::printf("VLP-32C: %zu points (reference %zu), median %.2f mm, p95 %.2f mm\n", ours.size(),
              ref.size(), median * 1e3, p95 * 1e3);
  EXPECT_NEAR(count_ratio, 1.0, 0.005);
  EXPECT_LT(median, 0.01);
  EXPECT_LT(p95, 0.03);
  // And the other way round: our points lie on the reference's.
  const auto to_ref = test::nearest_distances(ref, ours);
  EXPECT_LT(test::quantile(to_ref, 0.5), 0.01);
  EXPECT_LT(test::quantile(to_ref, 0.95), 0.03);
}

}  // namespace
}  // namespace ringtrack::io
