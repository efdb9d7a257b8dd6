// Completion of detections along their columns (detection/completion.hpp): a person whose legs
// the segmentation missed gets them back, the ground at the feet and the wall below a patch never
// join, and the fast walk agrees with a fixpoint reference on random scenes.

#include "ringtrack/detection/completion.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <set>

#include "ringtrack/detection/detector.hpp"
#include "ringtrack/sim/simple_scene.hpp"

namespace ringtrack::detection {
namespace {

constexpr double kGroundZ = -1.8;  // VLP-16 1.8 m above the ground
constexpr double kDeg = std::numbers::pi / 180.0;

struct Scene {
  sim::RenderedScan rendered;
  std::vector<std::uint8_t> labels;  // segment labels the detector sees
};

// Renders `scene` and marks as segment points only the object cells at least `visible_from_m`
// above the ground: the segmentation missed everything below (the legs).
Scene render_upper_bodies(const sim::SimpleScene& scene, double visible_from_m) {
  Scene out{sim::render(core::SensorModel::vlp16(), scene), {}};
  const auto& scan = out.rendered.scan;
  out.labels.assign(scan.size(), 0);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (out.rendered.labels[i] != 0 && scan.valid(i) &&
        scan.point(i).z() >= kGroundZ + visible_from_m) {
      out.labels[i] = kSegmentLabel;
    }
  }
  return out;
}

// Mean of the points of the cells labelled `id` (the evaluation's ground truth).
Eigen::Vector3d true_centroid(const sim::RenderedScan& r, std::uint32_t id) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (std::size_t i = 0; i < r.labels.size(); ++i) {
    if (r.labels[i] == id && r.scan.valid(i)) {
      sum += r.scan.point(i).cast<double>();
      ++n;
    }
  }
  return sum / n;
}

sim::SimpleScene people_at(const std::vector<std::pair<double, double>>& range_azimuth_deg) {
  sim::SimpleScene scene;
  scene.ground_z_m = kGroundZ;
  scene.range_noise_m = 0.01;
  std::uint32_t id = 1;
  for (const auto& [range, az] : range_azimuth_deg) {
    scene.cylinders.push_back(sim::SimpleScene::person(
        range * std::cos(az * kDeg), range * std::sin(az * kDeg), kGroundZ, id++));
  }
  return scene;
}

