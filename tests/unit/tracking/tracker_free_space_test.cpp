// Tracker free-space rules against hand-made organized scans: a small ray caster renders boxes
// (walls, pillars, people) into a 16-ring scan, the person's detection is made of the cells that
// hit it, and the tracker gets the scan's VisibilityQuery. Each scenario also runs the
// configuration without the rule (box test, no query) so that it cannot pass vacuously.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/core/visibility.hpp"
#include "ringtrack/tracking/tracker.hpp"
#include "support/scripted_detections.hpp"

namespace ringtrack::tracking {
namespace {

using testing::scan_stamp_ns;

constexpr double kDt = 0.1;
constexpr double kSensorHeight = 1.0;

// Labels of what a cell's beam hit.
enum Label : int {
  kNothing = -1,
  kWall = 0,
  kPillar = 1,
  kPerson = 2,
  kBinA = 3,
  kBinB = 4,
  kPasser = 5
};

struct Block {
  core::Box3 box;
  int label;
};

core::Box3 make_box(double x0, double x1, double y0, double y1, double z0, double z1) {
  core::Box3 b;
  b.extend(Eigen::Vector3f(static_cast<float>(x0), static_cast<float>(y0), static_cast<float>(z0)));
  b.extend(Eigen::Vector3f(static_cast<float>(x1), static_cast<float>(y1), static_cast<float>(z1)));
  return b;
}

// A person 0.5 m wide and 1.75 m tall standing at (x, y) on the ground (z = 0).
Block person_at(double x, double y) {
  return {make_box(x - 0.25, x + 0.25, y - 0.25, y + 0.25, 0.0, 1.75), kPerson};
}

// A wall across the view at x (0.3 m thick, 40 m wide, 3 m high).
Block wall_at(double x) {
  return {make_box(x, x + 0.3, -20.0, 20.0, 0.0, 3.0), kWall};
}

// 16 rings from -15 to 15 degrees (VLP-16 elevations without beam offsets), 0.5 degree columns.
const core::SensorModel& sensor() {
  static const core::SensorModel m = core::SensorModel::generic(
      {-15, -13, -11, -9, -7, -5, -3, -1, 1, 3, 5, 7, 9, 11, 13, 15}, 720);
  return m;
}

core::Pose sensor_pose(double x, double y) {
  core::Pose p;
  p.translation = {x, y, kSensorHeight};
  return p;
}

// Distance along the ray to the box (slab test), or nothing.
std::optional<double> hit_distance(const Eigen::Vector3d& o, const Eigen::Vector3d& d,
                                   const core::Box3& box) {
  double near = 0.0;
  double far = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const double lo = box.min[k];
    const double hi = box.max[k];
    if (std::abs(d[k]) < 1e-12) {
      if (o[k] < lo || o[k] > hi) return std::nullopt;
      continue;
    }
    const double t0 = (lo - o[k]) / d[k];
    const double t1 = (hi - o[k]) / d[k];
    near = std::max(near, std::min(t0, t1));
    far = std::min(far, std::max(t0, t1));
    if (near > far) return std::nullopt;
  }
  return near;
}

// One rendered scan: the organized scan and what each cell hit.
struct Rendered {
  core::OrganizedScan scan;
  std::vector<int> label;
  core::Pose pose;
};

// Ray-casts every cell's beam against the blocks (nearest hit wins) with Gaussian range noise;
// beams hitting nothing return nothing.
Rendered render(const core::Pose& pose, const std::vector<Block>& blocks, std::int64_t stamp_ns,
                double range_noise_m = 0.0, std::mt19937_64* rng = nullptr) {
  const auto& m = sensor();
  Rendered r{core::OrganizedScan(m.rings(), m.columns()), {}, pose};
  r.scan.set_uniform_columns(m, stamp_ns);
  r.label.assign(r.scan.size(), kNothing);
  const Eigen::Matrix3d rot = pose.rotation.normalized().toRotationMatrix();
  std::normal_distribution<double> noise(0.0, range_noise_m);
  for (int ring = 0; ring < m.rings(); ++ring) {
    for (int c = 0; c < m.columns(); ++c) {
      const double az = r.scan.column_azimuth_rad[static_cast<std::size_t>(c)];
      const Eigen::Vector3d origin_s = m.point(ring, az, 0.0).cast<double>();
      const Eigen::Vector3d dir_s = (m.point(ring, az, 1.0).cast<double>() - origin_s).normalized();
      const Eigen::Vector3d o = rot * origin_s + pose.translation;
      const Eigen::Vector3d d = rot * dir_s;
      double best = std::numeric_limits<double>::infinity();
      int best_label = kNothing;
      for (const auto& b : blocks) {
        const auto t = hit_distance(o, d, b.box);
        if (t && *t < best) {
          best = *t;
          best_label = b.label;
        }
      }
      if (best_label == kNothing) continue;  // cells start as kNoReturn
      const double range = best + (rng != nullptr && range_noise_m > 0 ? noise(*rng) : 0.0);
      r.scan.set_range(m, ring, c, static_cast<float>(range), 1.0f);
      r.label[r.scan.index(ring, c)] = best_label;
    }
  }
  return r;
}

std::vector<std::uint32_t> cells_of(const Rendered& r, std::initializer_list<int> labels,
                                    double max_z = std::numeric_limits<double>::infinity()) {
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < r.label.size(); ++i) {
    if (std::find(labels.begin(), labels.end(), r.label[i]) == labels.end()) continue;
    if (r.pose.to_world(r.scan.point(i)).z() > max_z) continue;
    out.push_back(static_cast<std::uint32_t>(i));
  }
  return out;
}

