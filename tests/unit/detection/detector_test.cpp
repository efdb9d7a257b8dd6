// Detection on hand-drawn grids: each test paints segment points where an object would be and
// checks the clusters and the object model's verdicts.

#include "ringtrack/detection/detector.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "ringtrack/core/background_range.hpp"
#include "ringtrack/core/error.hpp"
#include "support/naive_detection.hpp"

namespace ringtrack::detection {
namespace {

using core::DetectionConfig;
using core::JoinRule;
using Indices = std::vector<std::uint32_t>;

constexpr double kDeg = std::numbers::pi / 180.0;

// A 16-ring grid like a VLP-16 without beam offsets (-15..15 deg in 2 deg steps) and one column
// per degree, so column c looks along azimuth c degrees. Cells start invalid and background.
struct Grid {
  core::SensorModel model;
  core::OrganizedScan scan;
  std::vector<std::uint8_t> labels;

  explicit Grid(core::SensorModel m) : model(std::move(m)), scan(model.rings(), model.columns()) {
    scan.set_uniform_columns(model, 0);
    labels.assign(scan.size(), 0);
  }
  Grid() : Grid(core::SensorModel::generic(elevations(), 360)) {}

  static std::vector<double> elevations() {
    std::vector<double> e;
    for (int k = 0; k < 16; ++k) e.push_back(-15.0 + 2.0 * k);
    return e;
  }

  // Segment points on a vertical surface at horizontal distance h_m: rings r0..r1, `count`
  // columns from c0 (wrapping past the last column). Returns the painted cells, ascending.
  Indices paint(int r0, int r1, int c0, int count, double h_m) {
    Indices cells;
    for (int k = 0; k < count; ++k) {
      const int c = (c0 + k) % scan.columns();
      for (int r = r0; r <= r1; ++r) {
        const double range = h_m / std::cos(model.elevation_rad[static_cast<std::size_t>(r)]);
        scan.set_range(model, r, c, static_cast<float>(range), 1.0f);
        labels[scan.index(r, c)] = kSegmentLabel;
        cells.push_back(static_cast<std::uint32_t>(scan.index(r, c)));
      }
    }
    std::sort(cells.begin(), cells.end());
    return cells;
  }

  // A person-like upright cylinder front (0.5 m wide, from ground_z_m up by height_m) at
  // horizontal distance h_m and azimuth az_deg, painted on every ring and column that sees it.
  Indices paint_person(double h_m, double az_deg, double ground_z_m, double height_m = 1.75) {
    Indices cells;
    const double half_width_rad = std::atan2(0.25, h_m);
    for (int c = 0; c < scan.columns(); ++c) {
      double d_az = scan.column_azimuth_rad[static_cast<std::size_t>(c)] - az_deg * kDeg;
      d_az = std::remainder(d_az, 2.0 * std::numbers::pi);
      if (std::abs(d_az) > half_width_rad) continue;
      for (int r = 0; r < scan.rings(); ++r) {
        const double el = model.elevation_rad[static_cast<std::size_t>(r)];
        const double z = h_m * std::tan(el) + model.vertical_offset_m[static_cast<std::size_t>(r)];
        if (z < ground_z_m || z > ground_z_m + height_m) continue;
        scan.set_range(model, r, c, static_cast<float>(h_m / std::cos(el)), 1.0f);
        labels[scan.index(r, c)] = kSegmentLabel;
        cells.push_back(static_cast<std::uint32_t>(scan.index(r, c)));
      }
    }
    std::sort(cells.begin(), cells.end());
    return cells;
  }

