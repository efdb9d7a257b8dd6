// The split step: people side by side that region growing merges come out as one detection
// each; single people and uniformly sampled surfaces are never split.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <set>

#include "ringtrack/core/error.hpp"
#include "ringtrack/detection/detector.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "support/naive_detection.hpp"

namespace ringtrack::detection {
namespace {

using core::DetectionConfig;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kGroundZ = -1.8;  // VLP-16 1.8 m above the ground

// People (0.25 m radius cylinders, 1.75 m tall) in a row across the line of sight at
// horizontal distance distance_m and azimuth az_deg, spacing_m apart centre to centre.
sim::SimpleScene row_of_people(int count, double distance_m, double spacing_m, double az_deg) {
  sim::SimpleScene scene;
  scene.ground_z_m = kGroundZ;
  scene.range_noise_m = 0.02;
  const Eigen::Vector2d along(std::cos(az_deg * kDeg), std::sin(az_deg * kDeg));
  const Eigen::Vector2d across(-along.y(), along.x());
  for (int k = 0; k < count; ++k) {
    const double offset = (k - 0.5 * (count - 1)) * spacing_m;
    const Eigen::Vector2d c = distance_m * along + offset * across;
    scene.cylinders.push_back(
        sim::SimpleScene::person(c.x(), c.y(), kGroundZ, static_cast<std::uint32_t>(k + 1)));
  }
  return scene;
}

// The rendered scan with the true object cells as segment labels: the detector alone is tested
// (whether segmentation keeps a 1.1 m pair is segmentation's business).
struct Labelled {
  sim::RenderedScan rendered;
  std::vector<std::uint8_t> labels;
};

Labelled render_labelled(const sim::SimpleScene& scene) {
  Labelled out{sim::render(core::SensorModel::vlp16(), scene), {}};
  out.labels.resize(out.rendered.labels.size());
  for (std::size_t i = 0; i < out.labels.size(); ++i) {
    out.labels[i] = out.rendered.labels[i] != 0 ? kSegmentLabel : 0;
  }
  return out;
}

// The object each detection's cells belong to (all of them must agree).
std::vector<std::uint32_t> owners(const std::vector<core::Detection>& detections,
                                  const std::vector<std::uint32_t>& truth) {
  std::vector<std::uint32_t> out;
  for (const auto& d : detections) {
    std::map<std::uint32_t, std::size_t> votes;
    for (const auto i : d.indices) ++votes[truth[i]];
    EXPECT_EQ(votes.size(), 1u) << "a detection mixes objects";
    out.push_back(votes.begin()->first);
  }
  return out;
}

void expect_same_as_reference(const Labelled& l, const DetectionConfig& config) {
  Detector detector(config);
  const auto& fast = detector.detect(l.rendered.scan, l.labels, core::Pose{});
  const auto slow = testing::naive_detect(l.rendered.scan, l.labels, config, core::Pose{});
  ASSERT_EQ(fast.size(), slow.size());
  for (std::size_t k = 0; k < fast.size(); ++k) EXPECT_EQ(fast[k].indices, slow[k].indices);
}

// Each of `count` people in a row is found once, at its place: its lateral position (across the
// line of sight) within 0.15 m; the centroid of the visible front lies up to r * pi / 4 = 0.2 m
// in front of the centre, so the full horizontal error is allowed 0.3 m.
void expect_each_person_once(int count, double distance_m, double spacing_m, double az_deg) {
  const auto scene = row_of_people(count, distance_m, spacing_m, az_deg);
  const auto l = render_labelled(scene);
  const std::string what = std::to_string(count) + " people " + std::to_string(spacing_m) +
                           " m apart at " + std::to_string(distance_m) + " m";
  Detector detector{DetectionConfig{}};
  const auto& d = detector.detect(l.rendered.scan, l.labels, core::Pose{});
  ASSERT_EQ(d.size(), static_cast<std::size_t>(count))
      << what << ": clusters " << detector.stats().clusters << ", splits "
      << detector.stats().splits << ", too wide " << detector.stats().too_wide;
  const auto who = owners(d, l.rendered.labels);
  EXPECT_EQ(std::set<std::uint32_t>(who.begin(), who.end()).size(), static_cast<std::size_t>(count))
      << what;
  const Eigen::Vector2d across(-std::sin(az_deg * kDeg), std::cos(az_deg * kDeg));
  for (std::size_t k = 0; k < d.size(); ++k) {
    const auto& person = scene.cylinders[who[k] - 1];
    const Eigen::Vector2d error =
        d[k].centroid.head<2>().cast<double>() - Eigen::Vector2d(person.x_m, person.y_m);
    EXPECT_LT(std::abs(error.dot(across)), 0.15) << what << ", person " << who[k];
    EXPECT_LT(error.norm(), 0.3) << what << ", person " << who[k];
    EXPECT_FALSE(d[k].relaxed) << what;
  }
  expect_same_as_reference(l, DetectionConfig{});
}

TEST(DetectorSplit, TwoPeopleSideBySideAreTwoDetections) {
  for (const double distance : {5.0, 10.0, 20.0}) {
    for (const double spacing : {0.6, 0.7, 0.8}) {
      for (const double az : {30.0, 200.0}) expect_each_person_once(2, distance, spacing, az);
    }
  }
}

TEST(DetectorSplit, WithoutTheSplitSideBySidePeopleMerge) {
  // Control: region growing alone merges the pair at 20 m (the 0.1 m gap between them is under
  // the window's 3 columns), and the merged cluster is not two people.
  for (const double distance : {15.0, 20.0}) {
    const auto l = render_labelled(row_of_people(2, distance, 0.6, 30.0));
    DetectionConfig off;
    off.split_min_width_m = 0.0;
    Detector detector(off);
    const auto& d = detector.detect(l.rendered.scan, l.labels, core::Pose{});
    EXPECT_EQ(detector.stats().clusters, 1u) << distance;
    EXPECT_LE(d.size(), 1u);
    EXPECT_EQ(detector.stats().splits, 0u);
    Detector on{DetectionConfig{}};
    on.detect(l.rendered.scan, l.labels, core::Pose{});
    EXPECT_EQ(on.stats().splits, 1u) << distance;
  }
}

TEST(DetectorSplit, ThreePeopleInARowAreThree) {
  for (const double distance : {5.0, 10.0, 20.0}) {
    for (const double spacing : {0.6, 0.7}) expect_each_person_once(3, distance, spacing, 120.0);
  }
}

TEST(DetectorSplit, OnePersonIsOneDetection) {
  for (const double distance : {3.0, 5.0, 10.0, 20.0, 30.0})
    expect_each_person_once(1, distance, 0.0, 75.0);
}

TEST(DetectorSplit, WideUniformObjectsAreNotSplit) {
  // A round object much wider than a person (a 1.2-2.4 m drum or rounded car end): one mode.
  for (const double radius : {0.6, 0.9, 1.2}) {
    for (const double distance : {5.0, 10.0, 20.0}) {
      sim::SimpleScene scene;
      scene.ground_z_m = kGroundZ;
      scene.range_noise_m = 0.02;
      sim::Cylinder drum{distance, 1.0, radius, kGroundZ, kGroundZ + 1.5, 1};
      scene.cylinders.push_back(drum);
      const auto l = render_labelled(scene);
      DetectionConfig wide;
      wide.max_diagonal_m = 10.0;  // let the whole object through the model
      Detector detector(wide);
      const auto& d = detector.detect(l.rendered.scan, l.labels, core::Pose{});
      EXPECT_EQ(detector.stats().splits, 0u) << radius << " m radius at " << distance << " m";
      EXPECT_EQ(d.size(), 1u);
      expect_same_as_reference(l, wide);
    }
  }
}

// Grid of a VLP-16 without beam offsets where walls are painted as straight segments.
struct WallGrid {
  core::SensorModel model{core::SensorModel::vlp16()};
  core::OrganizedScan scan{model.rings(), model.columns()};
  std::vector<std::uint8_t> labels;

