#include "ringtrack/core/cloud_organizer.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <numeric>
#include <random>

#include "ringtrack/core/error.hpp"
#include "ringtrack/sim/simple_scene.hpp"

namespace ringtrack::core {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

// The cloud in a fixed random order: the organizer must not depend on the points' order.
UnorganizedCloud shuffled(const UnorganizedCloud& cloud, unsigned seed) {
  std::vector<std::size_t> order(cloud.size());
  std::iota(order.begin(), order.end(), 0);
  std::mt19937 rng(seed);
  std::shuffle(order.begin(), order.end(), rng);
  UnorganizedCloud out;
  out.stamp_ns = cloud.stamp_ns;
  for (std::size_t i : order) {
    out.xyz.push_back(cloud.xyz[i]);
    if (!cloud.intensity.empty()) out.intensity.push_back(cloud.intensity[i]);
    if (!cloud.time_ns.empty()) out.time_ns.push_back(cloud.time_ns[i]);
  }
  return out;
}

// Cell for cell: the same cells hold returns, with the same point and intensity.
void expect_same_cells(const OrganizedScan& expected, const OrganizedScan& actual) {
  ASSERT_EQ(actual.rings(), expected.rings());
  ASSERT_EQ(actual.columns(), expected.columns());
  std::size_t differing = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    if (expected.valid(i) != actual.valid(i)) {
      if (++differing <= 5) {
        ADD_FAILURE() << "cell (ring " << expected.ring_of(i) << ", column "
                      << expected.column_of(i) << "): valid " << expected.valid(i) << " vs "
                      << actual.valid(i);
      }
      continue;
    }
    if (!expected.valid(i)) continue;
    ASSERT_EQ(actual.point(i), expected.point(i)) << "cell " << i;
    ASSERT_EQ(actual.intensity(i), expected.intensity(i)) << "cell " << i;
    ASSERT_NEAR(actual.range_m(i), expected.range_m(i), 2e-5f * expected.range_m(i) + 1e-5f);
  }
  EXPECT_EQ(differing, 0u);
}

