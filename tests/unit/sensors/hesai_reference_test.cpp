// Validation against real Hesai captures: ../shared/data/hesai_nebula/<Model>/ (see its README):
// a ROS 2 bag of pandar_msgs/PandarScan, the sensor's angle-correction CSV and one scan decoded
// by tier4/nebula (dual return, scan phase 0, full window, the range limits below). nebula writes
// Hesai points in the sensor's own frame (x = h sin(azimuth), y = h cos(azimuth), azimuth
// clockwise from +y); ringtrack's frame puts +x at azimuth 0 and turns counter-clockwise, so the
// reference is rotated into it: (x, y) -> (y, -x). Skips when the data is absent.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "ringtrack/io/rosbag_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/sensors/hesai/hesai_calibration.hpp"
#include "ringtrack/sensors/hesai/hesai_decoder.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"
#include "support/nearest_distances.hpp"

namespace ringtrack::sensors::hesai {
namespace {

namespace fs = std::filesystem;

fs::path data_dir() {
  if (const char* env = std::getenv("RINGTRACK_TEST_DATA")) return fs::path(env) / "hesai_nebula";
  return fs::path(RINGTRACK_SOURCE_DIR) / ".." / "shared" / "data" / "hesai_nebula";
}

struct Case {
  const char* model;
  double min_range_m;
  double max_range_m;
};

class HesaiReference : public ::testing::TestWithParam<Case> {};

fs::path reference_of(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("reference_scan_", 0) == 0 && e.path().extension() == ".pcd") return e.path();
  }
  return {};
}

// Every return of the bag with both echoes of dual pairs, split into revolutions at 0 deg by
// the block azimuths (a revolution ends where the azimuth falls back).
std::vector<std::vector<Eigen::Vector3d>> flat_revolutions(const fs::path& bag,
                                                           const HesaiCalibration& cal,
                                                           const Case& c, std::string& model) {
  auto reader = io::open_rosbag(bag);
  std::string topic;
  for (const auto& t : reader->topics()) {
    if (io::normalize_ros_type(t.type) == io::kPandarScanRosType) topic = t.name;
  }
  EXPECT_FALSE(topic.empty());
  reader->select_topic(topic);
  std::vector<std::vector<Eigen::Vector3d>> revolutions(1);
  double previous = -1;
  io::RosbagMessage message;
  HesaiParsedPacket parsed;
  std::vector<HesaiPoint> points;
  while (reader->next(message)) {
    for (const auto& p : io::parse_pandar_scan(message.data, reader->serialization(), "bag")) {
      const HesaiFormat* f = identify_hesai_packet(p.data);
      EXPECT_NE(f, nullptr);
      if (f == nullptr) continue;
      model = f->name;
      EXPECT_EQ(parse_hesai_packet(p.data, *f, parsed), HesaiPacketStatus::kOk);
      std::array<std::size_t, kMaxBlocks> revolution{};
      for (int b = 0; b < parsed.blocks; ++b) {
        const double az = parsed.azimuth[static_cast<std::size_t>(b)] * 0.01;
        if (previous >= 0 && az < previous - 180.0) revolutions.emplace_back();
        previous = az;
        revolution[static_cast<std::size_t>(b)] = revolutions.size() - 1;
      }
      points.clear();
      append_hesai_points(parsed, cal, points);
      for (const auto& pt : points) {
        if (pt.distance_m < c.min_range_m || pt.distance_m > c.max_range_m) continue;
        revolutions[revolution[static_cast<std::size_t>(pt.block)]].push_back(pt.xyz());
      }
    }
  }
  return revolutions;
}