// A detection of the given cells: centroid, covariance (floored) and box of their world points.
core::Detection detection_of(const Rendered& r, const std::vector<std::uint32_t>& cells) {
  core::Detection d;
  d.indices = cells;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> pts;
  for (const auto i : cells) {
    const Eigen::Vector3f p = r.pose.to_world(r.scan.point(i));
    pts.push_back(p.cast<double>());
    sum += pts.back();
    d.box.extend(p);
  }
  const Eigen::Vector3d mean = sum / static_cast<double>(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  cov /= static_cast<double>(pts.size());
  cov.diagonal().array() += 1e-4;
  d.centroid = mean.cast<float>();
  d.covariance = cov.cast<float>();
  return d;
}

// Runs one tracker over rendered scans; with_visibility chooses whether it sees the query.
struct TrackerRun {
  TrackerRun(const core::TrackingConfig& config, bool with_visibility)
      : tracker(config), visibility(with_visibility) {}

  const std::vector<Hypothesis>& step(const Rendered& r,
                                      const std::vector<core::Detection>& detections) {
    const std::int64_t stamp = scan_stamp_ns(scan++);
    if (!visibility) return tracker.update(detections, stamp, nullptr);
    const core::VisibilityQuery query(r.scan, sensor(), r.pose);
    return tracker.update(detections, stamp, &query);
  }

  // The hypothesis of detection 0 this scan, if any.
  [[nodiscard]] const Hypothesis* of_first() const {
    for (const auto& h : tracker.hypotheses()) {
      if (h.detection == 0) return &h;
    }
    return nullptr;
  }
  // Its id, 0 when none.
  [[nodiscard]] std::uint64_t id_of_first() const {
    const Hypothesis* h = of_first();
    return h != nullptr ? h->id : 0;
  }

  Tracker tracker;
  bool visibility;
  int scan{0};
};

core::TrackingConfig box_config() {
  core::TrackingConfig c;
  c.dynamic_test = core::DynamicTest::kBox;
  return c;
}

// Share of the cells whose beam does not hit the given label in the scan (it hits what is
// behind, or nothing: the lowest rings pass the wall's foot).
double share_without_label(const Rendered& r, const std::vector<std::uint32_t>& cells, int label) {
  int n = 0;
  for (const auto i : cells) n += r.label[i] != label ? 1 : 0;
  return cells.empty() ? 0.0 : static_cast<double>(n) / static_cast<double>(cells.size());
}

// A person stands 5 m in front of a wall for 100 scans (3 cm range noise), then walks sideways
// at 1 m/s. With sensor_y the sensor's y during the walk (the anchor was seen from y = 0).
// Returns the walking scan (1-based) at which each tracker first reported the person dynamic
// (0: never), and checks the standing phase on the way.
struct WalkResult {
  int free_space_dynamic{0};
  int box_dynamic{0};
  int possible{0};  // first walking scan where >= half the anchor cells see past the person
                    // and it moved > 0.45 m
  int clear{0};     // first walking scan where all anchor cells see past it, moved > 0.55 m
};

WalkResult walk_away_from_wall(double walk_sensor_x, std::uint64_t seed) {
  const core::TrackingConfig config;
  TrackerRun free_space(config, true);
  TrackerRun box(box_config(), true);
  std::mt19937_64 rng(seed);
  WalkResult out;
  std::vector<std::uint32_t> anchor_cells;
  std::uint64_t id = 0;
  for (int k = 0; k < 100; ++k) {
    const auto r = render(sensor_pose(0, 0), {wall_at(8.0), person_at(5.0, 0.0)}, scan_stamp_ns(k),
                          0.03, &rng);
    const auto cells = cells_of(r, {kPerson});
    if (k == 0) anchor_cells = cells;
    const std::vector<core::Detection> dets{detection_of(r, cells)};
    free_space.step(r, dets);
    box.step(r, dets);
    const Hypothesis* h = free_space.of_first();
    EXPECT_NE(h, nullptr);
    if (h == nullptr) continue;
    if (k == 0) id = h->id;
    EXPECT_EQ(h->id, id) << "scan " << k;
    EXPECT_FALSE(h->dynamic) << "standing person turned dynamic in scan " << k;
  }
  EXPECT_EQ(free_space.tracker.hypotheses().size(), 1u);
  for (int j = 1; j <= 30; ++j) {
    const double y = 0.1 * j;
    const auto r = render(sensor_pose(walk_sensor_x, 0), {wall_at(8.0), person_at(5.0, y)},
                          scan_stamp_ns(100 + j), 0.03, &rng);
    const auto cells = cells_of(r, {kPerson});
    const std::vector<core::Detection> dets{detection_of(r, cells)};
    free_space.step(r, dets);
    box.step(r, dets);
    const double wall_share = share_without_label(r, anchor_cells, kPerson);
    if (out.possible == 0 && wall_share >= 0.5 && y > 0.45) out.possible = j;
    if (out.clear == 0 && wall_share == 1.0 && y > 0.55) out.clear = j;
    const Hypothesis* h = free_space.of_first();
    const Hypothesis* hb = box.of_first();
    EXPECT_TRUE(h != nullptr && h->id == id) << "walking scan " << j;
    EXPECT_NE(hb, nullptr);
    if (out.free_space_dynamic == 0 && h != nullptr && h->dynamic) out.free_space_dynamic = j;
    if (out.box_dynamic == 0 && hb != nullptr && hb->dynamic) out.box_dynamic = j;
  }
  return out;
}

TEST(TrackerFreeSpace, PersonLeavingAWallTurnsDynamicWhenTheWallIsSeenAgain) {
  const int confirm = core::TrackingConfig{}.free_space_confirm_scans;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const WalkResult w = walk_away_from_wall(0.0, seed);
    ASSERT_GT(w.possible, 0);
    ASSERT_GT(w.clear, 0);
    ASSERT_GT(w.free_space_dynamic, 0) << "seed " << seed;
    // Not before the wall behind the anchor shows and the person moved 0.5 m ...
    EXPECT_GE(w.free_space_dynamic, w.possible + confirm - 1) << "seed " << seed;
    // ... and within the confirmation scans once both clearly hold.
    EXPECT_LE(w.free_space_dynamic, w.clear + confirm - 1) << "seed " << seed;
    // The box test needs 1 m and five scans of disjoint footprints: later.
    ASSERT_GT(w.box_dynamic, 0) << "seed " << seed;
    EXPECT_GT(w.box_dynamic, w.free_space_dynamic) << "seed " << seed;
  }
}