  const std::vector<core::Detection>& detect(Detector& d, const core::Pose& pose = {},
                                             const std::vector<Eigen::Vector3f>& predictions = {}) {
    return d.detect(scan, labels, pose, predictions);
  }
};

// The fast detector must agree with the reference on every hand-drawn grid too.
void expect_matches_reference(const Grid& g, const DetectionConfig& config,
                              const core::Pose& pose = {},
                              const std::vector<Eigen::Vector3f>& predictions = {}) {
  Detector detector(config);
  const auto& fast = detector.detect(g.scan, g.labels, pose, predictions);
  const auto slow = testing::naive_detect(g.scan, g.labels, config, pose, predictions);
  ASSERT_EQ(fast.size(), slow.size());
  for (std::size_t k = 0; k < fast.size(); ++k) {
    EXPECT_EQ(fast[k].indices, slow[k].indices);
    EXPECT_EQ(fast[k].relaxed, slow[k].relaxed);
  }
}

TEST(Detector, PersonIsOneDetectionWithItsCells) {
  Grid g;
  const auto person = g.paint(2, 10, 20, 6, 5.0);  // 1.4 m tall, 0.44 m wide at 5 m
  Detector detector{DetectionConfig{}};
  const auto& d = g.detect(detector);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_EQ(d[0].indices, person);
  EXPECT_FALSE(d[0].relaxed);
  EXPECT_EQ(detector.stats().segment_points, person.size());
  EXPECT_EQ(detector.stats().detections, 1u);
}

TEST(Detector, TwoPeopleOneBehindTheOtherStayApart) {
  // Paper Fig. 3: the front person hides part of the one behind; on the grid their points are
  // direct neighbours (columns 15 and 16), only the distance tells them apart.
  for (const auto rule : {JoinRule::kRangeDifference, JoinRule::kEuclidean}) {
    Grid g;
    const auto front = g.paint(2, 10, 10, 6, 5.0);  // columns 10..15
    const auto back = g.paint(2, 11, 16, 6, 6.5);   // columns 16..21, 1.5 m behind
    DetectionConfig config;
    config.join_rule = rule;
    Detector detector(config);
    const auto& d = g.detect(detector);
    ASSERT_EQ(d.size(), 2u) << "rule " << static_cast<int>(rule);
    EXPECT_EQ(d[0].indices, front);
    EXPECT_EQ(d[1].indices, back);
    expect_matches_reference(g, config);

    // Control: without the distance test the two merge into one (too wide) cluster (the split
    // step, which would cut it at the range step, is off here).
    config.join_distance_m = 100.0;
    config.split_min_width_m = 0.0;
    Detector merged(config);
    EXPECT_TRUE(g.detect(merged).empty());
    EXPECT_EQ(merged.stats().clusters, 1u);
    EXPECT_EQ(merged.stats().too_wide, 1u);
  }
}

TEST(Detector, PersonSplitByTheSeamIsOneDetection) {
  Grid g;
  const auto person = g.paint(2, 10, 357, 6, 5.0);  // columns 357, 358, 359, 0, 1, 2
  for (const auto rule : {JoinRule::kRangeDifference, JoinRule::kEuclidean}) {
    DetectionConfig config;
    config.join_rule = rule;
    Detector detector(config);
    const auto& d = g.detect(detector);
    ASSERT_EQ(d.size(), 1u);
    EXPECT_EQ(d[0].indices, person);
    // Centroid straight ahead of the sensor (azimuth ~ 359.5 deg), not at the grid's middle.
    EXPECT_NEAR(d[0].centroid.x(), 5.0, 0.05);
    EXPECT_NEAR(d[0].centroid.y(), 5.0 * std::sin(-0.5 * kDeg), 0.02);
    EXPECT_LT(d[0].box.diagonal_xy(), 0.6f);
    expect_matches_reference(g, config);
  }
  // A single column on each side of the seam is joined too (grid distance 1 across the seam).
  Grid thin;
  const auto cells = thin.paint(2, 10, 359, 2, 5.0);
  Detector detector{DetectionConfig{}};
  ASSERT_EQ(thin.detect(detector).size(), 1u);
  EXPECT_EQ(detector.detections()[0].indices, cells);
}

TEST(Detector, SeamIsNotAGapButRingsDoNotWrap) {
  // Columns 358 and 2 are 4 apart across the seam: beyond radius 3, so two clusters.
  Grid g;
  g.paint(2, 10, 357, 2, 5.0);  // 357, 358
  g.paint(2, 10, 2, 2, 5.0);    // 2, 3
  DetectionConfig config;
  Detector detector(config);
  g.detect(detector);
  EXPECT_EQ(detector.stats().clusters, 2u);
  config.neighbor_radius = 4;
  Detector wide(config);
  g.detect(wide);
  EXPECT_EQ(wide.stats().clusters, 1u);

  // The bottom and the top ring are far apart in the scene: never neighbours.
  Grid rings;
  rings.paint(0, 0, 100, 6, 5.0);
  rings.paint(15, 15, 100, 6, 5.0);
  config.neighbor_radius = 3;
  config.join_distance_m = 100.0;
  Detector d(config);
  rings.detect(d);
  EXPECT_EQ(d.stats().clusters, 2u);
}

TEST(Detector, PersonCutByTheTopOrBottomRingSkipsTheMinimumHeight) {
  // Rings 13..15 at 5 m: 0.37 m of extent, far below min_height_m, but the object may go on
  // above the field of view.
  DetectionConfig config;
  for (const auto& [r0, r1, accepted] :
       {std::tuple{13, 15, true}, std::tuple{0, 2, true}, std::tuple{10, 12, false}}) {
    Grid g;
    const auto cells = g.paint(r0, r1, 50, 6, 5.0);
    Detector detector(config);
    const auto& d = g.detect(detector);
    ASSERT_EQ(d.size(), accepted ? 1u : 0u) << "rings " << r0 << ".." << r1;
    if (accepted) {
      EXPECT_EQ(d[0].indices, cells);
      EXPECT_FALSE(d[0].relaxed);
    } else {
      EXPECT_EQ(detector.stats().too_short, 1u);
    }
  }
  // The maximum height still applies to cut clusters: rings 0..15 at 5 m span 2.7 m.
  Grid g;
  g.paint(0, 15, 50, 6, 5.0);
  Detector detector(config);
  EXPECT_TRUE(g.detect(detector).empty());
  EXPECT_EQ(detector.stats().too_tall, 1u);
}

TEST(Detector, WallIsTooWide) {
  Grid g;
  g.paint(3, 12, 0, 60, 5.0);  // 5 m of wall, 1.6 m tall
  Detector detector{DetectionConfig{}};
  EXPECT_TRUE(g.detect(detector).empty());
  EXPECT_EQ(detector.stats().clusters, 1u);
  EXPECT_EQ(detector.stats().too_wide, 1u);
  // A prediction nearby does not make a wall a person: wider than the relaxed diagonal too.
  Detector near{DetectionConfig{}};
  EXPECT_TRUE(g.detect(near, {}, {Eigen::Vector3f(5.0f, 2.5f, 0.0f)}).empty());
}

TEST(Detector, ThinPolesAndStubsAreRejected) {
  DetectionConfig config;
  config.min_height_ring_gap_deg = 0.0;  // test the bare extents
  // A lamp post: one column, rings 0..15 at 5 m (2.7 m tall): too tall.
  Grid pole;
  pole.paint(0, 15, 90, 1, 5.0);
  Detector d1(config);
  EXPECT_TRUE(pole.detect(d1).empty());
  EXPECT_EQ(d1.stats().too_tall, 1u);
  // A bollard: one column, rings 5..8 (0.52 m) in the middle of the field of view: too short.
  Grid stub;
  stub.paint(5, 8, 90, 1, 5.0);
  Detector d2(config);
  EXPECT_TRUE(stub.detect(d2).empty());
  EXPECT_EQ(d2.stats().too_short, 1u);
  // A thin person-height pole (1.4 m) fits the model: the model has no minimum width; the
  // segmentation's noise filter is what removes objects narrower than min_width_m.
  Grid post;
  post.paint(2, 10, 90, 1, 5.0);
  Detector d3(config);
  EXPECT_EQ(post.detect(d3).size(), 1u);
}

TEST(Detector, ClusterTooWideUnlessNearAPrediction) {
  Grid g;
  const auto cells = g.paint(2, 10, 40, 17, 5.0);  // 1.4 m wide, 1.4 m tall at 5 m
  Detector detector{DetectionConfig{}};
  EXPECT_TRUE(g.detect(detector).empty());
  EXPECT_EQ(detector.stats().too_wide, 1u);
  // Relaxed: a track predicted here allows up to relaxed_max_diagonal_m (1.8 m).
  const Eigen::Vector3f here(static_cast<float>(5.0 * std::cos(48 * kDeg)),
                             static_cast<float>(5.0 * std::sin(48 * kDeg)), 0.0f);
  const auto& d = g.detect(detector, {}, {here});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_TRUE(d[0].relaxed);
  EXPECT_EQ(d[0].indices, cells);
  EXPECT_EQ(detector.stats().relaxed, 1u);
  expect_matches_reference(g, DetectionConfig{}, {}, {here});
  // 2.6 m wide exceeds even the relaxed model.
  Grid wider;
  wider.paint(2, 10, 40, 31, 5.0);
  EXPECT_TRUE(wider.detect(detector, {}, {here}).empty());
}

TEST(Detector, RelaxedDetectionOnlyNearAPrediction) {
  // A partly occluded person: rings 6..8 at 5 m, 0.35 m of extent.
  Grid g;
  const auto cells = g.paint(6, 8, 60, 6, 5.0);
  const double az = 62.5 * kDeg;
  const Eigen::Vector3f at(static_cast<float>(5.0 * std::cos(az)),
                           static_cast<float>(5.0 * std::sin(az)), -0.3f);
  Detector detector{DetectionConfig{}};
  EXPECT_TRUE(g.detect(detector).empty());
  EXPECT_EQ(detector.stats().too_short, 1u);

  const auto& d = g.detect(detector, {}, {Eigen::Vector3f(50.0f, 0.0f, 0.0f), at});
  ASSERT_EQ(d.size(), 1u);
  EXPECT_TRUE(d[0].relaxed);
  EXPECT_EQ(d[0].indices, cells);

  // The vicinity is horizontal: a prediction above the cluster still counts...
  EXPECT_EQ(g.detect(detector, {}, {at + Eigen::Vector3f(0.0f, 0.0f, 5.0f)}).size(), 1u);
  // ...a prediction 2 m to the side does not.
  const Eigen::Vector3f aside = at + Eigen::Vector3f(static_cast<float>(-2.0 * std::sin(az)),
                                                     static_cast<float>(2.0 * std::cos(az)), 0.0f);
  EXPECT_TRUE(g.detect(detector, {}, {aside}).empty());

  // A cluster that fits the strict model is never flagged relaxed, prediction or not.
  Grid person;
  person.paint(2, 10, 60, 6, 5.0);
  const auto& strict = person.detect(detector, {}, {at});
  ASSERT_EQ(strict.size(), 1u);
  EXPECT_FALSE(strict[0].relaxed);
  EXPECT_EQ(detector.stats().relaxed, 0u);
}

TEST(Detector, SparseClustersOnlyInFrontOfALearnedBackground) {
  // A resting sensor looked at a wall 80 m away for three scans; now two far people stand in
  // front of it, hit by one and by two beams, and one wall cell is labelled a segment point.
  Grid g;
  for (int r = 0; r < g.scan.rings(); ++r) {
    for (int c = 0; c < g.scan.columns(); ++c) {
      g.scan.set_range(g.model, r, c, 80.0f, 1.0f);
    }
  }
  core::BackgroundRangeConfig learn_fast;
  learn_fast.scans_to_learn = 3;
  core::BackgroundRangeModel background(g.model, learn_fast);
  for (int k = 0; k < 3; ++k) background.update(g.scan);
  ASSERT_EQ(background.learned_count(), g.scan.size());

  const auto one = g.paint(8, 8, 100, 1, 50.0);   // 1 point, 0.87 m above the sensor
  const auto two = g.paint(7, 7, 200, 2, 50.0);   // 2 points side by side
  const auto wall = g.paint(8, 8, 300, 1, 80.0);  // on the background: old structure
  Detector detector{DetectionConfig{}};
  EXPECT_TRUE(g.detect(detector).empty()) << "without memory a cluster needs 3 points";
  EXPECT_EQ(detector.stats().too_small, 3u);

  const auto& d = detector.detect(g.scan, g.labels, {}, {}, &background);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].indices, two);  // in order of the smallest cell: ring 7 before ring 8
  EXPECT_EQ(d[1].indices, one);
  for (const auto& x : d) {
    EXPECT_TRUE(x.sparse);
    EXPECT_FALSE(x.relaxed);
  }
  EXPECT_EQ(detector.stats().sparse, 2u);
  EXPECT_EQ(detector.stats().too_small, 1u) << "the wall cell";
  static_cast<void>(wall);