// The fixpoint the walk must reach, computed the slow way: sweep every cell of the scan until
// no cell joins, detection after detection in order, each cell joining when a neighbour in the
// ring above or below (same column or one beside it) already belongs to the object and the
// documented conditions hold.
std::vector<std::vector<std::uint32_t>> reference_completion(
    const core::OrganizedScan& scan, const core::DetectionConfig& config,
    const std::vector<core::Detection>& detections) {
  const auto columns = static_cast<std::size_t>(scan.columns());
  std::vector<int> owner(scan.size(), -1);
  for (std::size_t d = 0; d < detections.size(); ++d) {
    for (const auto i : detections[d].indices) owner[i] = static_cast<int>(d);
  }
  auto world = [&](std::size_t i) -> Eigen::Vector3d { return scan.point(i).cast<double>(); };
  auto level = [&](std::size_t k, std::size_t j) {
    if (!scan.valid(k)) return false;
    const Eigen::Vector3d step = world(k) - world(j);
    return std::abs(step.z()) <= 0.03 + 0.0524 * std::min(1.0, step.head<2>().norm());
  };
  // On the ground: level with the cell below, or with a cell of its ring at the same range just
  // past the object's half width (+0.3 m) to the left or right.
  auto on_ground = [&](std::size_t j, double half_width) {
    if (j >= columns && level(j - columns, j)) return true;
    const double arc = scan.range_m(j) * 2.0 * std::numbers::pi / static_cast<double>(columns);
    const auto offset = static_cast<std::size_t>(1 + std::ceil((half_width + 0.3) / arc));
    if (offset >= columns / 2) return false;
    const std::size_t ring_start = j - j % columns;
    for (const std::size_t c :
         {(j % columns + columns - offset) % columns, (j % columns + offset) % columns}) {
      const std::size_t k = ring_start + c;
      if (level(k, j) && std::abs(scan.range_m(k) - scan.range_m(j)) <= config.complete_range_m) {
        return true;
      }
    }
    return false;
  };
  std::vector<std::vector<std::uint32_t>> out(detections.size());
  for (std::size_t d = 0; d < detections.size(); ++d) {
    const auto& det = detections[d];
    const double m = config.complete_margin_m;
    const double half_width = 0.5 * (det.box.max - det.box.min).head<2>().norm();
    std::set<std::size_t> members(det.indices.begin(), det.indices.end());
    std::set<std::size_t> added;
    for (bool changed = true; changed;) {
      changed = false;
      for (std::size_t j = 0; j < scan.size(); ++j) {
        if (owner[j] != -1 || !scan.valid(j)) continue;
        const Eigen::Vector3d w = world(j);
        if (w.x() < det.box.min.x() - m || w.x() > det.box.max.x() + m ||
            w.y() < det.box.min.y() - m || w.y() > det.box.max.y() + m ||
            w.z() > det.box.max.z() + m) {
          continue;
        }
        bool joined = false;
        for (const bool j_below : {true, false}) {
          for (const long dc : {-1L, 0L, 1L}) {
            if (joined) break;
            if ((j_below && j + columns >= scan.size()) || (!j_below && j < columns)) continue;
            const std::size_t ring_start = (j_below ? j + columns : j - columns) - j % columns;
            const auto c = static_cast<std::size_t>(
                (static_cast<long>(j % columns) + dc + static_cast<long>(columns)) %
                static_cast<long>(columns));
            const std::size_t i = ring_start + c;
            if (!members.count(i)) continue;
            if (std::abs(scan.range_m(j) - scan.range_m(i)) > config.complete_range_m) continue;
            const Eigen::Vector3d step = w - world(i);
            if (std::abs(step.z()) < step.head<2>().norm()) continue;
            if (j_below && on_ground(j, half_width)) continue;
            members.insert(j);
            added.insert(j);
            owner[j] = static_cast<int>(d);
            changed = true;
            joined = true;
          }
        }
      }
    }
    double low = det.box.min.z(), high = det.box.max.z();
    for (const auto j : added) {
      low = std::min(low, world(j).z());
      high = std::max(high, world(j).z());
    }
    if (high - low > config.max_height_m) {
      for (const auto j : added) owner[j] = -1;
      added.clear();
    }
    out[d].assign(added.begin(), added.end());
  }
  return out;
}

TEST(DetectionCompleter, PeopleGetTheirLegsBackButNotTheGround) {
  const auto scene = people_at({{4.0, 10.0}, {7.0, 80.0}, {10.0, 170.0}, {14.0, 250.0}});
  const Scene s = render_upper_bodies(scene, 0.9);
  Detector detector{core::DetectionConfig{}};
  const auto detections = detector.detect(s.rendered.scan, s.labels, core::Pose{});
  ASSERT_EQ(detections.size(), 4u);
  DetectionCompleter completer{core::DetectionConfig{}};
  const auto& completed = completer.complete(s.rendered.scan, core::Pose{}, detections);
  ASSERT_EQ(completed.size(), detections.size());
  for (std::size_t d = 0; d < completed.size(); ++d) {
    const auto& c = completed[d];
    EXPECT_EQ(c.indices, detections[d].indices);  // the detector's cells and shape stay
    EXPECT_EQ(c.centroid, detections[d].centroid);
    ASSERT_FALSE(c.completion.empty()) << "detection " << d;
    const std::uint32_t id = s.rendered.labels[c.indices.front()];
    std::size_t legs = 0;
    for (std::size_t i = 0; i < s.rendered.labels.size(); ++i) {
      legs += s.rendered.labels[i] == id && s.labels[i] == 0 && s.rendered.scan.valid(i) ? 1 : 0;
    }
    for (const auto j : c.completion) {
      EXPECT_EQ(s.rendered.labels[j], id) << "detection " << d << " took cell " << j;
    }
    // Every leg cell but those on the ground-level feet joins.
    EXPECT_GE(c.completion.size() * 10, legs * 8)
        << "person " << id << ": " << c.completion.size() << " of " << legs << " leg cells";
    const Eigen::Vector3d truth = true_centroid(s.rendered, id);
    const double before = (c.centroid.cast<double>() - truth).norm();
    const double after = (c.object_centroid().cast<double>() - truth).norm();
    EXPECT_LT(after, 0.05) << "person " << id;
    EXPECT_LT(after, 0.5 * before) << "person " << id;
  }
}