// The anchor was seen from y = 0; the walk is seen from 0.3 m further back: beyond
// free_space_max_viewpoint_shift_m the box test decides, so both trackers agree. Within it
// (5 cm) the free-space test still decides, as early as from the anchor's viewpoint.
TEST(TrackerFreeSpace, MovedSensorFallsBackToTheBoxTest) {
  const int confirm = core::TrackingConfig{}.free_space_confirm_scans;
  ASSERT_LT(0.05, core::TrackingConfig{}.free_space_max_viewpoint_shift_m);
  ASSERT_GT(0.3, core::TrackingConfig{}.free_space_max_viewpoint_shift_m);
  const WalkResult moved = walk_away_from_wall(-0.3, 4);
  ASSERT_GT(moved.box_dynamic, 0);
  EXPECT_EQ(moved.free_space_dynamic, moved.box_dynamic);
  const WalkResult near = walk_away_from_wall(-0.05, 4);
  ASSERT_GT(near.free_space_dynamic, 0);
  EXPECT_LE(near.free_space_dynamic, near.clear + confirm - 1);
  EXPECT_LT(near.free_space_dynamic, near.box_dynamic);
}

// A pillar with two bins beside it, seen from a sensor translating 2 m sideways: the cluster
// the detector would report changes with the view (pillar alone, with one bin, with the other,
// with both; centroid jumps of about half a metre). It stays one static hypothesis, also when
// the free-space test is forced for every viewpoint.
TEST(TrackerFreeSpace, PillarSeenFromAMovingSensorStaysStatic) {
  core::TrackingConfig forced;
  forced.free_space_max_viewpoint_shift_m = 5.0;
  TrackerRun normal(core::TrackingConfig{}, true);
  TrackerRun forced_run(forced, true);
  TrackerRun box(box_config(), true);
  const std::vector<Block> scene{
      wall_at(8.0),
      {make_box(5.0, 5.3, -0.15, 0.15, 0.0, 2.0), kPillar},
      {make_box(4.9, 5.3, 0.35, 0.85, 0.0, 0.8), kBinA},
      {make_box(4.9, 5.3, -0.85, -0.35, 0.0, 0.8), kBinB},
  };
  std::mt19937_64 rng(11);
  std::uint64_t ids[3] = {0, 0, 0};
  float min_y = 1e9f;
  float max_y = -1e9f;
  for (int k = 0; k < 100; ++k) {
    const double sensor_y = -1.0 + 2.0 * k / 99.0;
    const auto r = render(sensor_pose(0, sensor_y), scene, scan_stamp_ns(k), 0.03, &rng);
    std::vector<std::uint32_t> cells;
    switch (k % 4) {
      case 0:
        cells = cells_of(r, {kPillar});
        break;
      case 1:
        cells = cells_of(r, {kPillar, kBinA});
        break;
      case 2:
        cells = cells_of(r, {kPillar, kBinB});
        break;
      default:
        cells = cells_of(r, {kPillar, kBinA, kBinB});
        break;
    }
    const std::vector<core::Detection> dets{detection_of(r, cells)};
    min_y = std::min(min_y, dets[0].centroid.y());
    max_y = std::max(max_y, dets[0].centroid.y());
    TrackerRun* runs[3] = {&normal, &forced_run, &box};
    for (int i = 0; i < 3; ++i) {
      runs[i]->step(r, dets);
      const Hypothesis* h = runs[i]->of_first();
      ASSERT_NE(h, nullptr) << "tracker " << i << ", scan " << k;
      if (k == 0) ids[i] = h->id;
      EXPECT_EQ(h->id, ids[i]) << "tracker " << i << ", scan " << k;
      EXPECT_FALSE(h->dynamic) << "tracker " << i << ", scan " << k;
    }
  }
  EXPECT_GT(max_y - min_y, 0.4f);  // the cluster really changed
}