  WallGrid() {
    scan.set_uniform_columns(model, 0);
    labels.assign(scan.size(), 0);
  }

  // A vertical wall from a to b (horizontal, sensor frame) between heights z0 and z1.
  void paint_wall(const Eigen::Vector2d& a, const Eigen::Vector2d& b, double z0, double z1) {
    for (int c = 0; c < scan.columns(); ++c) {
      const double az = scan.column_azimuth_rad[static_cast<std::size_t>(c)];
      const Eigen::Vector2d dir(std::cos(az), std::sin(az));
      // Solve t * dir = a + s * (b - a) for t > 0, s in [0, 1].
      const Eigen::Vector2d e = b - a;
      const double det = dir.x() * -e.y() + dir.y() * e.x();
      if (std::abs(det) < 1e-12) continue;
      const double t = (a.x() * -e.y() + a.y() * e.x()) / det;
      const double s = (dir.x() * a.y() - dir.y() * a.x()) / det;
      if (t <= 0.0 || s < 0.0 || s > 1.0) continue;
      for (int r = 0; r < scan.rings(); ++r) {
        const double el = model.elevation_rad[static_cast<std::size_t>(r)];
        const double z = t * std::tan(el) + model.vertical_offset_m[static_cast<std::size_t>(r)];
        if (z < z0 || z > z1) continue;
        scan.set_range(model, r, c, static_cast<float>(t / std::cos(el)), 1.0f);
        labels[scan.index(r, c)] = kSegmentLabel;
      }
    }
  }
};

TEST(DetectorSplit, UniformWallsAreNotSplitAtAnyAngleOrRange) {
  // Wall segments 1-4 m long, facing the sensor or turned up to 70 degrees away, at 4-30 m:
  // uniformly sampled, so never cut into person-sized pieces.
  for (const double distance : {4.0, 8.0, 15.0, 30.0}) {
    for (const double length : {1.0, 1.5, 2.5, 4.0}) {
      for (const double turn_deg : {0.0, 30.0, 55.0, 70.0}) {
        WallGrid g;
        const double az = 40.0 * kDeg;
        const Eigen::Vector2d centre = distance * Eigen::Vector2d(std::cos(az), std::sin(az));
        const double dir_rad = az + (90.0 + turn_deg) * kDeg;
        const Eigen::Vector2d half =
            0.5 * length * Eigen::Vector2d(std::cos(dir_rad), std::sin(dir_rad));
        g.paint_wall(centre - half, centre + half, kGroundZ + 0.2, kGroundZ + 1.6);
        DetectionConfig config;
        config.max_diagonal_m = 10.0;
        config.min_height_m = 0.0;
        Detector detector(config);
        const auto& d = detector.detect(g.scan, g.labels, core::Pose{});
        const std::string what = std::to_string(length) + " m wall at " + std::to_string(distance) +
                                 " m turned " + std::to_string(turn_deg) + " deg";
        EXPECT_EQ(detector.stats().splits, 0u) << what;
        EXPECT_LE(d.size(), 1u) << what;
      }
    }
  }
}

TEST(DetectorSplit, ConfigDisablesAndValidates) {
  DetectionConfig bad;
  bad.split_valley_ratio = 1.0;
  EXPECT_THROW(Detector{bad}, core::ConfigError);
  bad = {};
  bad.split_bin_m = 0.0;
  EXPECT_THROW(Detector{bad}, core::ConfigError);
  bad = {};
  bad.split_min_width_m = -1.0;
  EXPECT_THROW(Detector{bad}, core::ConfigError);
}

}  // namespace
}  // namespace ringtrack::detection