void expect_recovered(const SensorModel& model, const sim::SimpleScene& scene) {
  auto rendered = sim::render(model, scene);
  rendered.scan.set_uniform_columns(model, 1'000'000'000);
  ASSERT_GT(rendered.scan.valid_count(), rendered.scan.size() / 3) << model.name;
  const UnorganizedCloud cloud = shuffled(flatten_scan(rendered.scan), 7);
  ASSERT_EQ(cloud.size(), rendered.scan.valid_count());
  const CloudOrganizer organizer(model);
  const OrganizedCloud organized = organizer.organize(cloud);
  SCOPED_TRACE(model.name);
  expect_same_cells(rendered.scan, organized.scan);
  EXPECT_EQ(organized.stats.points, cloud.size());
  EXPECT_EQ(organized.stats.organized, cloud.size());
  EXPECT_EQ(organized.stats.dropped(), 0u);
  EXPECT_LT(organized.stats.max_elevation_error_deg, 1e-3);
  const bool offsets = std::any_of(model.vertical_offset_m.begin(), model.vertical_offset_m.end(),
                                   [](double v) { return v != 0.0; });
  EXPECT_EQ(organized.stats.beam_offsets, offsets);  // chosen by the points
  EXPECT_EQ(organized.scan.column_stamp_ns, rendered.scan.column_stamp_ns);
  EXPECT_EQ(organized.scan.stamp_ns, rendered.scan.stamp_ns);
  for (int c = 0; c < model.columns(); ++c) {
    const auto u = static_cast<std::size_t>(c);
    EXPECT_NEAR(
        std::remainder(organized.scan.column_azimuth_rad[u] - rendered.scan.column_azimuth_rad[u],
                       2 * std::numbers::pi),
        0.0, 0.5 * model.azimuth_step_rad());
  }
}

TEST(CloudOrganizer, RecoversFlattenedShuffledScansOfEachModel) {
  // VLP-16: beam origins up to 11 mm off the axis; VLP-32C: per-laser azimuth offsets and rings
  // 0.33 deg apart; HDL-32E: 32 evenly spaced rings; a generic 64-ring sensor, without and with
  // large beam offsets; the built-in HDL-64E (two blocks of 1/3 and 1/2 deg gaps, beam origins
  // 0.11 / 0.20 m up).
  std::vector<double> e64;
  for (int r = 0; r < 64; ++r) e64.push_back(-24.8 + 0.42 * r);
  SensorModel hdl64_like = SensorModel::generic(e64, 2048, 10.0, 120.0);
  // Beam origins 0.14 m (lower block) and 0.20 m (upper block) up, as on an HDL-64E: seen from
  // the sensor origin a return at 5 m is 5 rings off its own.
  for (int r = 0; r < 64; ++r) hdl64_like.vertical_offset_m[r] = r < 32 ? 0.14 : 0.20;
  for (const auto& model : {SensorModel::vlp16(), SensorModel::vlp32c(), SensorModel::hdl32e(),
                            SensorModel::generic(e64, 2048), hdl64_like, SensorModel::hdl64e()}) {
    expect_recovered(model, sim::SimpleScene::demo());
    expect_recovered(model, sim::SimpleScene::hard_wall());  // returns down to 0.6 m
  }
}

TEST(CloudOrganizer, UndoesTheFiringDelayOfAClockwiseSensor) {
  // Points as a Velodyne decode places them: column c fires at azimuth -(c + 0.5) steps (clockwise
  // from +x), each laser later by its firing offset, i.e. further clockwise.
  const SensorModel model = SensorModel::vlp16();
  const int columns = model.columns();
  const double step = 2 * std::numbers::pi / columns;
  const double turn_per_us = 2 * std::numbers::pi * model.scan_rate_hz * 1e-6;
  OrganizedScan expected(model.rings(), columns);
  for (int c = 0; c < columns; c += 3) {
    for (int r = 0; r < model.rings(); r += 1 + c % 2) {
      const double az = -(c + 0.5) * step - turn_per_us * model.firing_offset_us[r];
      const auto range = static_cast<float>(5.0 + 0.001 * c);
      expected.set_return(r, c, range, static_cast<float>(r), model.point(r, az, range));
    }
  }
  CloudOrganizerOptions options;
  options.clockwise = true;
  options.undo_firing_rotation = true;
  options.first_column_azimuth_rad = -0.5 * step;
  const OrganizedCloud organized =
      CloudOrganizer(model, options).organize(shuffled(flatten_scan(expected), 3));
  expect_same_cells(expected, organized.scan);
  EXPECT_EQ(organized.stats.dropped(), 0u);
  EXPECT_NEAR(organized.scan.column_azimuth_rad[1], 2 * std::numbers::pi - 1.5 * step, 1e-12);
}

SensorModel three_rings() {
  return SensorModel::generic({-2.0, 0.0, 2.0}, 360);  // 1 degree columns, no offsets
}

Eigen::Vector3f at(double elevation_deg, double azimuth_deg, double range_m) {
  const double h = range_m * std::cos(elevation_deg * kDeg);
  return {static_cast<float>(h * std::cos(azimuth_deg * kDeg)),
          static_cast<float>(h * std::sin(azimuth_deg * kDeg)),
          static_cast<float>(range_m * std::sin(elevation_deg * kDeg))};
}

TEST(CloudOrganizer, TwoPointsInOneCellKeepTheNearer) {
  for (bool near_first : {true, false}) {
    UnorganizedCloud cloud;
    cloud.xyz = {at(0.1, 10.2, near_first ? 4.0 : 9.0), at(-0.1, 9.8, near_first ? 9.0 : 4.0)};
    cloud.intensity = {1.0f, 2.0f};
    const OrganizedCloud o = CloudOrganizer(three_rings()).organize(cloud);
    const std::size_t cell = o.scan.index(1, 10);
    ASSERT_TRUE(o.scan.valid(cell));
    EXPECT_NEAR(o.scan.range_m(cell), 4.0f, 1e-5f);
    EXPECT_EQ(o.scan.intensity(cell), near_first ? 1.0f : 2.0f);
    EXPECT_EQ(o.stats.organized, 1u);
    EXPECT_EQ(o.stats.collided, 1u);
    EXPECT_EQ(o.scan.valid_count(), 1u);
  }
}

TEST(CloudOrganizer, PointsBetweenRingsAreDroppedAndCounted) {
  // Rings 2 degrees apart, window 1/4 of the gap: within 0.5 deg of a ring is assigned, farther
  // is dropped (a point of another beam, a multipath echo, or the wrong model).
  UnorganizedCloud cloud;
  cloud.xyz = {at(1.0, 20, 5), at(1.6, 30, 5),  at(0.4, 40, 5), at(-2.45, 50, 5),
               at(2.6, 60, 5), at(-2.6, 70, 5), at(1.45, 80, 5)};
  const OrganizedCloud o = CloudOrganizer(three_rings()).organize(cloud);
  // Dropped: 1.0 (mid-gap), 1.45 (0.55 below ring 2), 2.6 and -2.6 (0.6 outside the fan).
  EXPECT_EQ(o.stats.between_rings, 4u);
  EXPECT_EQ(o.stats.organized, 3u);
  EXPECT_TRUE(o.scan.valid(o.scan.index(2, 30)));  // 1.6: 0.4 below ring 2
  EXPECT_TRUE(o.scan.valid(o.scan.index(1, 40)));  // 0.4: 0.4 above ring 1
  EXPECT_TRUE(o.scan.valid(o.scan.index(0, 50)));  // -2.45: 0.45 below ring 0
  EXPECT_NEAR(o.stats.max_elevation_error_deg, 0.45, 1e-4);
  EXPECT_NEAR(o.stats.median_elevation_error_deg, 0.4, 1e-4);
}

TEST(CloudOrganizer, AWiderWindowAssignsEveryPointOfTheFan) {
  CloudOrganizerOptions options;
  options.ring_window = 0.5;
  UnorganizedCloud cloud;
  cloud.xyz = {at(0.9, 20, 5), at(1.1, 30, 5), at(-2.9, 40, 5), at(3.1, 50, 5)};
  const OrganizedCloud o = CloudOrganizer(three_rings(), options).organize(cloud);
  EXPECT_TRUE(o.scan.valid(o.scan.index(1, 20)));
  EXPECT_TRUE(o.scan.valid(o.scan.index(2, 30)));
  EXPECT_TRUE(o.scan.valid(o.scan.index(0, 40)));
  EXPECT_EQ(o.stats.between_rings, 1u);  // 3.1 is 1.1 deg above the top ring
  EXPECT_NEAR(o.stats.median_elevation_error_deg, 0.9, 1e-4);
}

TEST(CloudOrganizer, SkipsAndCountsNaNPointsOriginPointsAndRangeLimits) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  UnorganizedCloud cloud;
  cloud.xyz = {Eigen::Vector3f(nan, 1, 1),
               Eigen::Vector3f(1, std::numeric_limits<float>::infinity(), 0),
               Eigen::Vector3f::Zero(),
               at(0, 5, 0.1),  // too close
               at(0, 6, 150),  // too far
               at(0, 7, 10)};
  cloud.intensity = {1, 1, 1, 1, 1, nan};
  const OrganizedCloud o = CloudOrganizer(three_rings()).organize(cloud);
  EXPECT_EQ(o.stats.points, 6u);
  EXPECT_EQ(o.stats.non_finite, 2u);
  EXPECT_EQ(o.stats.at_origin, 1u);
  EXPECT_EQ(o.stats.out_of_range, 2u);
  EXPECT_EQ(o.stats.organized, 1u);
  EXPECT_EQ(o.scan.status(o.scan.index(1, 5)), ReturnStatus::kTooClose);
  EXPECT_EQ(o.scan.status(o.scan.index(1, 6)), ReturnStatus::kTooFar);
  EXPECT_EQ(o.scan.intensity(o.scan.index(1, 7)), 0.0f);  // a NaN intensity becomes 0
  CloudOrganizeTotals totals;
  totals.add(o.stats);
  totals.add(o.stats);
  EXPECT_EQ(totals.sum.points, 12u);
  EXPECT_NE(totals.summary().find("organized 2 clouds: 2 of 12 points in cells"), std::string::npos)
      << totals.summary();
}