// A person walks at 0.5 m/s behind a 1.2 m wide pillar (static sensor, wall far behind):
// while hidden, the cells at its predicted position show the pillar in front (occluded), so the
// hypothesis coasts longer than the covariance test allows and keeps its id. Without the
// visibility query the same detections lose the track.
TEST(TrackerFreeSpace, PersonBehindAPillarKeepsItsIdentity) {
  const core::TrackingConfig config;
  TrackerRun with(config, true);
  TrackerRun without(config, false);
  const std::vector<Block> still{wall_at(12.0), {make_box(4.0, 4.3, -0.4, 0.4, 0.0, 2.5), kPillar}};
  int gap = 0;
  int longest_gap = 0;
  int hits_before_gap = 0;
  std::uint64_t id = 0;
  std::uint64_t id_without = 0;
  std::optional<core::Detection> last_seen;
  bool reappeared = false;
  std::uint64_t id_after = 0;
  std::uint64_t id_after_without = 0;
  int max_missed = 0;
  int hidden_scans = 0;     // nothing of the person in the scan
  int occluded_hidden = 0;  // ... and the hypothesis saw the pillar in front of its prediction
  for (int k = 0; k < 140; ++k) {
    auto scene = still;
    scene.push_back(person_at(6.0, -3.0 + 0.05 * k));
    const auto r = render(sensor_pose(0, 0), scene, scan_stamp_ns(k));
    const auto cells = cells_of(r, {kPerson});
    std::vector<core::Detection> dets;
    // The strict object model rejects slivers of a person; they would also halve the measured
    // speed as the visible part shrinks.
    if (cells.size() >= 60) dets.push_back(detection_of(r, cells));
    with.step(r, dets);
    without.step(r, dets);
    if (dets.empty()) {
      ++gap;
      ASSERT_EQ(with.tracker.stats().deleted_seen_through, 0) << "scan " << k;
      for (const auto& h : with.tracker.hypotheses()) {
        if (h.id != id) continue;
        max_missed = std::max(max_missed, h.missed_scans);
        if (cells.empty()) {
          ++hidden_scans;
          occluded_hidden += h.occluded ? 1 : 0;
        }
      }
      continue;
    }
    if (gap > 0 && !reappeared) {
      reappeared = true;
      longest_gap = gap;
      id_after = with.id_of_first();
      id_after_without = without.id_of_first();
    }
    gap = 0;
    if (!reappeared) {
      ++hits_before_gap;
      if (id == 0) {
        id = with.id_of_first();
        id_without = without.id_of_first();
      }
      last_seen = dets[0];
    }
  }
  ASSERT_TRUE(reappeared);
  ASSERT_TRUE(last_seen);
  const int allowed = missed_scans_until_deletion(
      config, with.tracker.measurement_covariance(*last_seen),
      with.tracker.update_covariance(*last_seen), kDt, hits_before_gap - 1);
  EXPECT_GT(longest_gap, allowed) << "the scene must hide the person longer than the "
                                     "covariance test allows";
  EXPECT_LE(longest_gap, config.occluded_coast_scans);
  EXPECT_EQ(max_missed, longest_gap);
  EXPECT_GT(hidden_scans, 0);
  EXPECT_EQ(occluded_hidden, hidden_scans);
  EXPECT_EQ(id_after, id);
  EXPECT_NE(id_after_without, id_without);
}

