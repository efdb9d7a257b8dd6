// sensor_msgs/PointCloud2: parsing both serializations (against the test support serializer)
// and organizing clouds into scans (against clouds built from a known grid).
#include "ringtrack/io/pointcloud2.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numbers>
#include <random>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/velodyne_packet.hpp"
#include "support/rosbag_writers.hpp"

namespace ringtrack::io {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

RosSerialization to_io(test::RosEncoding e) {
  return e == test::RosEncoding::kCdr ? RosSerialization::kCdr : RosSerialization::kRos1;
}

// The range of cell (ring, column) in the grid clouds below; 0 = no point.
float grid_range(int ring, int column) {
  if ((ring * 7 + column * 3) % 11 == 0) return 0.0f;
  return 1.0f + static_cast<float>((ring * 131 + column * 17) % 900) * 0.01f;
}

// A VLP-16 cell's point as a driver computes it: the firing sequence of column c starts in the
// middle of its column (Velodyne azimuth cut + (c + 0.5) step), the laser fires later, and the
// point carries the azimuth of that moment.
struct GridPoint {
  int ring, column;
  test::TestPoint point;
  double firing_rad;  // ringtrack azimuth of the firing sequence
};

std::vector<GridPoint> grid_points(const core::SensorModel& m, double cut_deg) {
  std::vector<GridPoint> out;
  const int columns = m.columns();
  const double step = 360.0 / columns;
  for (int c = 0; c < columns; ++c) {
    const double firing = velodyne_to_ringtrack_azimuth_rad(cut_deg + (c + 0.5) * step);
    for (int r = 0; r < m.rings(); ++r) {
      const float range = grid_range(r, c);
      if (range == 0.0f) continue;
      const auto u = static_cast<std::size_t>(r);
      const double az =
          firing + m.azimuth_offset_rad[u] - kTwoPi * m.scan_rate_hz * m.firing_offset_us[u] * 1e-6;
      const Eigen::Vector3f p = m.point(r, az, range);
      test::TestPoint tp{p.x(),
                         p.y(),
                         p.z(),
                         static_cast<float>(r * 10 + c % 7),
                         static_cast<std::uint16_t>(r),
                         static_cast<float>(c) * 1e-5f};
      out.push_back({r, c, tp, firing});
    }
  }
  return out;
}

PointCloud2 parse(const test::TestPointCloud2& c, test::RosEncoding e,
                  std::vector<std::uint8_t>& storage) {
  storage = test::serialize_pointcloud2(c, e);
  return parse_pointcloud2(storage, to_io(e), "test");
}

TEST(PointCloud2, ParsesBothSerializations) {
  std::vector<test::TestPoint> pts;
  for (int i = 0; i < 6; ++i) {
    const auto f = static_cast<float>(i);
    pts.push_back({f, -2.0f, 0.5f, 7.0f, static_cast<std::uint16_t>(i), 1e-3f * f});
  }
  auto cloud = test::make_xyzirt_cloud(pts, 2, 3, 1'700'000'000'123'456'789);
  cloud.frame_id = "lidar_top";
  for (const auto e : {test::RosEncoding::kRos1, test::RosEncoding::kCdr}) {
    std::vector<std::uint8_t> bytes;
    const PointCloud2 c = parse(cloud, e, bytes);
    EXPECT_EQ(c.stamp_ns, 1'700'000'000'123'456'789);
    EXPECT_EQ(c.frame_id, "lidar_top");
    EXPECT_EQ(c.height, 2u);
    EXPECT_EQ(c.width, 3u);
    ASSERT_EQ(c.fields.size(), 6u);
    EXPECT_EQ(c.fields[4].name, "ring");
    EXPECT_EQ(c.fields[4].offset, 16u);
    EXPECT_EQ(c.fields[4].datatype, 4);
    EXPECT_EQ(c.fields[5].name, "time");
    EXPECT_EQ(c.point_step, 24u);
    EXPECT_EQ(c.row_step, 72u);
    EXPECT_TRUE(std::equal(c.data.begin(), c.data.end(), cloud.data.begin(), cloud.data.end()));
    EXPECT_FALSE(c.is_dense);
    EXPECT_EQ(c.value(*c.find("x"), 1, 2), 5.0);
    EXPECT_EQ(c.value(*c.find("ring"), 1, 0), 3.0);
    EXPECT_FLOAT_EQ(static_cast<float>(c.value(*c.find("time"), 0, 1)), 1e-3f);
  }
}

TEST(PointCloud2, MalformedMessagesAreClearErrors) {
  auto cloud = test::make_xyzirt_cloud({{1, 2, 3, 4, 5, 0}, {1, 2, 3, 4, 5, 0}}, 1, 2, 0);
  for (const auto e : {test::RosEncoding::kRos1, test::RosEncoding::kCdr}) {
    const auto good = test::serialize_pointcloud2(cloud, e);
    // Every truncation is an error naming where, never a crash.
    for (std::size_t n = 0; n < good.size(); ++n) {
      const std::vector<std::uint8_t> cut(good.begin(), good.begin() + static_cast<long>(n));
      try {
        parse_pointcloud2(cut, to_io(e), "bag.db3 (topic /points, message 3)");
        FAIL() << "no error at length " << n;
      } catch (const core::InputError& err) {
        EXPECT_NE(std::string(err.what()).find("message 3"), std::string::npos) << err.what();
      }
    }
    const auto expect_error = [&](test::TestPointCloud2 c, const std::string& needle) {
      const auto bytes = test::serialize_pointcloud2(c, e);
      try {
        parse_pointcloud2(bytes, to_io(e), "where");
        FAIL() << "expected an error about " << needle;
      } catch (const core::InputError& err) {
        EXPECT_NE(std::string(err.what()).find(needle), std::string::npos) << err.what();
      }
    };
    auto c = cloud;
    c.fields[2].offset = 22;  // a float at 22..26 in a 24-byte record
    expect_error(c, "does not fit");
    c = cloud;
    c.fields[1].datatype = 9;
    expect_error(c, "unknown datatype 9");
    c = cloud;
    c.data.resize(30);
    expect_error(c, "data holds 30 bytes");
    c = cloud;
    c.row_step = 24;
    expect_error(c, "row_step");
    c = cloud;
    c.is_bigendian = true;
    expect_error(c, "big endian");
  }
}

TEST(PointCloud2, UnorganizedCloudWithRingsFillsTheGrid) {
  const double cut = 33.0;
  const auto model = core::SensorModel::vlp16();
  auto points = grid_points(model, cut);
  std::mt19937 rng(7);
  std::shuffle(points.begin(), points.end(), rng);  // order must not matter
  std::vector<test::TestPoint> tps;
  for (const auto& g : points) tps.push_back(g.point);
  const std::int64_t stamp = 5'000'000'000;
  const auto cloud = test::make_xyzirt_cloud(tps, 1, static_cast<std::uint32_t>(tps.size()), stamp);
  for (const auto e : {test::RosEncoding::kRos1, test::RosEncoding::kCdr}) {
    std::vector<std::uint8_t> bytes;
    const PointCloud2 c = parse(cloud, e, bytes);
    PointCloud2Options options;
    options.cut_azimuth_deg = cut;
    PointCloud2Organizer organizer(options);
    const core::OrganizedScan scan = organizer.organize(c, "test");
    EXPECT_EQ(organizer.model().name, "VLP-16");
    ASSERT_EQ(scan.rings(), 16);
    ASSERT_EQ(scan.columns(), model.columns());
    EXPECT_EQ(scan.valid_count(), points.size());
    EXPECT_EQ(organizer.stats().dropped_points, 0u);
    for (const auto& g : points) {
      const std::size_t i = scan.index(g.ring, g.column);
      ASSERT_TRUE(scan.valid(i)) << "ring " << g.ring << " column " << g.column;
      EXPECT_NEAR(scan.range_m(i), grid_range(g.ring, g.column), 1e-4f);
      EXPECT_EQ(scan.point(i), Eigen::Vector3f(g.point.x, g.point.y, g.point.z));
      EXPECT_EQ(scan.intensity(i), g.point.intensity);
      EXPECT_NEAR(
          std::remainder(scan.column_azimuth_rad[static_cast<std::size_t>(g.column)] - g.firing_rad,
                         kTwoPi),
          0.0, 1e-5);
      // Column stamps: the header stamp plus the earliest point time of the column.
      EXPECT_NEAR(
          static_cast<double>(scan.column_stamp_ns[static_cast<std::size_t>(g.column)] - stamp),
          g.column * 1e4, 2.0);
    }
    EXPECT_EQ(scan.stamp_ns, scan.column_stamp_ns[0]);
  }
}

TEST(PointCloud2, OrganizedCloudsWithoutRingFieldUseRowsBottomOrTopFirst) {
  const auto model = core::SensorModel::vlp16();
  const auto points = grid_points(model, 0.0);
  const int columns = model.columns();
  for (const bool top_first : {false, true}) {
    // One row per ring, one column per firing; missing returns are NaN points.
    const float nan = std::numeric_limits<float>::quiet_NaN();
    std::vector<test::TestPoint> grid(static_cast<std::size_t>(16 * columns),
                                      test::TestPoint{nan, nan, nan, 0, 0, 0});
    for (const auto& g : points) {
      const int row = top_first ? 15 - g.ring : g.ring;
      grid[static_cast<std::size_t>(row * columns + g.column)] = g.point;
    }
    const auto cloud = test::make_xyzirt_cloud(grid, 16, static_cast<std::uint32_t>(columns), 0,
                                               /*with_ring=*/false);
    std::vector<std::uint8_t> bytes;
    const PointCloud2 c = parse(cloud, test::RosEncoding::kCdr, bytes);
    PointCloud2Organizer organizer;
    const auto scan = organizer.organize(c, "test");
    EXPECT_EQ(scan.valid_count(), points.size());
    EXPECT_EQ(organizer.stats().empty_points, grid.size() - points.size());
    for (const auto& g : points) {
      ASSERT_TRUE(scan.valid(scan.index(g.ring, g.column))) << "top first " << top_first;
      EXPECT_NEAR(scan.range_m(scan.index(g.ring, g.column)), grid_range(g.ring, g.column), 1e-4f);
    }
  }
}

TEST(PointCloud2, CollisionsRangesAndBadRings) {
  const auto model = core::SensorModel::vlp16();
  const auto at = [&](int ring, double velodyne_deg, float range) {
    const double az = velodyne_to_ringtrack_azimuth_rad(velodyne_deg) -
                      kTwoPi * 10.0 * model.firing_offset_us[static_cast<std::size_t>(ring)] * 1e-6;
    const Eigen::Vector3f p = model.point(ring, az, range);
    return test::TestPoint{p.x(), p.y(), p.z(), 1, static_cast<std::uint16_t>(ring), 0};
  };
  const double step = 360.0 / model.columns();
  const std::vector<test::TestPoint> pts{
      at(3, 10.5 * step, 5.0f),   // column 10
      at(3, 10.6 * step, 4.0f),   // same cell, nearer: kept
      at(3, 10.7 * step, 6.0f),   // same cell, farther: dropped
      at(4, 20.5 * step, 0.1f),   // too close
      at(5, 30.5 * step, 150.f),  // too far
      {1, 1, 1, 1, 16, 0},        // ring 16 of a VLP-16
  };
  const auto cloud = test::make_xyzirt_cloud(pts, 1, static_cast<std::uint32_t>(pts.size()), 0);
  std::vector<std::uint8_t> bytes;
  const PointCloud2 c = parse(cloud, test::RosEncoding::kRos1, bytes);
  PointCloud2Options options;
  options.model = "vlp16";
  PointCloud2Organizer organizer(options);
  const auto scan = organizer.organize(c, "test");
  EXPECT_EQ(scan.valid_count(), 1u);
  EXPECT_NEAR(scan.range_m(scan.index(3, 10)), 4.0f, 1e-5f);
  EXPECT_EQ(organizer.stats().dropped_points, 2u);
  EXPECT_EQ(scan.status(scan.index(4, 20)), core::ReturnStatus::kTooClose);
  EXPECT_EQ(scan.status(scan.index(5, 30)), core::ReturnStatus::kTooFar);
  EXPECT_EQ(organizer.stats().bad_ring_points, 1u);
}

// organize_points (points already in memory) gives the scan the organizer makes of the same
// points as a PointCloud2 with a ring field: the whole shuffled grid plus a collision, a point
// too close, one too far and a ring the model lacks.
TEST(PointCloud2, OrganizePointsGivesTheScanOfTheSameCloud) {
  const double cut = 12.0;
  const auto model = core::SensorModel::vlp16();
  auto grid = grid_points(model, cut);
  std::mt19937 rng(3);
  std::shuffle(grid.begin(), grid.end(), rng);
  std::vector<test::TestPoint> tps;
  for (const auto& g : grid) tps.push_back(g.point);
  const auto near_copy = [](test::TestPoint p, float scale) {
    p.x *= scale;
    p.y *= scale;
    p.z *= scale;
    return p;
  };
  tps.push_back(near_copy(tps[5], 0.9f));   // the same cell, nearer: replaces it
  tps.push_back(near_copy(tps[6], 0.01f));  // too close
  tps.push_back(near_copy(tps[7], 40.0f));  // too far
  tps.push_back({1, 2, 0.5f, 3, 16, 0});    // ring 16 of a VLP-16
  const std::int64_t stamp = 7'000'000'000;
  const auto cloud = test::make_xyzirt_cloud(tps, 1, static_cast<std::uint32_t>(tps.size()), stamp);
  std::vector<std::uint8_t> bytes;
  const PointCloud2 c = parse(cloud, test::RosEncoding::kCdr, bytes);
  PointCloud2Options options;
  options.cut_azimuth_deg = cut;
  options.model = "vlp16";
  PointCloud2Organizer organizer(options);
  const core::OrganizedScan expected = organizer.organize(c, "test");

  std::vector<Eigen::Vector3f> xyz;
  std::vector<std::uint16_t> ring;
  std::vector<float> intensity;
  std::vector<std::int64_t> time_ns;
  for (const auto& p : tps) {
    xyz.emplace_back(p.x, p.y, p.z);
    ring.push_back(p.ring);
    intensity.push_back(p.intensity);
    time_ns.push_back(stamp + std::llround(static_cast<double>(p.time_s) * 1e9));
  }
  PointCloud2Stats stats;
  const core::OrganizedScan scan =
      organize_points({xyz, ring, intensity, time_ns, stamp}, model, options, &stats);
  ASSERT_EQ(scan.statuses(), expected.statuses());
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!expected.valid(i)) continue;  // invalid cells hold NaN
    ASSERT_EQ(scan.range_m(i), expected.range_m(i)) << "cell " << i;
    ASSERT_EQ(scan.intensity(i), expected.intensity(i)) << "cell " << i;
    ASSERT_EQ(scan.point(i), expected.point(i)) << "cell " << i;
  }
  EXPECT_EQ(scan.column_azimuth_rad, expected.column_azimuth_rad);
  ASSERT_EQ(scan.column_stamp_ns.size(), expected.column_stamp_ns.size());
  for (std::size_t k = 0; k < scan.column_stamp_ns.size(); ++k) {
    // The cloud's float seconds pass through double conversions: within a nanosecond.
    EXPECT_NEAR(static_cast<double>(scan.column_stamp_ns[k] - expected.column_stamp_ns[k]), 0.0,
                1.0);
  }
  EXPECT_EQ(stats.points, organizer.stats().points);
  EXPECT_EQ(stats.dropped_points, organizer.stats().dropped_points);
  EXPECT_EQ(stats.bad_ring_points, 1u);
  // The three copies share cells with grid points: the nearer replaces its point, the ones out
  // of range leave the cell's point in place; all three count as dropped, as for a cloud.
  EXPECT_EQ(stats.dropped_points, 3u);
  const std::size_t near_cell = scan.index(grid[5].ring, grid[5].column);
  EXPECT_NEAR(scan.range_m(near_cell), 0.9f * grid_range(grid[5].ring, grid[5].column), 1e-4f);
  const std::size_t kept_cell = scan.index(grid[6].ring, grid[6].column);
  EXPECT_NEAR(scan.range_m(kept_cell), grid_range(grid[6].ring, grid[6].column), 1e-4f);

  // Without times: nominal column stamps from the cloud's stamp.
  const core::OrganizedScan untimed = organize_points({xyz, ring, {}, {}, stamp}, model, options);
  EXPECT_EQ(untimed.statuses(), expected.statuses());
  EXPECT_EQ(untimed.column_stamp_ns[0], stamp);
  EXPECT_EQ(untimed.intensity(untimed.index(grid[0].ring, grid[0].column)), 0.0f);

  // Sizes that differ name what and how many.
  try {
    (void)organize_points({xyz, std::span(ring).first(3), {}, {}, stamp}, model, options);
    ADD_FAILURE() << "3 rings for all points were accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("organize_points: 3 rings for"), std::string::npos)
        << e.what();
  }
}