TEST(CloudOrganizer, RejectsMismatchedArraysAndBadOptions) {
  UnorganizedCloud cloud;
  cloud.xyz = {at(0, 5, 5)};
  cloud.intensity = {1, 2};
  EXPECT_THROW((void)CloudOrganizer(three_rings()).organize(cloud), InputError);
  CloudOrganizerOptions options;
  options.ring_window = 0.0;
  EXPECT_THROW(CloudOrganizer(three_rings(), options), ConfigError);
  options.ring_window = 0.6;
  EXPECT_THROW(CloudOrganizer(three_rings(), options), ConfigError);
}

TEST(CloudOrganizer, MeasuresTheSensorOnTheCloudWhenNoModelIsGiven) {
  // A generic sensor (no beam offsets) is measured exactly, and its scan recovered cell for cell.
  std::vector<double> elevations;
  for (int r = 0; r < 16; ++r) elevations.push_back(-15.0 + 2.0 * r);
  const SensorModel truth = SensorModel::generic(elevations, 1800, 10.0, 200.0);
  auto rendered = sim::render(truth, sim::SimpleScene::demo());
  rendered.scan.set_uniform_columns(truth, 0);
  const UnorganizedCloud cloud = shuffled(flatten_scan(rendered.scan), 11);
  const SensorModel measured = measure_cloud_sensor(cloud, "scan.bin");
  ASSERT_EQ(measured.rings(), 16);
  EXPECT_EQ(measured.columns(), 1800);
  for (int r = 0; r < 16; ++r) EXPECT_NEAR(measured.elevation_rad[r], truth.elevation_rad[r], 1e-5);
  const OrganizedCloud o = CloudOrganizer(measured).organize(cloud);
  expect_same_cells(rendered.scan, o.scan);

  // A VLP-16: its 1808 columns; rings within 0.15 deg (seen from the sensor origin, the 11 mm
  // beam offsets of the outer rings move their ground points at ~6 m by 0.11 deg).
  const SensorModel vlp16 = SensorModel::vlp16();
  auto v = sim::render(vlp16, sim::SimpleScene::demo());
  const SensorModel m16 = measure_cloud_sensor(flatten_scan(v.scan), "vlp16.bin");
  ASSERT_EQ(m16.rings(), 16);
  EXPECT_EQ(m16.columns(), vlp16.columns());
  for (int r = 0; r < 16; ++r)
    EXPECT_NEAR(m16.elevation_rad[r], vlp16.elevation_rad[r], 0.15 * kDeg);
}