// A person walks in the open (wall 6 m behind) and vanishes from the scan: the cells at its
// predicted position see the wall, so it is deleted after exactly free_delete_scans missed
// scans; without the query the covariance test keeps it for missed_scans_until_deletion.
TEST(TrackerFreeSpace, PersonSeenThroughIsDeletedAfterFreeDeleteScans) {
  for (const int free_delete : {2, 4}) {
    core::TrackingConfig config;
    config.free_delete_scans = free_delete;
    TrackerRun with(config, true);
    TrackerRun without(config, false);
    core::Detection last;
    const int walk = 30;
    for (int k = 0; k < walk; ++k) {
      const auto r = render(sensor_pose(0, 0), {wall_at(12.0), person_at(6.0, -1.0 + 0.05 * k)},
                            scan_stamp_ns(k));
      last = detection_of(r, cells_of(r, {kPerson}));
      with.step(r, {last});
      without.step(r, {last});
    }
    const int allowed =
        missed_scans_until_deletion(config, with.tracker.measurement_covariance(last),
                                    with.tracker.update_covariance(last), kDt, walk - 1);
    ASSERT_GT(allowed, free_delete);
    const auto empty = render(sensor_pose(0, 0), {wall_at(12.0)}, 0);
    for (int missed = 1; missed <= allowed; ++missed) {
      with.step(empty, {});
      without.step(empty, {});
      EXPECT_EQ(with.tracker.hypotheses().size(), missed < free_delete ? 1u : 0u)
          << "missed " << missed;
      EXPECT_EQ(with.tracker.stats().deleted_seen_through, missed == free_delete ? 1 : 0)
          << "missed " << missed;
      EXPECT_EQ(without.tracker.hypotheses().size(), missed < allowed ? 1u : 0u)
          << "missed " << missed;
      EXPECT_EQ(without.tracker.stats().deleted_uncertain, missed == allowed ? 1 : 0)
          << "missed " << missed;
      EXPECT_EQ(without.tracker.stats().deleted_seen_through, 0);
    }
  }
}