TEST(DetectionCompleter, AWallPatchIsNotDescendedAndCellsOfOthersAreNeverTaken) {
  sim::SimpleScene scene;
  scene.ground_z_m = kGroundZ;
  scene.wall_radius_m = 6.0;
  auto rendered = sim::render(core::SensorModel::vlp16(), scene);
  const auto& scan = rendered.scan;
  // A 1.4 m high patch of the wall a few columns wide, as a wall edge's segment would be.
  std::vector<std::uint8_t> labels(scan.size(), 0);
  for (int ring = 0; ring < scan.rings(); ++ring) {
    for (int column = 100; column < 106; ++column) {
      const std::size_t i = scan.index(ring, column);
      const float z = scan.point(i).z();
      if (scan.valid(i) && z > -0.5f && z < 0.9f) labels[i] = kSegmentLabel;
    }
  }
  Detector detector{core::DetectionConfig{}};
  const auto detections = detector.detect(scan, labels, core::Pose{});
  ASSERT_EQ(detections.size(), 1u);
  DetectionCompleter completer{core::DetectionConfig{}};
  // The wall below the patch continues beside it at the same height and range: a surface wider
  // than the object, so the walk does not descend it (and were it let down to the ground, the
  // completed patch would be taller than a person and keep nothing).
  const auto& wall = completer.complete(scan, core::Pose{}, detections).front();
  for (const auto j : wall.completion) {
    EXPECT_GE(scan.point(j).z(), wall.box.min.z() - 1e-4f) << "cell " << j << " below the patch";
  }

  // Two detections in the same columns, one above the other: neither takes the other's cells.
  const Scene s = render_upper_bodies(people_at({{8.0, 30.0}}), 0.9);
  auto parts = detector.detect(s.rendered.scan, s.labels, core::Pose{});
  ASSERT_EQ(parts.size(), 1u);
  core::Detection legs = parts.front();
  legs.indices.clear();
  for (std::size_t i = 0; i < s.rendered.labels.size(); ++i) {
    if (s.rendered.labels[i] == 1 && s.labels[i] == 0 && s.rendered.scan.valid(i)) {
      legs.indices.push_back(static_cast<std::uint32_t>(i));
    }
  }
  parts.push_back(legs);
  const auto& both = completer.complete(s.rendered.scan, core::Pose{}, parts);
  for (const auto j : both[0].completion) {
    EXPECT_FALSE(std::binary_search(legs.indices.begin(), legs.indices.end(), j));
  }
}

TEST(DetectionCompleter, OffLeavesTheDetectionsAsTheyAre) {
  const Scene s = render_upper_bodies(people_at({{6.0, 0.0}}), 0.9);
  Detector detector{core::DetectionConfig{}};
  const auto detections = detector.detect(s.rendered.scan, s.labels, core::Pose{});
  core::DetectionConfig off;
  off.complete_range_m = 0.0;
  DetectionCompleter completer{off};
  const auto& out = completer.complete(s.rendered.scan, core::Pose{}, detections);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_TRUE(out.front().completion.empty());
  EXPECT_EQ(out.front().object_centroid(), detections.front().centroid);
}

TEST(DetectionCompleter, MatchesTheFixpointReferenceOnRandomScenes) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> range(3.0, 25.0), azimuth(0.0, 360.0), cut(0.3, 1.2);
  DetectionCompleter completer{core::DetectionConfig{}};
  Detector detector{core::DetectionConfig{}};
  std::size_t compared = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<std::pair<double, double>> people;
    for (int k = 0; k < 6; ++k) people.emplace_back(range(rng), azimuth(rng));
    sim::SimpleScene scene = people_at(people);
    scene.seed = static_cast<std::uint64_t>(trial + 1);
    scene.range_noise_m = 0.03;
    const Scene s = render_upper_bodies(scene, cut(rng));
    const auto detections = detector.detect(s.rendered.scan, s.labels, core::Pose{});
    const auto& fast = completer.complete(s.rendered.scan, core::Pose{}, detections);
    const auto slow = reference_completion(s.rendered.scan, core::DetectionConfig{}, detections);
    ASSERT_EQ(fast.size(), slow.size());
    for (std::size_t d = 0; d < fast.size(); ++d) {
      EXPECT_EQ(fast[d].completion, slow[d]) << "trial " << trial << ", detection " << d;
      compared += slow[d].size();
    }
  }
  EXPECT_GT(compared, 100u) << "the scenes must exercise the completion";
}

}  // namespace
}  // namespace ringtrack::detection
