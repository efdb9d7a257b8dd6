// Dynamic-object filter and static map on hand-built scans: a ring of wall points, people as
// columns of points, detections taken straight from the known labels, the real tracker between.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <tuple>

#include "ringtrack/core/error.hpp"
#include "ringtrack/mapping/dynamic_object_filter.hpp"
#include "ringtrack/mapping/static_map.hpp"
#include "ringtrack/tracking/tracker.hpp"
#include "support/map_points.hpp"
#include "support/scripted_detections.hpp"

namespace ringtrack::mapping {
namespace {

constexpr int kRings = 8;
constexpr int kColumns = 720;
constexpr double kWallRadius = 10.0;
constexpr double kGroundZ = -1.5;  // world frame: people stand here
constexpr double kPersonRadius = 0.25;
constexpr double kPersonHeight = 1.75;

struct Person {
  double x, y;
  std::uint32_t label;
};

// A rendered scan with the label of each cell (0 = wall).
struct Frame {
  core::OrganizedScan scan;
  std::vector<std::uint32_t> labels;
  core::Pose pose;
};

// The sensor at pose looks along horizontal rays (one per column) at heights
// kGroundZ + 0.25 * ring in the world frame; each ray hits the nearest person cylinder or the
// wall, a circle of kWallRadius around the world origin.
Frame render(const std::vector<Person>& people, const core::Pose& pose) {
  Frame f{core::OrganizedScan(kRings, kColumns), std::vector<std::uint32_t>(kRings * kColumns, 0),
          pose};
  f.scan.stamp_ns = pose.stamp_ns;
  const Eigen::Isometry3d world_from_sensor = pose.isometry();
  const Eigen::Isometry3d sensor_from_world = world_from_sensor.inverse();
  const Eigen::Vector2d o = world_from_sensor.translation().head<2>();
  for (int c = 0; c < kColumns; ++c) {
    const double az = 2.0 * std::numbers::pi * c / kColumns;
    const Eigen::Vector2d dir(std::cos(az), std::sin(az));  // world-frame direction
    // Wall: |o + t dir| = R.
    const double b = o.dot(dir);
    double best = -b + std::sqrt(b * b - (o.squaredNorm() - kWallRadius * kWallRadius));
    std::uint32_t label = 0;
    for (const auto& p : people) {
      const Eigen::Vector2d d = o - Eigen::Vector2d(p.x, p.y);
      const double bb = d.dot(dir);
      const double disc = bb * bb - (d.squaredNorm() - kPersonRadius * kPersonRadius);
      if (disc < 0) continue;
      const double t = -bb - std::sqrt(disc);
      if (t > 0 && t < best) {
        best = t;
        label = p.label;
      }
    }
    for (int r = 0; r < kRings; ++r) {
      const double z = kGroundZ + 0.25 * r;
      const bool on_person = label != 0 && z <= kGroundZ + kPersonHeight;
      double t = best;
      if (label != 0 && !on_person) {
        // Above the person's head: the ray continues to the wall.
        t = -b + std::sqrt(b * b - (o.squaredNorm() - kWallRadius * kWallRadius));
      }
      const Eigen::Vector3d world(o.x() + t * dir.x(), o.y() + t * dir.y(), z);
      const Eigen::Vector3d local = sensor_from_world * world;
      f.scan.set_return(r, c, static_cast<float>(local.norm()), on_person ? 80.0f : 20.0f,
                        local.cast<float>());
      f.labels[f.scan.index(r, c)] = on_person ? label : 0;
    }
  }
  return f;
}

// One detection per listed label, straight from the labels (world frame).
std::vector<core::Detection> detect(const Frame& f, const std::vector<std::uint32_t>& wanted) {
  std::vector<core::Detection> out;
  for (const auto label : wanted) {
    core::Detection d;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    Eigen::Matrix3d sum2 = Eigen::Matrix3d::Zero();
    for (std::size_t i = 0; i < f.labels.size(); ++i) {
      if (f.labels[i] != label) continue;
      const Eigen::Vector3f p = f.pose.to_world(f.scan.point(i));
      d.indices.push_back(static_cast<std::uint32_t>(i));
      d.box.extend(p);
      sum += p.cast<double>();
      sum2 += p.cast<double>() * p.cast<double>().transpose();
    }
    if (d.indices.empty()) continue;
    const double n = static_cast<double>(d.indices.size());
    const Eigen::Vector3d mean = sum / n;
    d.centroid = mean.cast<float>();
    Eigen::Matrix3d cov = sum2 / n - mean * mean.transpose();
    cov.diagonal() = cov.diagonal().cwiseMax(0.03 * 0.03);
    d.covariance = cov.cast<float>();
    out.push_back(std::move(d));
  }
  return out;
}

// detect() without the cells `missed(cell, world point)` says the segmentation left out; each
// box is made anew from the cells kept (centroid and covariance stay the whole object's).
template <class Missed>
std::vector<core::Detection> detect_without(const Frame& f,
                                            const std::vector<std::uint32_t>& wanted,
                                            Missed missed) {
  auto detections = detect(f, wanted);
  for (auto& d : detections) {
    std::erase_if(d.indices,
                  [&](std::uint32_t i) { return missed(i, f.pose.to_world(f.scan.point(i))); });
    d.box = {};
    for (const auto i : d.indices) d.box.extend(f.pose.to_world(f.scan.point(i)));
  }
  return detections;
}

core::Pose sensor_pose(int k) {
  core::Pose p;
  p.stamp_ns = testing::scan_stamp_ns(k);
  p.translation = Eigen::Vector3d(1.0, -0.5, 0.0);
  p.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  return p;
}

// Map points inside an upright cylinder (world frame), above the ground.
int map_points_in_cylinder(const StaticMap& map, double x, double y, double radius) {
  int n = 0;
  map.for_each([&](const MapPoint& p) {
    if (std::hypot(p.position.x() - x, p.position.y() - y) < radius &&
        p.position.z() > kGroundZ - 0.01)
      ++n;
  });
  return n;
}

// Runs a script: positions of each person per scan, and which labels are detected.
struct ScriptRun {
  explicit ScriptRun(core::MappingConfig mapping = {})
      : tracker(core::TrackingConfig{}), filter(mapping) {}
  const FilterResult& step(const std::vector<Person>& people,
                           const std::vector<std::uint32_t>& detected) {
    frame = render(people, sensor_pose(k));
    detections = detect(frame, detected);
    const auto& hypotheses = tracker.update(detections, frame.pose.stamp_ns);
    ++k;
    return filter.process(frame.scan, frame.pose, detections, hypotheses);
  }
  tracking::Tracker tracker;
  DynamicObjectFilter filter;
  Frame frame;
  std::vector<core::Detection> detections;
  int k{0};
};

TEST(StaticMap, AveragesPerVoxelAndRemovesInsideBoxes) {
  StaticMap map(0.5);
  map.insert({0.1f, 0.1f, 0.1f}, 10.0f);
  map.insert({0.3f, 0.3f, 0.3f}, 20.0f);  // same voxel
  map.insert({-0.1f, 0.1f, 0.1f}, 5.0f);  // x < 0: next voxel
  map.insert({std::nanf(""), 0, 0}, 1.0f);
  map.insert({1e9f, 0, 0}, 1.0f);
  EXPECT_EQ(map.size(), 2u);
  EXPECT_EQ(map.dropped_points(), 2u);
  const auto pts = map.points();
  ASSERT_EQ(pts.size(), 2u);
  bool found = false;
  for (const auto& p : pts) {
    if (p.count == 2) {
      found = true;
      EXPECT_TRUE(p.position.isApprox(Eigen::Vector3f(0.2f, 0.2f, 0.2f)));
      EXPECT_FLOAT_EQ(p.intensity, 15.0f);
    }
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(map.remove_inside({{0.0f, 0.0f, 0.0f}, {0.25f, 0.25f, 0.25f}}), 1u);
  EXPECT_EQ(map.size(), 1u);
}

TEST(StaticMap, MatchesANaiveMapUnderRandomInsertsAndRemovals) {
  // Reference: std::map keyed by the voxel index triple with plain sums.
  StaticMap map(0.2);
  std::map<std::tuple<long, long, long>, std::pair<Eigen::Vector3d, int>> reference;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<float> u(-3.0f, 3.0f);
  for (int round = 0; round < 20; ++round) {
    for (int i = 0; i < 2000; ++i) {
      const Eigen::Vector3f p(u(rng), u(rng), u(rng) * 0.3f);
      map.insert(p, 1.0f);
      const auto key = std::make_tuple(std::lround(std::floor(p.x() / 0.2f)),
                                       std::lround(std::floor(p.y() / 0.2f)),
                                       std::lround(std::floor(p.z() / 0.2f)));
      auto& r = reference.try_emplace(key, Eigen::Vector3d::Zero(), 0).first->second;
      r.first += p.cast<double>();
      ++r.second;
    }
    const Eigen::Vector3f c(u(rng), u(rng), 0.0f);
    const core::Box3 box{c.array() - 0.7f, c.array() + 0.7f};
    const std::size_t removed = map.remove_inside(box);
    std::size_t expected = 0;
    for (auto it = reference.begin(); it != reference.end();) {
      if (box.contains((it->second.first / it->second.second).cast<float>())) {
        it = reference.erase(it);
        ++expected;
      } else {
        ++it;
      }
    }
    EXPECT_EQ(removed, expected);
    ASSERT_EQ(map.size(), reference.size());
  }
  const auto pts = map.points();
  std::size_t matched = 0;
  for (const auto& p : pts) {
    const auto key = std::make_tuple(std::lround(std::floor(p.position.x() / 0.2f)),
                                     std::lround(std::floor(p.position.y() / 0.2f)),
                                     std::lround(std::floor(p.position.z() / 0.2f)));
    const auto it = reference.find(key);
    if (it == reference.end()) continue;
    EXPECT_EQ(static_cast<int>(p.count), it->second.second);
    EXPECT_TRUE(p.position.isApprox((it->second.first / it->second.second).cast<float>(), 1e-4f));
    ++matched;
  }
  EXPECT_EQ(matched, reference.size());
}

TEST(StaticMap, SettledCellHintsDoNotChangeTheMap) {
  // The same scans inserted point by point and in batches with per-cell hints, with removals
  // in between (which invalidate the hints), give identical maps.
  StaticMap plain(0.1), hinted(0.1);
  SettledCells settled;
  std::mt19937_64 rng(5);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  const int cells = 3000;
  for (int scan = 0; scan < 150; ++scan) {
    std::vector<Eigen::Vector3f> points;
    std::vector<float> intensities;
    std::vector<std::uint32_t> cell_ids;
    std::vector<std::uint8_t> skip;
    for (int c = 0; c < cells; ++c) {
      if (c % 7 == scan % 7) continue;  // some cells invalid in each scan
      const float a = static_cast<float>(c) * 0.002f;
      points.emplace_back(5.0f * std::cos(a) + noise(rng), 5.0f * std::sin(a) + noise(rng),
                          static_cast<float>(c % 16) * 0.1f + noise(rng));
      intensities.push_back(static_cast<float>(c % 100));
      cell_ids.push_back(static_cast<std::uint32_t>(c));
      skip.push_back(c % 11 == 0 ? 1 : 0);
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (!skip[i]) plain.insert(points[i], intensities[i]);
    }
    hinted.insert(points, intensities, skip, cell_ids, settled);
    if (scan % 40 == 39) {
      const core::Box3 box{{4.0f, 0.0f, -1.0f}, {6.0f, 2.0f, 1.0f}};
      EXPECT_EQ(plain.remove_inside(box), hinted.remove_inside(box));
    }
  }
  const auto a = plain.points(), b = hinted.points();
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].count, b[i].count);
    EXPECT_EQ(a[i].position, b[i].position);
    EXPECT_EQ(a[i].intensity, b[i].intensity);
  }
  // Many voxels settled, so the hinted path skipped points.
  EXPECT_GT(std::count_if(a.begin(), a.end(),
                          [](const MapPoint& p) { return p.count == StaticMap::kSettledCount; }),
            100);
}