// A missed hypothesis whose predicted points the scan sees through is kept (its id survives a
// scan between beams) but not reported in that scan; without the query it is reported for
// report_missed_scans scans, and a hidden one stays reported.
TEST(TrackerFreeSpace, SeenThroughHypothesisIsKeptButNotReported) {
  core::TrackingConfig config;
  config.free_delete_scans = 0;  // never deleted as seen through
  TrackerRun with(config, true);
  TrackerRun without(config, false);
  TrackerRun hidden(config, true);
  for (int k = 0; k < 20; ++k) {
    const auto r =
        render(sensor_pose(0, 0), {wall_at(12.0), person_at(6.0, 1.0)}, scan_stamp_ns(k));
    const auto d = detection_of(r, cells_of(r, {kPerson}));
    with.step(r, {d});
    without.step(r, {d});
    hidden.step(r, {d});
  }
  ASSERT_TRUE(with.tracker.hypotheses().front().reported);
  const auto empty = render(sensor_pose(0, 0), {wall_at(12.0)}, 0);
  // A pillar between the sensor and the person hides it.
  const auto blocked = render(
      sensor_pose(0, 0),
      {wall_at(12.0), person_at(6.0, 1.0), {make_box(3.0, 3.4, 0.0, 1.0, 0.0, 3.0), kPillar}}, 0);
  for (int missed = 1; missed <= config.report_missed_scans + 1; ++missed) {
    with.step(empty, {});
    without.step(empty, {});
    hidden.step(blocked, {});
    ASSERT_EQ(with.tracker.hypotheses().size(), 1u);
    const auto& h = with.tracker.hypotheses().front();
    EXPECT_TRUE(h.unseen) << "missed " << missed;
    EXPECT_FALSE(h.reported) << "missed " << missed;
    EXPECT_EQ(without.tracker.hypotheses().front().reported, missed <= config.report_missed_scans)
        << "missed " << missed;
    EXPECT_FALSE(hidden.tracker.hypotheses().front().unseen) << "missed " << missed;
    EXPECT_TRUE(hidden.tracker.hypotheses().front().occluded) << "missed " << missed;
    // Hidden, it is listed as long as a missed hypothesis the scan shows is, no longer: an
    // object without hit points has no ground truth, listing it is a false positive.
    EXPECT_EQ(hidden.tracker.hypotheses().front().reported, missed <= config.report_missed_scans)
        << "missed " << missed;
  }
  // Measured again: reported again, with the same id.
  const auto back = render(sensor_pose(0, 0), {wall_at(12.0), person_at(6.0, 1.0)}, 0);
  const auto id = with.tracker.hypotheses().front().id;
  with.step(back, {detection_of(back, cells_of(back, {kPerson}))});
  ASSERT_EQ(with.tracker.hypotheses().size(), 1u);
  EXPECT_EQ(with.tracker.hypotheses().front().id, id);
  EXPECT_TRUE(with.tracker.hypotheses().front().reported);
  EXPECT_FALSE(with.tracker.hypotheses().front().unseen);
}