  // Nearer than the margin in front of the background is not evidence.
  DetectionConfig wide_margin;
  wide_margin.background_margin_m = 31.0;
  Detector strict_margin(wide_margin);
  EXPECT_TRUE(strict_margin.detect(g.scan, g.labels, {}, {}, &background).empty());
  // Two points are needed when sparse_min_points says so.
  DetectionConfig two_points;
  two_points.sparse_min_points = 2;
  Detector pairs(two_points);
  const auto& p = pairs.detect(g.scan, g.labels, {}, {}, &background);
  ASSERT_EQ(p.size(), 1u);
  EXPECT_EQ(p[0].indices, two);
  // A sparse cluster still meets the object model: the same point 10 m away is too short
  // (10 m * tan 2 deg of ring-gap credit is below the 0.8 m minimum height).
  Grid near;
  for (int c = 0; c < near.scan.columns(); ++c) near.scan.set_range(near.model, 8, c, 80.0f, 1.0f);
  core::BackgroundRangeModel near_background(near.model, learn_fast);
  for (int k = 0; k < 3; ++k) near_background.update(near.scan);
  near.paint(8, 8, 100, 1, 10.0);
  Detector model_check{DetectionConfig{}};
  EXPECT_TRUE(model_check.detect(near.scan, near.labels, {}, {}, &near_background).empty());
  // Dropped as too small: the memory is not asked about a small cluster of the wrong shape.
  EXPECT_EQ(model_check.stats().too_small, 1u);
  // With a lower minimum height the same point is a sparse detection: it was the model.
  DetectionConfig low;
  low.min_height_m = 0.3;
  Detector low_check(low);
  const auto& l = low_check.detect(near.scan, near.labels, {}, {}, &near_background);
  ASSERT_EQ(l.size(), 1u);
  EXPECT_TRUE(l[0].sparse);
}