TEST_P(HesaiReference, ReproducesTheReferenceScan) {
  const Case c = GetParam();
  const fs::path dir = data_dir() / c.model;
  const fs::path csv = dir / (std::string(c.model) + ".csv");
  if (!fs::exists(dir / "ros2_bag") || !fs::exists(csv) || reference_of(dir).empty()) {
    GTEST_SKIP() << "real Hesai test data not found at " << dir
                 << " (set RINGTRACK_TEST_DATA to the folder holding hesai_nebula/)";
  }
  std::vector<Eigen::Vector3d> ref = test::read_pcd_xyz(reference_of(dir).string());
  ASSERT_GT(ref.size(), 10000u);
  for (auto& p : ref) p = Eigen::Vector3d(p.y(), -p.x(), p.z());  // nebula's frame -> ringtrack's
  const HesaiCalibration cal = read_hesai_calibration(csv);

  std::string model;
  const auto revolutions = flat_revolutions(dir / "ros2_bag", cal, c, model);
  EXPECT_EQ(model, c.model);
  ASSERT_GE(revolutions.size(), 3u);
  // The reference is one of the complete revolutions (not the first or last, which are cut):
  // the one it matches best.
  double best_median = std::numeric_limits<double>::infinity();
  std::vector<double> best;
  std::size_t best_index = 0;
  for (std::size_t r = 1; r + 1 < revolutions.size(); ++r) {
    auto d = test::nearest_distances(revolutions[r], ref);
    const double median = test::quantile(d, 0.5);
    if (median < best_median) {
      best_median = median;
      best = std::move(d);
      best_index = r;
    }
  }
  const auto& ours = revolutions[best_index];
  const double p95 = test::quantile(best, 0.95);
  std::size_t exact = 0;
  for (const double d : best) exact += d < 1e-3;
  std::printf(
      "%s: revolution %zu of %zu, %zu points (reference %zu, %+.3f %%), median %.3f mm, "
      "p95 %.3f mm, %.1f %% within 1 mm\n",
      c.model, best_index, revolutions.size(), ours.size(), ref.size(),
      100.0 * (static_cast<double>(ours.size()) / static_cast<double>(ref.size()) - 1.0),
      best_median * 1e3, p95 * 1e3,
      100.0 * static_cast<double>(exact) / static_cast<double>(ref.size()));
  EXPECT_NEAR(static_cast<double>(ours.size()) / static_cast<double>(ref.size()), 1.0, 0.005);
  EXPECT_LT(best_median, 0.01);
  EXPECT_LT(p95, 0.03);
  // The other way round: our points lie on the reference's.
  const auto back = test::nearest_distances(ref, ours);
  EXPECT_LT(test::quantile(back, 0.5), 0.01);
  EXPECT_LT(test::quantile(back, 0.95), 0.03);

  // The organized scans (one return per cell) hold reference points: the default return (the
  // strongest; the QT64's last+first mode has none, so its last) and the last return, through
  // the bag source as `ringtrack run` opens it.
  for (const auto selection : {HesaiReturnSelection::kAuto, HesaiReturnSelection::kLast}) {
    io::RosbagSourceOptions options;
    options.calibration_path = csv.string();
    options.hesai.return_selection = selection;
    options.hesai.min_range_m = c.min_range_m;
    options.hesai.max_range_m = c.max_range_m;
    io::RosbagScanSource source(dir / "ros2_bag", options);
    double best_fraction = 0;
    std::size_t scans = 0;
    while (auto scan = source.next()) {
      ++scans;
      EXPECT_EQ(scan->rings(), cal.channels());
      std::vector<Eigen::Vector3d> cells;
      for (std::size_t i = 0; i < scan->size(); ++i) {
        if (scan->valid(i)) cells.push_back(scan->point(i).cast<double>());
      }
      const auto d = test::nearest_distances(ref, cells);
      std::size_t near = 0;
      for (const double v : d) near += v < 2e-3;
      best_fraction =
          std::max(best_fraction, static_cast<double>(near) / static_cast<double>(d.size()));
    }
    EXPECT_GE(scans, 2u) << source.summary();
    const HesaiDecoder* decoder = source.hesai_decoder();
    ASSERT_NE(decoder, nullptr);
    const HesaiDecoderStats stats = decoder != nullptr ? decoder->stats() : HesaiDecoderStats{};
    EXPECT_EQ(stats.skipped_packets(), 0u) << source.summary();
    EXPECT_EQ(source.model().name, c.model);
    EXPECT_GT(best_fraction, 0.98)
        << (selection == HesaiReturnSelection::kLast ? "last" : "strongest");
  }
}

INSTANTIATE_TEST_SUITE_P(
    RealCaptures, HesaiReference,
    ::testing::Values(Case{"PandarXT32", 0.05, 120.0}, Case{"PandarXT16", 0.05, 120.0},
                      Case{"PandarQT64", 0.1, 60.0}, Case{"Pandar40P", 0.3, 200.0},
                      Case{"Pandar64", 0.3, 200.0}),
    [](const auto& param_info) { return std::string(param_info.param.model); });

}  // namespace
}  // namespace ringtrack::sensors::hesai