TEST(DynamicObjectFilter, WalkingPersonLeavesNoPointsInTheMap) {
  ScriptRun run;
  const Person standing{-3.0, -5.0, 2};
  std::size_t removed_total = 0;
  for (int k = 0; k < 80; ++k) {
    const Person walker{-4.0 + 0.1 * k, 5.0, 1};  // 1 m/s across the scene
    const auto& r = run.step({walker, standing}, {1, 2});
    removed_total += r.removed_cells.size();
  }
  run.filter.flush();
  EXPECT_GT(removed_total, 0u);
  // Nothing left along the walker's path (x from -4 to 3.9 at y = 5)...
  for (double x = -4.0; x <= 3.9; x += 0.1) {
    EXPECT_EQ(map_points_in_cylinder(run.filter.map(), x, 5.0, kPersonRadius + 0.05), 0)
        << "x " << x;
  }
  // ...while the standing person and the wall stay.
  EXPECT_GT(map_points_in_cylinder(run.filter.map(), -3.0, -5.0, kPersonRadius + 0.05), 10);
  EXPECT_GT(run.filter.map().size(), 1000u);
}

TEST(DynamicObjectFilter, StandingThenWalkingIsRemovedRetroactively) {
  for (const int delay : {50, 10}) {  // 10: the standing scans are already in the map
    core::MappingConfig mapping;
    mapping.log_delay_scans = delay;
    ScriptRun run(mapping);
    std::size_t retro = 0, map_removed = 0;
    for (int k = 0; k < 70; ++k) {
      const double x = k < 30 ? 2.0 : 2.0 + 0.1 * (k - 30);  // stands 3 s, then walks
      const auto& r = run.step({{x, 3.0, 1}}, {1});
      retro += r.retroactive_points;
      map_removed += r.map_voxels_removed;
    }
    run.filter.flush();
    ASSERT_EQ(run.tracker.hypotheses().size(), 1u);
    EXPECT_TRUE(run.tracker.hypotheses().front().ever_dynamic);
    EXPECT_EQ(map_points_in_cylinder(run.filter.map(), 2.0, 3.0, kPersonRadius + 0.05), 0)
        << "delay " << delay;
    EXPECT_GT(retro, 0u) << "delay " << delay;
    if (delay == 10) {
      EXPECT_GT(map_removed, 0u);
    }
  }
}