TEST(PointCloud2, CloudsThatCannotBeOrganizedAreClearErrors) {
  std::vector<std::uint8_t> bytes;
  // No ring field and a single row.
  const auto flat = test::make_xyzirt_cloud({{1, 0, 0, 0, 0, 0}}, 1, 1, 0, /*with_ring=*/false);
  PointCloud2Organizer organizer;
  try {
    organizer.organize(parse(flat, test::RosEncoding::kCdr, bytes), "bag (topic /p, message 1)");
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("'ring' field"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("message 1"), std::string::npos) << e.what();
  }
  // 32 rings: which sensor? The user must say.
  const auto tall = test::make_xyzirt_cloud({{1, 0, 0, 0, 31, 0}}, 1, 1, 0);
  EXPECT_THROW(organizer.organize(parse(tall, test::RosEncoding::kCdr, bytes), "t"),
               core::InputError);
  PointCloud2Options options;
  options.model = "vlp32c";
  PointCloud2Organizer named(options);
  EXPECT_EQ(named.organize(parse(tall, test::RosEncoding::kCdr, bytes), "t").rings(), 32);
  // Rows that are not rings.
  const auto rows = test::make_xyzirt_cloud(std::vector<test::TestPoint>(8, {1, 0, 0, 0, 0, 0}), 8,
                                            1, 0, /*with_ring=*/false);
  PointCloud2Options vlp16;
  vlp16.model = "vlp16";
  PointCloud2Organizer o16(vlp16);
  EXPECT_THROW(o16.organize(parse(rows, test::RosEncoding::kCdr, bytes), "t"), core::InputError);
  // No coordinates.
  auto no_xyz = flat;
  no_xyz.fields[0].name = "u";
  EXPECT_THROW(organizer.organize(parse(no_xyz, test::RosEncoding::kCdr, bytes), "t"),
               core::InputError);
  EXPECT_THROW(PointCloud2Organizer({"nosuch", 10.0, 0.0, "ring"}), core::ConfigError);
}