TEST(Detector, ObjectModelAndOutputAreInTheWorldFrame) {
  Grid g;
  const auto cells = g.paint(2, 10, 20, 6, 5.0);
  core::Pose pose;
  pose.translation = Eigen::Vector3d(10.0, -4.0, 1.5);
  pose.rotation = Eigen::AngleAxisd(0.5 * std::numbers::pi, Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX());
  Detector detector{DetectionConfig{}};
  const auto& d = g.detect(detector, pose);
  ASSERT_EQ(d.size(), 1u);
  core::Box3 box;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto i : cells) {
    const Eigen::Vector3f w = pose.to_world(g.scan.point(i));
    box.extend(w);
    sum += w.cast<double>();
  }
  const Eigen::Vector3f centroid = (sum / static_cast<double>(cells.size())).cast<float>();
  EXPECT_TRUE(d[0].centroid.isApprox(centroid, 1e-5f)) << d[0].centroid.transpose();
  EXPECT_TRUE(d[0].box.min.isApprox(box.min, 1e-5f));
  EXPECT_TRUE(d[0].box.max.isApprox(box.max, 1e-5f));
  EXPECT_EQ(d[0].indices, cells);
  expect_matches_reference(g, DetectionConfig{}, pose);

  // Max altitude is a world-frame test: the same cluster seen from a sensor 5 m up is too high
  // (its lowest point is at about 4 m), and the relaxed model keeps that limit.
  core::Pose raised;
  raised.translation = Eigen::Vector3d(0.0, 0.0, 5.0);
  Eigen::Vector3f sensor_centroid = Eigen::Vector3f::Zero();
  for (const auto i : cells) sensor_centroid += g.scan.point(i);
  sensor_centroid /= static_cast<float>(cells.size());
  EXPECT_TRUE(g.detect(detector, raised, {raised.to_world(sensor_centroid)}).empty());
  EXPECT_EQ(detector.stats().too_high, 1u);

  // Relaxed vicinity is measured in the world frame too: a prediction at the world position of
  // a short cluster relaxes it under a moved sensor.
  Grid short_cluster;
  short_cluster.paint(6, 8, 0, 3, 5.0);  // straight ahead of the sensor
  EXPECT_TRUE(short_cluster.detect(detector, pose).empty());
  const auto near = pose.to_world(Eigen::Vector3f(5.0f, 0.087f, 0.0f));
  const auto& relaxed = short_cluster.detect(detector, pose, {near});
  ASSERT_EQ(relaxed.size(), 1u);
  EXPECT_TRUE(relaxed[0].relaxed);
}