// Without a visibility query a missed hypothesis coasts exactly as before: deleted by the
// covariance test after missed_scans_until_deletion scans, never as seen through, never held
// as occluded.
TEST(TrackerFreeSpace, NoVisibilityCoastsUntilTheCovarianceTest) {
  const core::TrackingConfig config;
  TrackerRun run(config, false);
  const auto r = render(sensor_pose(0, 0), {wall_at(8.0), person_at(5.0, 1.0)}, 0);
  const auto d = detection_of(r, cells_of(r, {kPerson}));
  const int hits = 40;
  for (int k = 0; k < hits; ++k) run.step(r, {d});
  ASSERT_EQ(run.tracker.hypotheses().size(), 1u);
  EXPECT_TRUE(run.tracker.hypotheses().front().last_points.empty());
  const int allowed = missed_scans_until_deletion(config, run.tracker.measurement_covariance(d),
                                                  run.tracker.update_covariance(d), kDt, hits - 1);
  ASSERT_GT(allowed, config.free_delete_scans);
  for (int missed = 1; missed <= allowed; ++missed) {
    run.step(r, {});
    EXPECT_EQ(run.tracker.hypotheses().size(), missed < allowed ? 1u : 0u) << "missed " << missed;
    EXPECT_EQ(run.tracker.stats().deleted_seen_through, 0);
    if (missed < allowed) {
      EXPECT_FALSE(run.tracker.hypotheses().front().occluded);
      EXPECT_EQ(run.tracker.hypotheses().front().seen_through_scans, 0);
    }
  }
  EXPECT_EQ(run.tracker.stats().deleted_uncertain, 1);
}

// A person stands 6 m away (wall behind) while a passer-by walks across 1.2 m in front of it at
// 0.6 m/s, hiding first one side of it, then all of it, then the other side (the static hall's
// walker who stops, docs/BENCHMARK.md, issue 12). The person's
// detection is what the scan still shows of it (three cells or more), the passer-by's its own.
// Returns the largest horizontal distance of the person's hypothesis from where it stands while
// the passer-by crosses, and whether it keeps its id through the pass (-1 distance: lost).
struct PassResult {
  double max_drift_m{-1.0};
  bool same_id{false};
  int held{0};  // scans the tracker held it at its full view (stats().held_partly_hidden)
};

// A scan's detections when something may hide part of the person: what is visible of the person
// (three cells or more) first, then the occluder's cells.
std::vector<core::Detection> person_and_occluder(const Rendered& r, int occluder) {
  std::vector<core::Detection> dets;
  const auto visible = cells_of(r, {kPerson});
  if (visible.size() >= 3) dets.push_back(detection_of(r, visible));
  const auto hiding = cells_of(r, {occluder});
  if (!hiding.empty()) dets.push_back(detection_of(r, hiding));
  return dets;
}

PassResult standing_person_behind_a_passer_by(bool hold) {
  core::TrackingConfig config;
  config.hold_partly_hidden = hold;
  TrackerRun run(config, true);
  const Block person = person_at(6.0, 0.0);
  std::uint64_t id = 0;
  PassResult out;
  const auto step = [&](const std::vector<Block>& scene, int k) {
    const auto r = render(sensor_pose(0, 0), scene, scan_stamp_ns(k));
    run.step(r, person_and_occluder(r, kPasser));
    out.held += run.tracker.stats().held_partly_hidden;
  };
  for (int k = 0; k < 30; ++k) step({wall_at(12.0), person}, k);
  const Hypothesis* first = run.of_first();
  if (first == nullptr) return out;
  id = first->id;
  const Eigen::Vector2d standing = first->position().head<2>();
  out.max_drift_m = 0.0;
  for (int j = 0; j <= 30; ++j) {
    Block passer = person_at(4.8, -0.9 + 0.06 * j);
    passer.label = kPasser;
    step({wall_at(12.0), person, passer}, 30 + j);
    for (const auto& h : run.tracker.hypotheses()) {
      if (h.id == id) {
        out.max_drift_m = std::max(out.max_drift_m, (h.position().head<2>() - standing).norm());
      }
    }
  }
  for (int k = 61; k < 70; ++k) step({wall_at(12.0), person}, k);
  out.same_id = run.id_of_first() == id;
  return out;
}

TEST(TrackerFreeSpace, StandingPersonBehindAPasserByStaysWhereItStands) {
  ASSERT_TRUE(core::TrackingConfig{}.hold_partly_hidden);
  const PassResult held = standing_person_behind_a_passer_by(true);
  // Held at its full view in the scans where a quarter or more of it was hidden (6 of the 11
  // that showed part of it; the first, barely hidden ones move it by centimetres).
  EXPECT_GE(held.held, 5);
  EXPECT_GE(held.max_drift_m, 0.0);
  EXPECT_LT(held.max_drift_m, 0.15);
  EXPECT_TRUE(held.same_id);
  // Without the rule the visible edge drags the track away (0.8 m here) and the person comes
  // back as a new identity.
  const PassResult followed = standing_person_behind_a_passer_by(false);
  EXPECT_EQ(followed.held, 0);
  EXPECT_GT(followed.max_drift_m, 0.3);
  EXPECT_FALSE(followed.same_id);
}