TEST(PointCloud2, PointTimesThatAreNoTimeAreClearErrors) {
  // Found by fuzz_ros_messages: a time field of -1e12 s (-1e21 ns) became INT64_MIN, and the
  // column stamps after it overflowed. A float32 "time" of +-1e12 s is no stamp: an error naming
  // the point; the largest plausible absolute stamps (float64 seconds since the epoch) still read.
  std::vector<std::uint8_t> bytes;
  for (const float seconds : {-1e12F, 1e12F}) {
    const auto cloud =
        test::make_xyzirt_cloud({{1, 0, 0, 0, 0, 0}, {0, 1, 0, 0, 3, seconds}}, 1, 2, 0);
    PointCloud2Organizer organizer;
    try {
      organizer.organize(parse(cloud, test::RosEncoding::kCdr, bytes), "bag (message 4)");
      ADD_FAILURE() << "expected an error for " << seconds;
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("bag (message 4): point (row 0, column 1) has time "
                                           "field 'time' = "),
                std::string::npos)
          << e.what();
    }
  }
  // Oracle: 2026 as float64 seconds since the epoch is an absolute stamp (scan stamp = column 0's,
  // within one revolution of the point's column), not an offset from the header stamp of 5 ns.
  auto absolute = test::make_xyzirt_cloud({{1, 0, 0, 0, 0, 0}}, 1, 1, 5);
  absolute.fields[5].datatype = 8;  // float64 "time" at offset 18 overlaps nothing after it
  absolute.point_step = 26;
  absolute.row_step = 26;
  absolute.data.resize(26);
  const double stamp_s = 1'780'000'000.25;
  std::memcpy(absolute.data.data() + 18, &stamp_s, 8);
  PointCloud2Organizer organizer;
  const auto scan = organizer.organize(parse(absolute, test::RosEncoding::kCdr, bytes), "t");
  EXPECT_NEAR(static_cast<double>(scan.stamp_ns), 1.78000000025e18, 1e8);
}

TEST(PointCloud2, EmptyCloudOfBillionsOfRowsIsAnEmptyScan) {
  // Found by fuzz_ros_messages (11 s for one message): width 0 with a height of 4 billion rows
  // holds no point, so organizing it walks no rows; the scan has no returns.
  std::vector<std::uint8_t> bytes;
  auto cloud = test::make_xyzirt_cloud({}, 1, 0, 1'000);
  cloud.height = 4'000'000'000u;
  PointCloud2Organizer organizer;
  const auto scan = organizer.organize(parse(cloud, test::RosEncoding::kRos1, bytes), "t");
  EXPECT_EQ(scan.rings(), 16);
  EXPECT_EQ(scan.valid_count(), 0u);
  EXPECT_EQ(organizer.stats().points, 0u);
  EXPECT_EQ(organizer.stats().clouds, 1u);
}

}  // namespace
}  // namespace ringtrack::io