// mapping.remove: a person who stands all along stays in the map under the paper's rule and
// leaves it, from the first scan on, when people or confirmed tracks are removed too; a walker
// leaves it under every rule.
TEST(DynamicObjectFilter, RemoveRuleDecidesWhetherAStandingPersonStays) {
  for (const auto rule : {core::RemovedObjects::kDynamic, core::RemovedObjects::kPerson,
                          core::RemovedObjects::kConfirmed}) {
    core::MappingConfig mapping;
    mapping.remove = rule;
    mapping.log_delay_scans = 10;  // the first scans reach the map before the flag is set
    ScriptRun run(mapping);
    for (int k = 0; k < 60; ++k) run.step({{2.0, 3.0, 1}, {-4.0 + 0.1 * k, -3.0, 2}}, {1, 2});
    run.filter.flush();
    const auto& hs = run.tracker.hypotheses();
    ASSERT_EQ(hs.size(), 2u);
    const auto standing =
        std::find_if(hs.begin(), hs.end(), [](const auto& h) { return !h.ever_dynamic; });
    ASSERT_NE(standing, hs.end());
    ASSERT_TRUE(standing->person && standing->confirmed);
    const int kept = map_points_in_cylinder(run.filter.map(), 2.0, 3.0, kPersonRadius + 0.05);
    if (rule == core::RemovedObjects::kDynamic) {
      EXPECT_GT(kept, 10);
    } else {
      EXPECT_EQ(kept, 0) << static_cast<int>(rule);
    }
    EXPECT_EQ(map_points_in_cylinder(run.filter.map(), 0.0, -3.0, kPersonRadius + 0.05), 0);
  }
}

