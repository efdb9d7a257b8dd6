#include "ringtrack/core/sensor_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "ringtrack/core/box3.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/core/organized_scan.hpp"

namespace ringtrack::core {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(SensorModel, Vlp16RingsAscendInTwoDegreeSteps) {
  const auto m = SensorModel::vlp16();
  m.validate();
  ASSERT_EQ(m.rings(), 16);
  for (int r = 0; r < 16; ++r) EXPECT_NEAR(m.elevation_rad[r], (-15 + 2 * r) * kDeg, 1e-12);
  EXPECT_EQ(m.laser_of_ring[0], 0);  // -15 deg is laser 0
  EXPECT_EQ(m.laser_of_ring[8], 1);  // +1 deg is laser 1
  EXPECT_EQ(m.ring_of_laser(15), 15);
  EXPECT_NEAR(m.azimuth_step_rad() / kDeg, 0.199, 0.001);  // 0.2 deg at 10 Hz
  EXPECT_EQ(m.columns(), 1808);                            // 1 / (10 Hz * 55.296 us) = 1808.4
  EXPECT_NEAR(m.vertical_offset_m[0], 0.0112, 1e-9);
}

TEST(SensorModel, OtherBuiltInsAreConsistent) {
  for (const auto& m : {SensorModel::vlp32c(), SensorModel::hdl32e()}) {
    m.validate();
    EXPECT_EQ(m.rings(), 32);
  }
  EXPECT_NEAR(SensorModel::vlp32c().elevation_rad.front(), -25 * kDeg, 1e-12);
  EXPECT_NEAR(SensorModel::hdl32e().elevation_rad.back(), 10.67 * kDeg, 1e-12);
  EXPECT_EQ(SensorModel::by_name("VLP-16").name, "VLP-16");
  EXPECT_THROW(SensorModel::by_name("os1-64"), Error);
}

TEST(SensorModel, Hdl64eHasTheManualsTwoBlocks) {
  const auto m = SensorModel::by_name("HDL-64E");
  m.validate();
  ASSERT_EQ(m.rings(), 64);
  EXPECT_EQ(m.name, "HDL-64E");
  // Lower block: -24.33 .. -8.83 in 1/2 deg steps (beam origins 0.11 m up); upper block:
  // -8.33 .. +2 in 1/3 deg steps (0.20 m up).
  for (int r = 0; r < 32; ++r) {
    EXPECT_NEAR(m.elevation_rad[r], (-24.33 + 0.5 * r) * kDeg, 1e-12) << r;
    EXPECT_NEAR(m.vertical_offset_m[r], 0.11, 1e-12);
  }
  for (int r = 32; r < 64; ++r) {
    EXPECT_NEAR(m.elevation_rad[r], (2.0 - (63 - r) / 3.0) * kDeg, 1e-12) << r;
    EXPECT_NEAR(m.vertical_offset_m[r], 0.20, 1e-12);
  }
  EXPECT_EQ(m.laser_of_ring[63], 0);  // the upper block's top laser
  EXPECT_EQ(m.laser_of_ring[0], 63);  // the lower block's bottom laser
  EXPECT_EQ(m.columns(), 2083);       // 1 / (10 Hz * 48 us)
  EXPECT_EQ(SensorModel::by_name("kitti").rings(), 64);
}

TEST(SensorModel, OneTableOfNamesAndOneErrorListingThem) {
  std::vector<std::string> with_geometry;
  for (const auto& row : built_in_sensors()) {
    if (row.make == nullptr) {
      EXPECT_STRNE(row.needs, "") << row.name;
      continue;
    }
    with_geometry.emplace_back(row.name);
    const auto m = SensorModel::by_name(row.name, 20.0);  // the canonical spelling resolves
    m.validate();
    EXPECT_EQ(m.scan_rate_hz, 20.0);
  }
  EXPECT_EQ(with_geometry, (std::vector<std::string>{"vlp16", "vlp32c", "hdl32e", "hdl64e"}));
  EXPECT_EQ(built_in_model_list(), "vlp16, vlp32c, hdl32e or hdl64e");
  const auto error_of = [](const std::string& name) {
    try {
      (void)SensorModel::by_name(name);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of("vlp64"),
            "unknown sensor model 'vlp64' (expected vlp16, vlp32c, hdl32e or hdl64e; `ringtrack "
            "sensors` lists every sensor)");
  // Known sensors without nominal geometry say what provides it.
  EXPECT_NE(error_of("PandarXT-32")
                .find("sensor 'PandarXT-32' (Hesai) has no built-in geometry: "
                      "it needs its angle-correction file (--calibration"),
            std::string::npos)
      << error_of("PandarXT-32");
  EXPECT_NE(
      error_of("os1-64").find("(Ouster) has no built-in geometry: it needs its metadata JSON"),
      std::string::npos)
      << error_of("os1-64");
}

TEST(SensorModel, GenericSortsElevations) {
  const auto m = SensorModel::generic({5.0, -5.0, 0.0}, 360);
  EXPECT_EQ(m.columns(), 360);
  EXPECT_EQ(m.laser_of_ring, (std::vector<int>{1, 2, 0}));
}

TEST(SensorModel, PointGeometry) {
  const auto m = SensorModel::generic({0.0, 30.0}, 360);
  const auto p = m.point(1, 90 * kDeg, 2.0);
  EXPECT_NEAR(p.x(), 0.0, 1e-6);
  EXPECT_NEAR(p.y(), 2.0 * std::cos(30 * kDeg), 1e-6);
  EXPECT_NEAR(p.z(), 1.0, 1e-6);
}

TEST(OrganizedScan, InvalidReturnsAreExplicit) {
  const auto m = SensorModel::vlp16();
  OrganizedScan s(m.rings(), m.columns());
  s.set_uniform_columns(m, 1000);
  EXPECT_EQ(s.valid_count(), 0u);
  s.set_range(m, 3, 10, 0.1f, 5);    // below min range
  s.set_range(m, 3, 11, 150.0f, 5);  // beyond max range
  s.set_range(m, 3, 12, 10.0f, 5);
  s.set_range(m, 3, 13, std::nanf(""), 5);
  EXPECT_EQ(s.status(s.index(3, 10)), ReturnStatus::kTooClose);
  EXPECT_EQ(s.status(s.index(3, 11)), ReturnStatus::kTooFar);
  EXPECT_EQ(s.status(s.index(3, 13)), ReturnStatus::kNoReturn);
  EXPECT_TRUE(s.valid(s.index(3, 12)));
  EXPECT_TRUE(std::isnan(s.range_m(s.index(3, 10))));
  EXPECT_EQ(s.valid_count(), 1u);
  EXPECT_EQ(s.column_stamp_ns[1] - s.column_stamp_ns[0], 55296);
  EXPECT_THROW(OrganizedScan(0, 10), Error);
}

TEST(Box3, IntersectsAndContains) {
  Box3 a;
  EXPECT_TRUE(a.empty());
  a.extend(Eigen::Vector3f(0, 0, 0));
  a.extend(Eigen::Vector3f(1, 1, 1));
  Box3 b{Eigen::Vector3f(1, 1, 1), Eigen::Vector3f(2, 2, 2)};
  Box3 c{Eigen::Vector3f(1.1f, 0, 0), Eigen::Vector3f(2, 1, 1)};
  EXPECT_TRUE(a.intersects(b));
  EXPECT_FALSE(a.intersects(c));
  EXPECT_FALSE(a.intersects(Box3{}));
  EXPECT_TRUE(a.contains(Eigen::Vector3f(0.5f, 0.5f, 0.5f)));
  EXPECT_NEAR(a.diagonal_xy(), std::sqrt(2.0f), 1e-6);
}

}  // namespace
}  // namespace ringtrack::core