TEST(CloudOrganizer, MergedCloudsOfTwoSensorsLoseTheSecond) {
  // docs/inputs.md, "Merged multi-sensor clouds": a VLP-16 scan of the demo scene merged with a
  // second VLP-16's scan whose sensor sits 0.4 m higher, turned by 90 degrees, organized with the
  // VLP-16 model at the first sensor. Its points mostly fall between the rings or land on them
  // as foreign ranges; the first sensor's points are only lost where a second one is nearer.
  const SensorModel model = SensorModel::vlp16();
  const auto first = sim::render(model, sim::SimpleScene::demo()).scan;
  const auto second = sim::render(model, sim::SimpleScene::hard_wall()).scan;
  UnorganizedCloud merged = flatten_scan(first);
  const std::size_t n1 = merged.size();
  const Eigen::Matrix3f turn =
      Eigen::AngleAxisf(static_cast<float>(std::numbers::pi / 2), Eigen::Vector3f::UnitZ())
          .toRotationMatrix();
  const UnorganizedCloud other = flatten_scan(second);
  for (std::size_t i = 0; i < other.size(); ++i) {
    merged.xyz.push_back(turn * other.xyz[i] + Eigen::Vector3f(0, 0, 0.4f));
    merged.intensity.push_back(1000.0f);  // marks the second sensor's points
    merged.time_ns.push_back(other.time_ns[i]);
  }
  const std::size_t n2 = other.size();
  const OrganizedCloud o = CloudOrganizer(model).organize(merged);
  std::size_t kept_second = 0;
  std::size_t kept_first = 0;
  for (std::size_t i = 0; i < o.scan.size(); ++i) {
    if (!o.scan.valid(i)) continue;
    (o.scan.intensity(i) == 1000.0f ? kept_second : kept_first) += 1;
  }
  const double share_first = static_cast<double>(kept_first) / static_cast<double>(n1);
  const double share_second = static_cast<double>(kept_second) / static_cast<double>(n2);
  const double between = static_cast<double>(o.stats.between_rings) / static_cast<double>(n2);
  std::printf(
      "merged: first sensor %zu points, %.1f %% kept; second %zu points, %.1f %% kept as foreign "
      "ranges, %.1f %% dropped between rings, %llu collided in all; elevation error median "
      "%.3f p95 %.3f deg\n",
      n1, 100.0 * share_first, n2, 100.0 * share_second, 100.0 * between,
      static_cast<unsigned long long>(o.stats.collided), o.stats.median_elevation_error_deg,
      o.stats.p95_elevation_error_deg);
  EXPECT_EQ(o.stats.points, n1 + n2);
  EXPECT_EQ(
      kept_first + kept_second + o.stats.collided + o.stats.between_rings + o.stats.out_of_range,
      n1 + n2);
  EXPECT_GT(o.stats.between_rings, n2 / 4);  // many of the second sensor's points do not fit
  EXPECT_GT(share_first, 0.5);
  EXPECT_LT(share_second, 0.75);
}

TEST(CloudOrganizer, MeasuringNeedsTwoRings) {
  UnorganizedCloud cloud;
  for (int c = 0; c < 360; ++c) cloud.xyz.push_back(at(1.0, c, 5.0));
  try {
    (void)measure_cloud_sensor(cloud, "one_ring.bin");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("one_ring.bin: cannot measure the ring elevations"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW((void)measure_cloud_sensor(UnorganizedCloud{}, "empty.bin"), InputError);
}

}  // namespace
}  // namespace ringtrack::core