TEST(DynamicObjectFilter, LostAndRecoveredDynamicObjectIsRemovedInTheGap) {
  ScriptRun run;
  for (int k = 0; k < 60; ++k) {
    const Person walker{-3.0 + 0.1 * k, 4.0, 1};
    // The detector misses the walker for 0.5 s although its points are in the scans.
    const bool missed = k >= 30 && k < 35;
    const auto& r =
        run.step({walker}, missed ? std::vector<std::uint32_t>{} : std::vector<std::uint32_t>{1});
    if (missed) {
      EXPECT_TRUE(r.removed_cells.empty());
    }
  }
  run.filter.flush();
  ASSERT_EQ(run.tracker.hypotheses().size(), 1u);
  for (int k = 28; k < 37; ++k) {
    EXPECT_EQ(map_points_in_cylinder(run.filter.map(), -3.0 + 0.1 * k, 4.0, kPersonRadius + 0.05),
              0)
        << "k " << k;
  }
}

TEST(DynamicObjectFilter, RemovedCellsAreTheDynamicDetections) {
  ScriptRun run;
  for (int k = 0; k < 20; ++k) {
    const auto& r = run.step({{-2.0 + 0.1 * k, -2.0, 1}, {3.0, 3.0, 2}}, {1, 2});
    const auto& hs = run.tracker.hypotheses();
    std::vector<std::uint32_t> expected;
    for (const auto& h : hs) {
      if (h.ever_dynamic && h.detection >= 0) expected = run.detections[h.detection].indices;
    }
    auto got = r.removed_cells;
    std::sort(got.begin(), got.end());
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(got, expected) << "scan " << k;
  }
}

// A walker whose detection misses its top rings (its head): the grown box removes them from the
// scan, and only them; without the margin they stay.
std::size_t head_cells_kept(double object_margin_m) {
  core::MappingConfig mapping;
  mapping.object_margin_m = object_margin_m;
  tracking::Tracker tracker{core::TrackingConfig{}};
  DynamicObjectFilter filter(mapping);
  // The top ring (rings are 0.25 m apart here: the person's top ring lies 0.25 m above the
  // detection's).
  const float cut_z = static_cast<float>(kGroundZ + kPersonHeight - 0.1);
  std::size_t kept = 0;
  for (int k = 0; k < 40; ++k) {
    const Frame frame = render({{-2.0 + 0.1 * k, -2.0, 1}}, sensor_pose(k));
    std::vector<std::uint32_t> head;
    auto detections = detect_without(frame, {1}, [&](std::uint32_t i, const Eigen::Vector3f& p) {
      const bool is_head = p.z() > cut_z;
      if (is_head) head.push_back(i);
      return is_head;
    });
    const auto& hypotheses = tracker.update(detections, frame.pose.stamp_ns);
    const auto& r = filter.process(frame.scan, frame.pose, detections, hypotheses);
    if (hypotheses.empty() || !hypotheses.front().ever_dynamic) continue;
    // The removed cells are the detection's and the head's, nothing else (no wall, no ground).
    std::vector<std::uint32_t> expected = detections.front().indices;
    std::vector<std::uint32_t> head_removed;
    for (const auto c : head) {
      if (std::find(r.removed_cells.begin(), r.removed_cells.end(), c) != r.removed_cells.end()) {
        head_removed.push_back(c);
      }
    }
    kept += head.size() - head_removed.size();
    expected.insert(expected.end(), head_removed.begin(), head_removed.end());
    auto got = r.removed_cells;
    std::sort(got.begin(), got.end());
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(got, expected) << "scan " << k;
    EXPECT_EQ(r.object_box_points, head_removed.size()) << "scan " << k;
  }
  return kept;
}

