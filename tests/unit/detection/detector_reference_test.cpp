// The fast detector against the union-find reference on random grids, and on rendered scenes
// against the people that were put in them.

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "ringtrack/detection/detector.hpp"
#include "ringtrack/segmentation/segmenter.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "support/naive_detection.hpp"

namespace ringtrack::detection {
namespace {

using core::DetectionConfig;
using core::JoinRule;

struct LabelledScan {
  core::OrganizedScan scan;
  std::vector<std::uint8_t> labels;
};

// Random scan: per ring, runs of columns share a base range (objects at different depths) plus
// noise, so joins and splits both happen; random segment labels (a few stray label values that
// are not segments), and invalid cells that may still carry a segment label.
LabelledScan random_scan(std::mt19937& rng, int rings, int columns, double density) {
  LabelledScan out{core::OrganizedScan(rings, columns), {}};
  out.labels.assign(out.scan.size(), 0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 0.15);
  std::uniform_int_distribution<int> run_length(1, 8);
  for (int r = 0; r < rings; ++r) {
    const double el =
        rings == 1 ? 0.0 : (-15.0 + 30.0 * r / (rings - 1)) * std::numbers::pi / 180.0;
    double base = 3.0 + 7.0 * u(rng);
    int run_left = run_length(rng);
    for (int c = 0; c < columns; ++c) {
      if (run_left-- == 0) {
        base = 3.0 + 7.0 * u(rng);
        run_left = run_length(rng);
      }
      const double az = 2.0 * std::numbers::pi * c / columns;
      const double range = base + noise(rng);
      const Eigen::Vector3f p(static_cast<float>(range * std::cos(el) * std::cos(az)),
                              static_cast<float>(range * std::cos(el) * std::sin(az)),
                              static_cast<float>(range * std::sin(el)));
      const double roll = u(rng);
      if (roll < 0.05) {
        out.scan.set_invalid(r, c, core::ReturnStatus::kNoReturn);
      } else {
        out.scan.set_return(r, c, static_cast<float>(range), 1.0f, p);
      }
      const double pick = u(rng);
      const auto i = out.scan.index(r, c);
      out.labels[i] = pick < density ? kSegmentLabel : (pick < density + 0.02 ? 2 : 0);
    }
  }
  return out;
}

core::Pose random_pose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  core::Pose pose;
  pose.translation = Eigen::Vector3d(5 * u(rng), 5 * u(rng), u(rng));
  pose.rotation = Eigen::AngleAxisd(3 * u(rng), Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(0.2 * u(rng), Eigen::Vector3d::UnitX());
  return pose;
}

void expect_same(const std::vector<core::Detection>& fast, const std::vector<core::Detection>& slow,
                 const std::string& what) {
  ASSERT_EQ(fast.size(), slow.size()) << what;
  for (std::size_t k = 0; k < fast.size(); ++k) {
    ASSERT_EQ(fast[k].indices, slow[k].indices) << what << " detection " << k;
    EXPECT_EQ(fast[k].relaxed, slow[k].relaxed) << what << " detection " << k;
    EXPECT_EQ(fast[k].sparse, slow[k].sparse) << what << " detection " << k;
    EXPECT_TRUE(fast[k].centroid.isApprox(slow[k].centroid, 1e-5f)) << what;
    EXPECT_TRUE(fast[k].box.min.isApprox(slow[k].box.min, 1e-5f)) << what;
    EXPECT_TRUE(fast[k].box.max.isApprox(slow[k].box.max, 1e-5f)) << what;
    EXPECT_LT((fast[k].covariance - slow[k].covariance).cwiseAbs().maxCoeff(), 1e-5f) << what;
  }
}

TEST(DetectorReference, ClustersEqualUnionFindOnRandomGrids) {
  std::mt19937 rng(2019);
  const std::vector<std::pair<int, int>> sizes = {{1, 8},  {2, 3},   {4, 5},   {3, 7},
                                                  {16, 9}, {16, 60}, {8, 120}, {16, 360}};
  int trials = 0, nontrivial = 0;
  std::size_t strict = 0, relaxed = 0, rejected = 0, splits = 0;
  for (const auto& [rings, columns] : sizes) {
    for (int radius : {0, 1, 2, 3, 5}) {
      for (const auto rule : {JoinRule::kRangeDifference, JoinRule::kEuclidean}) {
        for (double density : {0.1, 0.3, 0.7}) {
          if (rings * columns > 2000 && density > 0.3) continue;  // keep the O(n^2) reference quick
          auto [scan, labels] = random_scan(rng, rings, columns, density);
          // Clustering alone: an object model that accepts every cluster.
          DetectionConfig all;
          all.neighbor_radius = radius;
          all.join_rule = rule;
          all.join_distance_m = std::uniform_real_distribution<double>(0.1, 1.0)(rng);
          all.min_cluster_points = 1 + trials % 3;
          all.min_height_m = 0.0;
          all.max_height_m = 1e6;
          all.max_diagonal_m = 1e6;
          all.max_altitude_m = 1e6;
          const auto pose = random_pose(rng);
          Detector fast(all);
          const std::string what = std::to_string(rings) + "x" + std::to_string(columns) + " r" +
                                   std::to_string(radius) + " rule " +
                                   std::to_string(static_cast<int>(rule));
          const auto& got = fast.detect(scan, labels, pose);
          expect_same(got, testing::naive_detect(scan, labels, all, pose), what + " accept-all");
          nontrivial +=
              fast.stats().clusters > 1 && fast.stats().clusters < fast.stats().segment_points;
          splits += fast.stats().splits;

          // The default object model with predictions at some segment points.
          DetectionConfig model;
          model.neighbor_radius = radius;
          model.join_rule = rule;
          model.max_diagonal_m = 0.8;
          std::vector<Eigen::Vector3f> predictions;
          for (std::size_t i = 0; i < scan.size(); i += 37) {
            if (scan.valid(i)) predictions.push_back(pose.to_world(scan.point(i)));
          }
          Detector fast_model(model);
          expect_same(fast_model.detect(scan, labels, pose, predictions),
                      testing::naive_detect(scan, labels, model, pose, predictions),
                      what + " model");
          strict += fast_model.stats().detections - fast_model.stats().relaxed;
          relaxed += fast_model.stats().relaxed;
          rejected += fast_model.stats().clusters - fast_model.stats().detections;
          splits += fast_model.stats().splits;
          ++trials;
        }
      }
    }
  }
  // The random grids exercise real clustering and every verdict of the object model.
  EXPECT_GT(nontrivial, trials / 3);
  EXPECT_GT(strict, 100u);
  EXPECT_GT(relaxed, 100u);
  EXPECT_GT(rejected, 100u);
  EXPECT_GT(splits, 100u);  // the split step (default settings) is compared too
}

// A hand-made scene memory: a cell counts as seen free before unless its index is a multiple
// of 5 or its world point lies below z = -1 m (so both arguments matter).
class EveryFifthOccupied : public core::SceneMemory {
 public:
  [[nodiscard]] bool seen_free_before(const core::OrganizedScan& scan, std::size_t cell,
                                      const Eigen::Vector3d& world_point,
                                      double margin_m) const override {
    static_cast<void>(scan);
    EXPECT_DOUBLE_EQ(margin_m, 0.7);
    return cell % 5 != 0 && world_point.z() > -1.0;
  }
};

TEST(DetectorReference, SparseDetectionsEqualTheReferenceWithASceneMemory) {
  std::mt19937 rng(11);
  const EveryFifthOccupied memory;
  std::size_t sparse = 0, relaxed = 0, strict = 0;
  for (int k = 0; k < 60; ++k) {
    const int columns = k % 3 == 0 ? 360 : 120;
    auto [scan, labels] = random_scan(rng, 16, columns, 0.03 + 0.01 * (k % 5));
    DetectionConfig config;
    config.neighbor_radius = 1 + k % 3;
    config.min_cluster_points = 3 + k % 2;
    config.sparse_min_points = 1 + k % 2;
    config.background_margin_m = 0.7;
    config.min_height_m = 0.2;
    config.max_diagonal_m = 0.8;
    const auto pose = random_pose(rng);
    std::vector<Eigen::Vector3f> predictions;
    for (std::size_t i = 0; i < scan.size(); i += 97) {
      if (scan.valid(i)) predictions.push_back(pose.to_world(scan.point(i)));
    }
    Detector fast(config);
    const auto& got = fast.detect(scan, labels, pose, predictions, &memory);
    expect_same(got, testing::naive_detect(scan, labels, config, pose, predictions, &memory),
                "scan " + std::to_string(k));
    sparse += fast.stats().sparse;
    relaxed += fast.stats().relaxed;
    strict += fast.stats().detections - fast.stats().sparse - fast.stats().relaxed;
    for (const auto& d : got) {
      // Only clusters below min_cluster_points are sparse, never relaxed at the same time.
      if (d.sparse) {
        EXPECT_LT(d.indices.size(), static_cast<std::size_t>(config.min_cluster_points));
        EXPECT_FALSE(d.relaxed);
      }
    }
  }
  EXPECT_GT(sparse, 50u);
  EXPECT_GT(relaxed, 20u);
  EXPECT_GT(strict, 10u);
}

TEST(DetectorReference, ReusedDetectorEqualsFreshOne) {
  std::mt19937 rng(7);
  DetectionConfig config;
  config.min_height_m = 0.0;
  Detector reused(config);
  for (int k = 0; k < 20; ++k) {
    const int columns = k % 2 ? 360 : 90;
    auto [scan, labels] = random_scan(rng, 16, columns, 0.05 + 0.02 * k);
    const auto pose = random_pose(rng);
    Detector fresh(config);
    expect_same(reused.detect(scan, labels, pose), fresh.detect(scan, labels, pose),
                "call " + std::to_string(k));
  }
}

// Majority ground-truth label of each detection's cells.
std::vector<std::uint32_t> majority_labels(const std::vector<core::Detection>& detections,
                                           const std::vector<std::uint32_t>& truth) {
  std::vector<std::uint32_t> out;
  for (const auto& d : detections) {
    std::map<std::uint32_t, std::size_t> votes;
    for (const auto i : d.indices) ++votes[truth[i]];
    auto best = votes.begin();
    for (auto it = votes.begin(); it != votes.end(); ++it) {
      if (it->second > best->second) best = it;
    }
    EXPECT_GE(best->second * 10, d.indices.size() * 9) << "a detection mixes objects";
    out.push_back(best->first);
  }
  return out;
}

TEST(DetectorScene, OpenFieldFindsTheTenPeople) {
  // The benchmark's scene: ten people at 5-40 m, ground 2.5 m below a VLP-16.
  const auto model = core::SensorModel::vlp16();
  const auto scene = sim::SimpleScene::open_field(10);
  const auto rendered = sim::render(model, scene);
  segmentation::Segmenter segmenter{core::SegmentationConfig{}};
  std::vector<std::uint8_t> labels;
  segmenter.segment(rendered.scan, labels);
  Detector detector{DetectionConfig{}};
  const auto& d = detector.detect(rendered.scan, labels, core::Pose{});
  ASSERT_EQ(d.size(), 10u) << "clusters " << detector.stats().clusters << ", too short "
                           << detector.stats().too_short;
  const auto who = majority_labels(d, rendered.labels);
  EXPECT_EQ(std::set<std::uint32_t>(who.begin(), who.end()).size(), 10u);
  for (std::size_t k = 0; k < d.size(); ++k) {
    ASSERT_GE(who[k], 1u);
    const auto& person = scene.cylinders[who[k] - 1];
    EXPECT_LT(std::hypot(d[k].centroid.x() - person.x_m, d[k].centroid.y() - person.y_m), 0.3)
        << "person " << who[k];
    EXPECT_FALSE(d[k].relaxed);
  }
}

TEST(DetectorScene, DemoSceneFindsEachPersonOnceAndNotTheWall) {
  // Five people inside a wall at 12 m, and a thin pole. Whether the pole survives segmentation
  // is segmentation's business (its noise window spans min_width_m); the object model could not
  // reject it, as it crosses the whole field of view (height cut at both ends). The wall must
  // not appear, and each person exactly once.
  const auto model = core::SensorModel::vlp16();
  const auto scene = sim::SimpleScene::demo();
  const auto rendered = sim::render(model, scene);
  segmentation::Segmenter segmenter{core::SegmentationConfig{}};
  std::vector<std::uint8_t> labels;
  segmenter.segment(rendered.scan, labels);
  Detector detector{DetectionConfig{}};
  const auto& d = detector.detect(rendered.scan, labels, core::Pose{});
  const auto who = majority_labels(d, rendered.labels);
  std::multiset<std::uint32_t> people;
  for (std::size_t k = 0; k < d.size(); ++k) {
    if (who[k] != 0) people.insert(who[k]);
    EXPECT_LT(std::hypot(d[k].centroid.x(), d[k].centroid.y()), 11.0f) << "a piece of the wall";
  }
  EXPECT_EQ(people, (std::multiset<std::uint32_t>{1, 2, 3, 4, 5}));
}

}  // namespace
}  // namespace ringtrack::detection