// The same from a moving sensor: it walks sideways at 0.5 m/s behind a pillar 3 m away, whose
// shadow sweeps across a person standing 6 m away. The remembered points were seen from another
// viewpoint each time, and the person is still held where it stands.
PassResult standing_person_behind_a_pillar_seen_walking_past(bool hold) {
  core::TrackingConfig config;
  config.hold_partly_hidden = hold;
  TrackerRun run(config, true);
  const Block person = person_at(6.0, 0.0);
  const Block pillar{make_box(2.9, 3.1, -0.1, 0.1, 0.0, 2.5), kPillar};
  PassResult out;
  std::uint64_t id = 0;
  Eigen::Vector2d standing = Eigen::Vector2d::Zero();
  for (int k = 0; k < 90; ++k) {
    const double sensor_y = -2.25 + 0.05 * k;
    const auto r =
        render(sensor_pose(0, sensor_y), {wall_at(12.0), person, pillar}, scan_stamp_ns(k));
    run.step(r, person_and_occluder(r, kPillar));
    out.held += run.tracker.stats().held_partly_hidden;
    if (k == 20) {
      const Hypothesis* first = run.of_first();
      if (first == nullptr) return out;
      id = first->id;
      standing = first->position().head<2>();
      out.max_drift_m = 0.0;
    }
    if (k <= 20) continue;
    for (const auto& h : run.tracker.hypotheses()) {
      if (h.id == id)
        out.max_drift_m = std::max(out.max_drift_m, (h.position().head<2>() - standing).norm());
    }
  }
  out.same_id = run.id_of_first() == id;
  return out;
}

TEST(TrackerFreeSpace, StandingPersonBehindAPillarSeenWalkingPastStaysWhereItStands) {
  const PassResult held = standing_person_behind_a_pillar_seen_walking_past(true);
  const PassResult followed = standing_person_behind_a_pillar_seen_walking_past(false);
  // Held while the shadow crosses it (7 scans in this rendering), keeping its id. Its centroid
  // still moves a little with the viewpoint (the visible front turns with it), so the drift is
  // bounded rather than nil, and below that of the track that follows the visible edge.
  EXPECT_GE(held.held, 5);
  EXPECT_TRUE(held.same_id);
  EXPECT_GE(held.max_drift_m, 0.0);
  EXPECT_LT(held.max_drift_m, 0.2);
  EXPECT_EQ(followed.held, 0);
  EXPECT_LT(held.max_drift_m, followed.max_drift_m);
}

// A person at rest whose detection shrinks with nothing in front of it (it crouches: only the
// lower half is left) is followed as before: only a view hidden by something nearer is held.
TEST(TrackerFreeSpace, PersonAtRestShrinkingInTheOpenIsFollowed) {
  const core::TrackingConfig config;
  ASSERT_TRUE(config.hold_partly_hidden);
  TrackerRun run(config, true);
  for (int k = 0; k < 30; ++k) {
    const auto r =
        render(sensor_pose(0, 0), {wall_at(12.0), person_at(6.0, 0.0)}, scan_stamp_ns(k));
    run.step(r, {detection_of(r, cells_of(r, {kPerson}))});
  }
  const Hypothesis* before = run.of_first();
  ASSERT_NE(before, nullptr);
  const double z_before = before->position().z();
  Block crouched = person_at(6.0, 0.0);
  crouched.box.max.z() = 0.8f;
  for (int k = 30; k < 40; ++k) {
    const auto r = render(sensor_pose(0, 0), {wall_at(12.0), crouched}, scan_stamp_ns(k));
    run.step(r, {detection_of(r, cells_of(r, {kPerson}))});
    EXPECT_EQ(run.tracker.stats().held_partly_hidden, 0) << "scan " << k;
  }
  const Hypothesis* after = run.of_first();
  ASSERT_NE(after, nullptr);
  EXPECT_LT(after->position().z(), z_before - 0.2);
}

}  // namespace
}  // namespace ringtrack::tracking