TEST(DynamicObjectFilter, GrownObjectBoxRemovesTheUnclusteredHead) {
  EXPECT_EQ(head_cells_kept(0.3), 0u);
  EXPECT_GT(head_cells_kept(0.2), 20u);  // a ring spacing above the margin: out of reach
  EXPECT_GT(head_cells_kept(0.0), 20u);
}

// A walker whose detection holds only its middle rings (the segmentation left the legs to the
// ground and cut the head off): the grown box reaches down to object_ground_clearance_m above
// the lowest point around it (here the feet's ring, standing in for the ground, which stays) and
// up to object_min_height_m above it. Returns, over the scans in which the walker was dynamic,
// how many of its cells below and above the detection were kept, and whether any wall cell went.
struct OutsideKept {
  std::size_t below{0};
  std::size_t above{0};
  std::size_t lowest_removed{0};
  std::size_t walls_removed{0};
};
OutsideKept cells_outside_the_cluster(double clearance_m, double min_height_m) {
  core::MappingConfig mapping;
  mapping.object_ground_clearance_m = clearance_m;
  mapping.object_min_height_m = min_height_m;
  tracking::Tracker tracker{core::TrackingConfig{}};
  DynamicObjectFilter filter(mapping);
  const double low = kGroundZ + 0.7;   // rings 0-2 (the lowest at kGroundZ) below the cluster
  const double high = kGroundZ + 1.3;  // rings 6-7 above the cluster and its 0.2 m margin
  OutsideKept out;
  for (int k = 0; k < 40; ++k) {
    const Frame frame = render({{-2.0 + 0.1 * k, -2.0, 1}}, sensor_pose(k));
    std::vector<std::uint32_t> below, above, lowest;
    auto detections = detect_without(frame, {1}, [&](std::uint32_t i, const Eigen::Vector3f& p) {
      const double z = p.z();
      if (z < kGroundZ + 0.01) lowest.push_back(i);
      if (z < low) below.push_back(i);
      if (z > high) above.push_back(i);
      return z < low || z > high;
    });
    const auto& hypotheses = tracker.update(detections, frame.pose.stamp_ns);
    const auto& r = filter.process(frame.scan, frame.pose, detections, hypotheses);
    if (hypotheses.empty() || !hypotheses.front().ever_dynamic) continue;
    const std::set<std::uint32_t> removed(r.removed_cells.begin(), r.removed_cells.end());
    for (const auto c : below) out.below += removed.count(c) == 0 ? 1 : 0;
    for (const auto c : above) out.above += removed.count(c) == 0 ? 1 : 0;
    for (const auto c : lowest) out.lowest_removed += removed.count(c);
    for (const auto c : removed) out.walls_removed += frame.labels[c] == 0 ? 1 : 0;
  }
  return out;
}

TEST(DynamicObjectFilter, GrownObjectBoxReachesDownToTheGroundAndUpToABodysHeight) {
  const OutsideKept off = cells_outside_the_cluster(0.0, 0.0);
  ASSERT_GT(off.below, 40u) << "without the keys the legs below the cluster stay";
  ASSERT_GT(off.above, 20u) << "and the head above its margin";
  const OutsideKept on = cells_outside_the_cluster(0.1, 2.0);
  EXPECT_EQ(on.walls_removed, 0u);
  EXPECT_EQ(on.above, 0u);
  EXPECT_EQ(on.lowest_removed, 0u) << "the lowest point around is the ground: it stays";
  // Of the cells below, only the lowest ring stays (one per scan and column that hit the walker).
  EXPECT_LT(on.below, off.below / 2);
  const OutsideKept down_only = cells_outside_the_cluster(0.1, 0.0);
  EXPECT_EQ(down_only.below, on.below);
  EXPECT_EQ(down_only.above, off.above);
}

// The same walker standing for its first 15 scans (its static era) before it walks: when it
// turns dynamic, the retroactive boxes of those scans (still in the log) reach the legs below
// and the head above the cluster too. Returns the walker's points left in the static-era scans
// after the log was flushed, but for its lowest ring (the ground here).
std::size_t static_era_points_kept(double clearance_m, double min_height_m) {
  core::MappingConfig mapping;
  mapping.object_ground_clearance_m = clearance_m;
  mapping.object_min_height_m = min_height_m;
  mapping.free_space = false;  // the boxes alone
  tracking::Tracker tracker{core::TrackingConfig{}};
  DynamicObjectFilter filter(mapping);
  constexpr int kStanding = 15;
  std::map<std::uint64_t, std::vector<std::uint32_t>> labels;  // per sequence
  std::size_t kept = 0;
  const auto count = [&](const std::vector<LoggedScan>& released) {
    for (const LoggedScan& scan : released) {
      if (scan.sequence >= kStanding) continue;
      for (std::size_t i = 0; i < scan.points.size(); ++i) {
        const bool walker = labels[scan.sequence][scan.cells[i]] == 1;
        const bool lowest = scan.points[i].z() < kGroundZ + 0.01;
        if (walker && !lowest && !scan.removed[i]) ++kept;
      }
    }
  };
  for (int k = 0; k < 60; ++k) {
    const double x = -2.0 + 0.1 * std::max(0, k - kStanding);
    const Frame frame = render({{x, -2.0, 1}}, sensor_pose(k));
    labels[static_cast<std::uint64_t>(k)] = frame.labels;
    auto detections = detect_without(frame, {1}, [](std::uint32_t, const Eigen::Vector3f& p) {
      const double z = p.z();
      return z < kGroundZ + 0.7 || z > kGroundZ + 1.3;
    });
    const auto& hypotheses = tracker.update(detections, frame.pose.stamp_ns);
    filter.process(frame.scan, frame.pose, detections, hypotheses);
    count(filter.released());
  }
  filter.flush();
  count(filter.released());
  return kept;
}