TEST(Detector, CovarianceIsThePointSpreadWithAFloor) {
  // One column: no horizontal spread, so x and y variances sit on the floor; z keeps its
  // population variance.
  Grid g;
  const auto cells = g.paint(2, 10, 0, 1, 5.0);
  DetectionConfig config;
  config.min_height_ring_gap_deg = 0.0;
  Detector detector(config);
  const auto& d = g.detect(detector);
  ASSERT_EQ(d.size(), 1u);
  double mean_z = 0;
  for (const auto i : cells) mean_z += g.scan.zs()[i];
  mean_z /= static_cast<double>(cells.size());
  double var_z = 0;
  for (const auto i : cells) var_z += (g.scan.zs()[i] - mean_z) * (g.scan.zs()[i] - mean_z);
  var_z /= static_cast<double>(cells.size());
  const float floor = 0.03f * 0.03f;
  EXPECT_FLOAT_EQ(d[0].covariance(0, 0), floor);
  EXPECT_FLOAT_EQ(d[0].covariance(1, 1), floor);
  EXPECT_NEAR(d[0].covariance(2, 2), var_z, 1e-6);
  EXPECT_GT(var_z, 0.1);
  EXPECT_NEAR(d[0].covariance(0, 2), 0.0f, 1e-6f);
  EXPECT_TRUE(d[0].covariance.isApprox(d[0].covariance.transpose()));
  // A larger floor lifts the z variance too.
  config.min_position_stddev_m = 1.0;
  Detector big(config);
  EXPECT_FLOAT_EQ(g.detect(big)[0].covariance(2, 2), 1.0f);
}