TEST(DynamicObjectFilter, StaticEraBoxesReachTheLegsAndTheHeadToo) {
  const std::size_t off = static_era_points_kept(0.0, 0.0);
  ASSERT_GT(off, 100u) << "without the keys the legs and the head of the standing scans stay";
  EXPECT_EQ(static_era_points_kept(0.1, 2.0), 0u);
}

// A walker beside the wall whose detection holds only the half of its points nearer the wall's
// side of its path: the rest lie up to a body's radius beside the box. Between object_margin_m
// (0.2 m) and object_outer_margin_m (0.3 m) the walker's points leave, and the wall's stay when
// the map has seen them often (free_space_protect_count). Counts over the scans in which the
// walker was dynamic: its points kept in that ring, and the wall's points in it removed.
struct OuterRing {
  std::size_t walker_kept{0};
  std::size_t walls_in_ring{0};
  std::size_t walls_removed{0};
};
OuterRing outer_ring(double outer_margin_m, int protect_count) {
  core::MappingConfig mapping;
  mapping.object_outer_margin_m = outer_margin_m;
  mapping.free_space_protect_count = protect_count;
  mapping.log_delay_scans = 2;  // the wall reaches the map early and is seen there often
  tracking::Tracker tracker{core::TrackingConfig{}};
  DynamicObjectFilter filter(mapping);
  OuterRing out;
  for (int k = 0; k < 60; ++k) {
    // Walking along y beside the wall (a circle of kWallRadius), its centre 0.27 m from it: the
    // sensor sees the near half of the body, so the box ends at the centre, the wall 0.27 m on.
    const double y = -3.0 + 0.1 * k;
    const double x = std::sqrt(kWallRadius * kWallRadius - y * y) - 0.27;
    const Frame frame = render({{x, y, 1}}, sensor_pose(k));
    std::vector<std::uint32_t> dropped;
    auto detections = detect_without(frame, {1}, [&](std::uint32_t i, const Eigen::Vector3f& p) {
      const bool behind = p.y() > y;
      if (behind) dropped.push_back(i);
      return behind;
    });
    const auto& hypotheses = tracker.update(detections, frame.pose.stamp_ns);
    const auto& r = filter.process(frame.scan, frame.pose, detections, hypotheses);
    if (hypotheses.empty() || !hypotheses.front().ever_dynamic || detections.empty()) continue;
    const std::set<std::uint32_t> removed(r.removed_cells.begin(), r.removed_cells.end());
    const core::Box3& box = detections.front().box;
    const auto in_ring = [&](const Eigen::Vector3f& p) {
      const float dx = std::max({box.min.x() - p.x(), p.x() - box.max.x(), 0.0f});
      const float dy = std::max({box.min.y() - p.y(), p.y() - box.max.y(), 0.0f});
      const float d = std::max(dx, dy);
      return d > 0.21f && d < 0.29f && p.z() >= box.min.z() && p.z() <= box.max.z();
    };
    for (const auto c : dropped) {
      if (in_ring(frame.pose.to_world(frame.scan.point(c))))
        out.walker_kept += removed.count(c) == 0;
    }
    for (std::size_t c = 0; c < frame.labels.size(); ++c) {
      if (frame.labels[c] != 0 || !in_ring(frame.pose.to_world(frame.scan.point(c)))) continue;
      ++out.walls_in_ring;
      out.walls_removed += removed.count(static_cast<std::uint32_t>(c));
    }
  }
  return out;
}

TEST(DynamicObjectFilter, OuterMarginTakesTheWalkerNotTheWallBesideIt) {
  const OuterRing off = outer_ring(0.2, 10);
  ASSERT_GT(off.walker_kept, 10u) << "at 0.2 m the walker's points beside the box stay";
  ASSERT_GT(off.walls_in_ring, 10u)
      << "the wall must come within the ring, or the test shows nothing";
  EXPECT_EQ(off.walls_removed, 0u);
  const OuterRing on = outer_ring(0.3, 10);
  EXPECT_EQ(on.walker_kept, 0u);
  EXPECT_EQ(on.walls_removed, 0u) << "the map has seen the wall often: it stays";
  const OuterRing unprotected = outer_ring(0.3, 1000000);
  EXPECT_GT(unprotected.walls_removed, 10u) << "without the map's protection the wall goes";
}