TEST(Detector, MinimumClusterSizeAndInvalidCells) {
  Grid g;
  g.paint(5, 6, 30, 1, 5.0);  // two points
  DetectionConfig config;
  config.min_height_m = 0.0;
  Detector detector(config);
  EXPECT_TRUE(g.detect(detector).empty());
  EXPECT_EQ(detector.stats().too_small, 1u);
  config.min_cluster_points = 2;
  Detector two(config);
  EXPECT_EQ(g.detect(two).size(), 1u);
  // A segment label on an invalid cell is ignored.
  Grid h;
  h.paint(2, 10, 30, 6, 5.0);
  h.scan.set_invalid(5, 32, core::ReturnStatus::kNoReturn);
  Detector d(config);
  ASSERT_EQ(h.detect(d).size(), 1u);
  EXPECT_EQ(d.detections()[0].indices.size(), 6u * 9u - 1u);
  EXPECT_EQ(d.stats().segment_points, 6u * 9u - 1u);
}

TEST(Detector, JoinRuleRangeDifferenceKeepsAFarPersonWhole) {
  // VLP-16 at 2.5 m above the ground, a person 25 m away: two rings hit, 0.87 m apart. The
  // Euclidean rule at theta 0.5 cuts the person into one cluster per ring (the far-range failure
  // that makes range difference the default); the range difference keeps it whole.
  Grid g(core::SensorModel::vlp16());
  const auto cells = g.paint_person(25.0, 30.0, -2.5);
  DetectionConfig config;
  Detector by_range(config);
  ASSERT_EQ(g.detect(by_range).size(), 1u);
  EXPECT_EQ(by_range.detections()[0].indices, cells);
  config.join_rule = JoinRule::kEuclidean;
  Detector by_distance(config);
  g.detect(by_distance);
  EXPECT_EQ(by_distance.stats().clusters, 2u);
}

TEST(Detector, PeopleAt5To40MetresOnAVlp16) {
  // The default object model accepts a person at any range in the field of view; beyond 28 m a
  // VLP-16 sees one ring only, so the ring-gap allowance carries the minimum-height test.
  for (double h = 5.0; h <= 40.0; h += 1.0) {
    Grid g(core::SensorModel::vlp16());
    const auto cells = g.paint_person(h, 100.0, -2.5);
    Detector detector{DetectionConfig{}};
    const auto& d = g.detect(detector);
    ASSERT_EQ(d.size(), 1u) << "at " << h << " m";
    EXPECT_EQ(d[0].indices, cells);
  }
}

TEST(Detector, ReusesItsBuffersAndAdaptsToNewGridSizes) {
  Grid a;
  a.paint(2, 10, 10, 6, 5.0);
  a.paint(2, 10, 100, 6, 7.0);
  Grid b(core::SensorModel::vlp16());
  b.paint_person(8.0, 10.0, -1.5);
  Detector detector{DetectionConfig{}};
  for (int k = 0; k < 3; ++k) {
    ASSERT_EQ(a.detect(detector).size(), 2u);
    ASSERT_EQ(b.detect(detector).size(), 1u);
  }
  EXPECT_EQ(a.detect(detector)[1].indices, a.paint(2, 10, 100, 6, 7.0));
}

TEST(Detector, RejectsMismatchedLabelsAndImpossibleSettings) {
  Grid g;
  Detector detector{DetectionConfig{}};
  std::vector<std::uint8_t> short_labels(10, 0);
  EXPECT_THROW(detector.detect(g.scan, short_labels, {}), core::InputError);
  DetectionConfig bad;
  bad.min_cluster_points = 0;
  EXPECT_THROW(Detector{bad}, core::ConfigError);
  bad = {};
  bad.neighbor_radius = -1;
  EXPECT_THROW(Detector{bad}, core::ConfigError);
  // An empty scan has no detections.
  core::OrganizedScan empty;
  EXPECT_TRUE(detector.detect(empty, {}, {}).empty());
}

}  // namespace
}  // namespace ringtrack::detection