// The transient line (mapping.transient_scans): a walker nothing detects (too far, too sparse
// to track) whose cells the segmentation marks, beside a post it marks too, seen by a resting
// sensor for 100 scans. Returns the points of each left in the map above the feet, and the
// points the line removed.
struct TransientRun {
  int walker_kept{0};
  int post_kept{0};
  std::size_t removed{0};
};

TransientRun transient_run(const core::MappingConfig& mapping, bool ground_known) {
  DynamicObjectFilter filter(mapping);
  if (ground_known) filter.set_ground_z(kGroundZ);
  TransientRun out;
  constexpr int kScans = 100;
  for (int k = 0; k < kScans; ++k) {
    const Person walker{-4.0 + 0.1 * k, 5.0, 1};  // 1 m/s
    const Person post{-3.0, -5.0, 2};
    const Frame f = render({walker, post}, sensor_pose(k));
    std::vector<std::uint8_t> segments(f.labels.size());
    for (std::size_t i = 0; i < segments.size(); ++i) segments[i] = f.labels[i] != 0 ? 1 : 0;
    out.removed += filter.process(f.scan, f.pose, {}, {}, {nullptr, &segments}).transient_points;
  }
  out.removed += filter.flush().transient_points;
  // Above the feet (ring 0 lies on the ground) and along the path of the scans judged: the last
  // transient_scans scans have too few later ones and are left alone.
  const auto above_feet = [](const MapPoint& p) { return p.position.z() > kGroundZ + 0.2; };
  const double judged_x = -4.0 + 0.1 * (kScans - 1 - mapping.transient_scans) - kPersonRadius;
  filter.map().for_each([&](const MapPoint& p) {
    if (!above_feet(p)) return;
    // (The wall crosses y = 5 at x = -8.66, left of where the walker starts.)
    if (std::abs(p.position.y() - 5.0) < kPersonRadius + 0.05 &&
        p.position.x() > -4.0 - kPersonRadius - 0.05 && p.position.x() < judged_x) {
      ++out.walker_kept;
    }
    if (std::hypot(p.position.x() + 3.0, p.position.y() + 5.0) < kPersonRadius + 0.05) {
      ++out.post_kept;
    }
  });
  return out;
}

TEST(DynamicObjectFilter, TransientLineTakesAnUntrackedWalkerNotAPost) {
  core::MappingConfig off;
  off.transient_scans = 0;
  const TransientRun before = transient_run(off, true);
  ASSERT_GT(before.walker_kept, 100) << "without the line the walker stays in the map";
  EXPECT_EQ(before.removed, 0u);

  const core::MappingConfig defaults;
  ASSERT_EQ(defaults.transient_scans, 20);
  const TransientRun on = transient_run(defaults, true);
  EXPECT_EQ(on.walker_kept, 0);
  EXPECT_GT(on.removed, 500u);
  EXPECT_GT(on.post_kept, 10) << "what stands is segmented again and stays";
  EXPECT_EQ(on.post_kept, before.post_kept);

  // The ground decides what may be transient: without it the line is off, and points below
  // transient_min_height_m above it never count.
  EXPECT_EQ(transient_run(defaults, false).removed, 0u);
  core::MappingConfig high = defaults;
  high.transient_min_height_m = kPersonHeight + 0.1;
  EXPECT_EQ(transient_run(high, true).removed, 0u);
  // A log shorter than transient_scans never holds enough later scans to judge one.
  core::MappingConfig short_log = defaults;
  short_log.log_delay_scans = defaults.transient_scans - 1;
  EXPECT_EQ(transient_run(short_log, true).removed, 0u);
}

// lowest_in against a direct scan of the points, with and without the block bounds.
TEST(LoggedScan, LowestInMatchesADirectScan) {
  LoggedScan scan;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  for (int i = 0; i < 1000; ++i) {
    scan.points.emplace_back(u(rng), u(rng), u(rng) * 0.3f);
    scan.cells.push_back(static_cast<std::uint32_t>(i));
    scan.removed.push_back(0);
  }
  const float inf = std::numeric_limits<float>::infinity();
  for (int t = 0; t < 50; ++t) {
    const float x = u(rng), y = u(rng), z = u(rng) * 0.3f;
    const core::Box3 box{{x - 1.0f, y - 1.0f, -inf}, {x + 1.0f, y + 1.0f, z}};
    float expected = inf;
    for (const auto& p : scan.points) {
      if (box.contains(p)) expected = std::min(expected, p.z());
    }
    scan.block_bounds.clear();
    scan.bounded_points = 0;
    EXPECT_EQ(scan.lowest_in(box), expected) << "unbounded, box " << t;
    scan.update_bounds();
    EXPECT_EQ(scan.lowest_in(box), expected) << "bounded, box " << t;
  }
  EXPECT_EQ(scan.lowest_in({{100.0f, 100.0f, -inf}, {101.0f, 101.0f, 0.0f}}), inf);
}

TEST(DynamicObjectFilter, MemoryStaysBoundedOnALongStaticRun) {
  core::MappingConfig mapping;
  mapping.log_delay_scans = 30;
  ScriptRun run(mapping);
  std::size_t map_size = 0;
  for (int k = 0; k < 2000; ++k) {
    const auto& r = run.step({{3.0, 0.0, 1}, {-2.0, 4.0, 2}}, {1, 2});
    EXPECT_LE(run.filter.log().size(), 30u);
    if (k >= 30) {
      EXPECT_EQ(run.filter.log().size(), 30u);
      EXPECT_EQ(r.scans_to_map, 1u);
      ASSERT_EQ(run.filter.released().size(), 1u);
      EXPECT_EQ(run.filter.released().front().sequence, static_cast<std::uint64_t>(k - 30));
    }
    if (k == 40) map_size = run.filter.map().size();
    if (k > 40) {
      ASSERT_EQ(run.filter.map().size(), map_size) << "scan " << k;
    }
  }
  EXPECT_EQ(run.filter.tracked_objects(), 2u);
  EXPECT_GT(map_size, 0u);
  run.filter.flush();
  EXPECT_TRUE(run.filter.log().empty());
  EXPECT_EQ(run.filter.released().size(), 30u);
  EXPECT_EQ(run.filter.map().size(), map_size);
}

// A sensor driving straight along x at 0.5 m per scan, seeing rings of ground 2-16 m around it.
core::OrganizedScan ground_rings_scan(int k) {
  constexpr int kGroundColumns = 360;
  core::OrganizedScan scan(kRings, kGroundColumns);
  scan.stamp_ns = testing::scan_stamp_ns(k);
  for (int r = 0; r < kRings; ++r) {
    const double d = 2.0 + 2.0 * r;
    for (int c = 0; c < kGroundColumns; ++c) {
      const double az = 2.0 * std::numbers::pi * c / kGroundColumns;
      const Eigen::Vector3f p(static_cast<float>(d * std::cos(az)),
                              static_cast<float>(d * std::sin(az)), static_cast<float>(kGroundZ));
      scan.set_return(r, c, p.norm(), static_cast<float>(c % 100), p);
    }
  }
  return scan;
}

// mapping.map_radius_m bounds the map: no voxel farther than the radius plus the travel of two
// sweeps (2 x kSweepScans scans: a voxel checked first in one sweep may be checked last in the
// next) from the sensor stays in memory, the map stops growing, and what left
// (evicted(), taken after every scan) together with what stayed is exactly the unbounded map: the
// same voxels with the same means (the sensor never comes back, and a voxel's points all arrive
// before it is that far behind).
TEST(DynamicObjectFilter, MapRadiusBoundsTheMapAndHandsOverEveryVoxelThatLeaves) {
  core::MappingConfig unbounded;
  unbounded.log_delay_scans = 5;
  unbounded.free_space = false;
  core::MappingConfig bounded = unbounded;
  bounded.map_radius_m = 30.0;
  DynamicObjectFilter all(unbounded), near(bounded);
  std::vector<MapPoint> evicted;
  std::size_t size_at_400 = 0, largest = 0;
  constexpr int kScans = 1200;  // 600 m
  for (int k = 0; k < kScans; ++k) {
    core::Pose pose;
    pose.stamp_ns = testing::scan_stamp_ns(k);
    pose.translation = Eigen::Vector3d(0.5 * k, 3.0, 0.0);
    const core::OrganizedScan scan = ground_rings_scan(k);
    all.process(scan, pose, {}, {});
    const auto& r = near.process(scan, pose, {}, {});
    EXPECT_EQ(r.map_voxels_evicted, near.evicted().size());
    evicted.insert(evicted.end(), near.evicted().begin(), near.evicted().end());
    if (k % 20 == 0) {
      near.map().for_each([&](const MapPoint& p) {
        ASSERT_LE((p.position.head<2>().cast<double>() - pose.translation.head<2>()).norm(),
                  bounded.map_radius_m + 0.5 * 2 * DynamicObjectFilter::kSweepScans + 1e-3)
            << "scan " << k;
      });
    }
    if (k == 400) size_at_400 = near.map().size();
    largest = std::max(largest, near.map().size());
  }
  all.flush();
  near.flush();
  EXPECT_TRUE(near.evicted().empty());  // flush moves the log into the map, bounds nothing
  EXPECT_GT(all.map().size(), 8 * near.map().size());
  EXPECT_LE(largest, size_at_400 + size_at_400 / 10);
  std::vector<MapPoint> together = near.map().points();
  together.insert(together.end(), evicted.begin(), evicted.end());
  test::expect_same_map_points(together, all.map().points(), "evicted + kept vs unbounded");
}

TEST(DynamicObjectFilter, RejectsHypothesesNamingMissingDetections) {
  DynamicObjectFilter filter{core::MappingConfig{}};
  const Frame f = render({}, sensor_pose(0));
  tracking::Hypothesis h;
  h.id = 1;
  h.detection = 3;
  EXPECT_THROW(filter.process(f.scan, f.pose, {}, {h}), core::InputError);
}

}  // namespace
}  // namespace ringtrack::mapping
