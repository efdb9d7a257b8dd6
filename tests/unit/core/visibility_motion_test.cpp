// Visibility queries of a scan swept by a moving sensor: every column measured from the sensor's
// pose at its own stamp, the points motion-compensated to the scan's pose.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/core/recent_views.hpp"
#include "ringtrack/core/visibility.hpp"
#include "support/naive_visibility.hpp"

namespace ringtrack::core {
namespace {

constexpr double kWallX = 10.0;  // the only surface: the world plane x = 10

Pose start_pose() {
  Pose p;
  p.stamp_ns = 5'000'000'000;
  p.translation = {1.0, -2.0, 2.5};
  p.rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.1, 0.2, 1.0).normalized()));
  return p;
}

// Fast and turning: 5 m/s and 1.25 rad/s, a MAV in a tight turn.
Motion turning() {
  Motion m;
  m.velocity_mps = {3.0, 4.0, 0.3};
  m.angular_velocity_radps = {0.1, -0.15, 1.25};
  return m;
}

// The sensor at a column's stamp: the naive reference (Eigen's angle-axis, no series).
Pose column_pose(const OrganizedScan& scan, const Pose& pose, const Motion& motion, int column) {
  const double dt =
      1e-9 *
      static_cast<double>(scan.column_stamp_ns[static_cast<std::size_t>(column)] - scan.stamp_ns);
  return motion.advance(pose, dt);
}

// Ring r's beam of column c in the world, fired from `sensor`.
BeamRay naive_ray(const SensorModel& m, const OrganizedScan& scan, const Pose& sensor, int r,
                  int c) {
  const auto ri = static_cast<std::size_t>(r);
  const double az = scan.column_azimuth_rad[static_cast<std::size_t>(c)] + m.azimuth_offset_rad[ri];
  const double el = m.elevation_rad[ri];
  const Eigen::Isometry3d t = sensor.isometry();
  const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
  return {t * Eigen::Vector3d(0.0, 0.0, m.vertical_offset_m[ri]), t.linear() * d};
}

// What stands in the world besides the wall at x = 10: the ground, a pole, a person (a box).
struct Scene {
  bool ground{false};                         // the plane z = 0
  std::optional<Eigen::Vector2d> pole;        // a vertical cylinder of radius 0.1 m, 0-3 m high
  std::optional<Eigen::AlignedBox3d> person;  // an upright box
};

constexpr double kPoleRadius = 0.1;

// Distance along the ray to the nearest surface of the scene, infinity when none.
double cast(const Scene& scene, const BeamRay& ray) {
  const Eigen::Vector3d& o = ray.origin;
  const Eigen::Vector3d& d = ray.direction;
  double best = std::numeric_limits<double>::infinity();
  if (d.x() > 1e-3) best = (kWallX - o.x()) / d.x();
  if (scene.ground && d.z() < -1e-6) best = std::min(best, -o.z() / d.z());
  if (scene.pole) {
    // |(o + t d - c)_xy| = r: a quadratic in t; the nearer root within the pole's height.
    const Eigen::Vector2d oc = o.head<2>() - *scene.pole;
    const Eigen::Vector2d dxy = d.head<2>();
    const double a = dxy.squaredNorm();
    const double b = 2.0 * oc.dot(dxy);
    const double c = oc.squaredNorm() - kPoleRadius * kPoleRadius;
    const double disc = b * b - 4 * a * c;
    if (a > 0.0 && disc >= 0.0) {
      const double t = (-b - std::sqrt(disc)) / (2 * a);
      const double z = o.z() + t * d.z();
      if (t > 0.0 && z >= 0.0 && z <= 3.0) best = std::min(best, t);
    }
  }
  if (scene.person) {
    double t0 = 0.0;
    double t1 = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 3; ++k) {
      const double a = (scene.person->min()[k] - o[k]) / d[k];
      const double b = (scene.person->max()[k] - o[k]) / d[k];
      t0 = std::max(t0, std::min(a, b));
      t1 = std::min(t1, std::max(a, b));
    }
    if (t0 <= t1 && t0 > 0.0) best = std::min(best, t0);
  }
  return best;
}

// The scene measured by a sensor moving with `motion` from `pose` during the sweep, each return
// re-expressed in the frame of `pose` (what pipeline::deskew_scan produces; ranges as measured).
OrganizedScan swept_scan(const SensorModel& m, const Pose& pose, const Motion& motion,
                         const Scene& scene = {}) {
  OrganizedScan scan(m.rings(), m.columns());
  scan.set_uniform_columns(m, pose.stamp_ns);
  const Eigen::Isometry3d scan_from_world = pose.isometry().inverse();
  for (int c = 0; c < m.columns(); ++c) {
    const Pose sensor = column_pose(scan, pose, motion, c);
    for (int r = 0; r < m.rings(); ++r) {
      const BeamRay ray = naive_ray(m, scan, sensor, r, c);
      const double range = cast(scene, ray);
      if (range > 90.0) continue;  // no return
      const Eigen::Vector3d world = ray.origin + range * ray.direction;
      scan.set_return(r, c, static_cast<float>(range), 1.0f,
                      (scan_from_world * world).cast<float>());
    }
  }
  return scan;
}

OrganizedScan swept_wall(const SensorModel& m, const Pose& pose, const Motion& motion) {
  return swept_scan(m, pose, motion);
}

TEST(VisibilityMotion, ColumnBeamsStartFromTheColumnsPose) {
  const SensorModel m = SensorModel::vlp16();
  const Pose pose = start_pose();
  const Motion motion = turning();
  const OrganizedScan scan = swept_wall(m, pose, motion);
  const VisibilityQuery q(scan, m, pose, motion);
  ASSERT_TRUE(q.per_column_poses());
  double worst_origin = 0.0;
  double worst_direction = 0.0;
  for (int c = 0; c < m.columns(); c += 7) {
    const Pose sensor = column_pose(scan, pose, motion, c);
    for (int r = 0; r < m.rings(); ++r) {
      const BeamRay want = naive_ray(m, scan, sensor, r, c);
      const BeamRay got = q.cell_ray(r, c);
      worst_origin = std::max(worst_origin, (got.origin - want.origin).norm());
      worst_direction = std::max(worst_direction, (got.direction - want.direction).norm());
    }
  }
  EXPECT_LT(worst_origin, 1e-9);
  EXPECT_LT(worst_direction, 1e-9);
}

TEST(VisibilityMotion, EveryReturnIsOccupiedInItsOwnCell) {
  const SensorModel m = SensorModel::vlp16();
  const Pose pose = start_pose();
  const Motion motion = turning();
  const OrganizedScan scan = swept_wall(m, pose, motion);
  const VisibilityQuery moving(scan, m, pose, motion);
  const VisibilityQuery frozen(scan, m, pose);  // every beam from the scan's pose: the old answer
  ASSERT_FALSE(frozen.per_column_poses());
  int returns = 0;
  int frozen_wrong = 0;
  int inside = 0;
  const int seam_columns = m.columns() / 40;
  for (int r = 0; r < m.rings(); ++r) {
    for (int c = 0; c < m.columns(); ++c) {
      const std::size_t i = scan.index(r, c);
      if (!scan.valid(i)) continue;
      ++returns;
      const Eigen::Vector3d x = moving.world_point(i);
      if (frozen.at(x, 0.02) != Visibility::kOccupied) ++frozen_wrong;
      const auto cell = moving.cell_of(x);
      // Within the sensor's turn (7 degrees) of the seam two columns saw the same place: either
      // may answer, and the other one's beam passes up to half a ring gap beside the point.
      const bool seam = c < seam_columns || c >= m.columns() - seam_columns;
      if (seam) continue;
      ++inside;
      ASSERT_TRUE(cell.has_value()) << "ring " << r << " column " << c;
      ASSERT_EQ(*cell, i) << "ring " << r << " column " << c;
      const auto probe = moving.probe(x, 0.02);
      ASSERT_EQ(probe.visibility, Visibility::kOccupied) << "ring " << r << " column " << c;
      EXPECT_LT(probe.lateral_m, 0.05);
      EXPECT_NEAR(probe.beyond_m, 0.0, 0.02);
      // Along its own beam: a metre short of the wall is seen free, a metre behind is occluded.
      const BeamRay ray = moving.cell_ray(r, c);
      const double range = scan.range_m(i);
      if (range > 2.0) {
        EXPECT_EQ(moving.at(ray.origin + (range - 1.0) * ray.direction, 0.3), Visibility::kFree);
        EXPECT_EQ(moving.at(ray.origin + (range + 1.0) * ray.direction, 0.3),
                  Visibility::kOccluded);
      }
    }
  }
  ASSERT_GT(returns, 5000);
  EXPECT_GT(inside, returns * 8 / 10);
  // Without the per-column poses most of the wall is misjudged: the test has teeth.
  EXPECT_GT(frozen_wrong, returns / 3);
}

TEST(VisibilityMotion, BoxesMatchTheNaiveReferenceOverEveryCell) {
  const SensorModel m = SensorModel::vlp16();
  const Pose pose = start_pose();
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int nonempty = 0;
  int seen_through = 0;
  int blocked = 0;
  for (int trial = 0; trial < 4; ++trial) {
    Motion motion;
    motion.velocity_mps = {8 * (u(rng) - 0.5), 8 * (u(rng) - 0.5), u(rng) - 0.5};
    motion.angular_velocity_radps = {0.4 * (u(rng) - 0.5), 0.4 * (u(rng) - 0.5),
                                     3.0 * (u(rng) - 0.5)};
    const OrganizedScan scan = swept_wall(m, pose, motion);
    const VisibilityQuery q(scan, m, pose, motion);
    for (int b = 0; b < 40; ++b) {
      const double dist = 0.5 + 12.0 * u(rng);
      const double az = 2 * std::numbers::pi * u(rng);
      const Eigen::Vector3d centre =
          pose.isometry() *
          Eigen::Vector3d(dist * std::cos(az), dist * std::sin(az), 3 * (u(rng) - 0.5));
      const Eigen::Vector3d half(0.05 + u(rng), 0.05 + u(rng), 0.05 + u(rng));
      const Box3 box{(centre - half).cast<float>(), (centre + half).cast<float>()};
      // Reference: every cell's beam (cell_ray, checked against Eigen above) by slabs.
      std::vector<std::size_t> cells;
      const VisibilityCounts want = testing::naive_in_box(q, box, 0.1, cells);
      ASSERT_EQ(q.in_box(box, 0.1), want) << "trial " << trial << " box " << b;
      nonempty += want.total() > 0 ? 1 : 0;
      // seen_through_box stops at the first blocking beam but must say what the counts say.
      const bool through = want.free > 0 && want.occupied == 0 && want.occluded == 0;
      ASSERT_EQ(q.seen_through_box(box, 0.1), through) << "trial " << trial << " box " << b;
      seen_through += through ? 1 : 0;
      blocked += want.occupied + want.occluded > 0 ? 1 : 0;
    }
  }
  EXPECT_GT(nonempty, 80);
  EXPECT_GT(seen_through, 10);
  EXPECT_GT(blocked, 5);  // measured: 9 of 160 boxes (the only surface is the wall)
}

TEST(VisibilityMotion, AStillSensorOrAScanWithoutTimesUsesTheScanPose) {
  const SensorModel m = SensorModel::vlp16();
  const Pose pose = start_pose();
  OrganizedScan scan = swept_wall(m, pose, turning());
  EXPECT_FALSE(VisibilityQuery(scan, m, pose, Motion{}).per_column_poses());
  // A scan built without times keeps zero stamps: they place no column on the path.
  std::fill(scan.column_stamp_ns.begin(), scan.column_stamp_ns.end(), 0);
  EXPECT_FALSE(VisibilityQuery(scan, m, pose, turning()).per_column_poses());
  scan.column_stamp_ns.clear();
  EXPECT_FALSE(VisibilityQuery(scan, m, pose, turning()).per_column_poses());
}

TEST(VisibilityMotion, NonFiniteMotionIsAnError) {
  const SensorModel m = SensorModel::vlp16();
  const Pose pose = start_pose();
  const OrganizedScan scan = swept_wall(m, pose, turning());
  Motion bad = turning();
  bad.angular_velocity_radps.y() = std::numeric_limits<double>::quiet_NaN();
  try {
    const VisibilityQuery q(scan, m, pose, bad);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("motion"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("5000000000 ns"), std::string::npos) << e.what();
  }
}

TEST(Motion, BetweenTwoPosesReproducesTheirInterpolation) {
  const Pose a = start_pose();
  Pose b;
  b.stamp_ns = a.stamp_ns + 100'000'000;
  b.translation = a.translation + Eigen::Vector3d(0.4, -0.3, 0.05);
  b.rotation =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.3, -0.1, 1.0).normalized())) *
      a.rotation;
  const Motion m = Motion::between(a, b);
  for (const double t : {0.0, 0.25, 0.5, 1.0, 1.5}) {
    const Pose want = Pose::interpolate(a, b, t);
    const Pose got = m.advance(a, 0.1 * t);
    EXPECT_LT((got.translation - want.translation).norm(), 1e-12) << t;
    EXPECT_LT(got.rotation.angularDistance(want.rotation), 1e-9) << t;
  }
  // Not later, or not finite: still.
  EXPECT_TRUE(Motion::between(b, a).still());
  EXPECT_TRUE(Motion::between(a, a).still());
  Pose nan = b;
  nan.translation.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(Motion::between(a, nan).still());
}

// ---------------------------------------------------------------------------------------------
// RecentViews: a moving sensor's memory of what its earlier scans saw through.

// A sensor flying along +y at 2 m/s, 2.5 m up, turning slowly: scan k starts at 0.1 k s.
constexpr std::int64_t kScanNs = 100'000'000;

Motion flight() {
  Motion m;
  m.velocity_mps = {0.0, 2.0, 0.0};
  m.angular_velocity_radps = {0.0, 0.0, 0.2};
  return m;
}

Pose flight_pose(int k) {
  Pose start;
  start.stamp_ns = 1'000'000'000;
  start.translation = {0.0, -3.0, 2.5};
  return flight().advance(start, 1e-9 * static_cast<double>(k * kScanNs));
}

struct Flight {
  SensorModel model = SensorModel::vlp16();
  BackgroundRangeConfig config{};
  RecentViews views{model, config};
  Flight() = default;
  explicit Flight(const BackgroundRangeConfig& c) : config(c), views(model, c) {
    views.set_ground_z(0.0);
  }
  // Adds scans 0 .. count-1 of the scene to the memory.
  void fly(int count, const Scene& scene) {
    for (int k = 0; k < count; ++k) {
      views.add(swept_scan(model, flight_pose(k), flight(), scene), flight_pose(k), flight());
    }
  }
  // How many of the returns of scan k inside `region` the memory says were seen free before.
  std::pair<int, int> new_points(int k, const Scene& scene, const Eigen::AlignedBox3d& region) {
    const OrganizedScan scan = swept_scan(model, flight_pose(k), flight(), scene);
    const VisibilityQuery now(scan, model, flight_pose(k), flight());
    int inside = 0;
    int fresh = 0;
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (!scan.valid(i)) continue;
      const Eigen::Vector3d x = now.world_point(i);
      if (!region.contains(x)) continue;
      ++inside;
      fresh += views.seen_free_before(scan, i, x, 0.3) ? 1 : 0;
    }
    return {inside, fresh};
  }
};

const Eigen::AlignedBox3d kPersonBox(Eigen::Vector3d(7.0, 0.3, 0.0),
                                     Eigen::Vector3d(7.4, 0.7, 1.8));

TEST(RecentViews, APersonWhereEarlierScansSawThroughIsNew) {
  Flight f;
  const Scene empty{true, std::nullopt, std::nullopt};
  f.fly(10, empty);
  Scene with_person = empty;
  with_person.person = kPersonBox;
  const auto [inside, fresh] = f.new_points(10, with_person, kPersonBox);
  ASSERT_GT(inside, 20);
  // A third of its points (32 of 90) lie within 5 cm of a beam of scan 5 or scan 0 that saw
  // the wall through that space; the others had no beam of theirs close enough to say.
  EXPECT_GT(fresh, inside / 4) << fresh << " of " << inside;
}

TEST(RecentViews, APoleSeenFromAMovingSensorIsNotNew) {
  Flight f;
  Scene scene{true, Eigen::Vector2d(7.0, 0.5), std::nullopt};
  f.fly(21, scene);
  const Eigen::AlignedBox3d pole(Eigen::Vector3d(6.8, 0.3, 0.05), Eigen::Vector3d(7.2, 0.7, 3.0));
  const auto [inside, fresh] = f.new_points(21, scene, pole);
  ASSERT_GT(inside, 20);
  EXPECT_EQ(fresh, 0);
}

TEST(RecentViews, TheGroundUnderGrazingBeamsIsNotNew) {
  Flight f;
  const Scene empty{true, std::nullopt, std::nullopt};
  f.fly(21, empty);
  const Eigen::AlignedBox3d ground(Eigen::Vector3d(-30, -30, -0.1), Eigen::Vector3d(30, 30, 0.1));
  const auto [inside, fresh] = f.new_points(21, empty, ground);
  ASSERT_GT(inside, 5000);
  EXPECT_EQ(fresh, 0);
}

// The per-point test alone (a lateral tolerance of 0: no earlier beam ever passes exactly through
// a point) against the column test alone: where the person now stands, the earlier scans' beams
// passed through the columns under its hits and ended at the wall.
BackgroundRangeConfig column_only(double half_width_m) {
  BackgroundRangeConfig c;
  c.moving_lateral_m = 0.0;
  c.moving_column_m = half_width_m;
  return c;
}

TEST(RecentViews, TheColumnUnderAHitTellsWhereNoEarlierBeamPassedTheHitItself) {
  const Scene empty{true, std::nullopt, std::nullopt};
  Scene with_person = empty;
  with_person.person = kPersonBox;
  // Hits at least 0.35 m up have a column of 0.05 m or more above moving_column_ground_m (0.2 m).
  const Eigen::AlignedBox3d upper(Eigen::Vector3d(7.0, 0.3, 0.35), Eigen::Vector3d(7.4, 0.7, 1.8));
  Flight without(column_only(0.0));
  without.fly(10, empty);
  EXPECT_EQ(without.new_points(10, with_person, upper).second, 0);
  Flight with(column_only(0.1));
  with.fly(10, empty);
  const auto [inside, fresh] = with.new_points(10, with_person, upper);
  ASSERT_GT(inside, 20);
  EXPECT_GT(fresh * 10, inside * 9) << fresh << " of " << inside;
}

TEST(RecentViews, AnObjectThatStoodThereAllAlongFillsItsColumns) {
  // The same box, present in every earlier scan (a parked crate, a bush): the beams under its
  // hits ended on it, so none of its points is new; nor is a pole's or the ground's.
  Scene standing{true, Eigen::Vector2d(5.0, -1.0), kPersonBox};
  Flight f(column_only(0.1));
  f.fly(21, standing);
  const auto [inside, fresh] = f.new_points(21, standing, kPersonBox);
  ASSERT_GT(inside, 20);
  EXPECT_EQ(fresh, 0);
  const Eigen::AlignedBox3d pole(Eigen::Vector3d(4.8, -1.2, 0.05), Eigen::Vector3d(5.2, -0.8, 3.0));
  const auto [pole_inside, pole_fresh] = f.new_points(21, standing, pole);
  ASSERT_GT(pole_inside, 5);
  EXPECT_EQ(pole_fresh, 0);
  const Eigen::AlignedBox3d ground(Eigen::Vector3d(-30, -30, -0.1), Eigen::Vector3d(30, 30, 0.1));
  EXPECT_EQ(f.new_points(21, standing, ground).second, 0);
}

TEST(RecentViews, WhereAnEarlierBeamHitThePointItselfTheColumnIsNotAsked) {
  // A box floating 1.2-1.8 m up (a sign, an overhang), there all along: the space under it is
  // empty, so by its columns alone its hits would be new. An earlier beam that passed within
  // moving_lateral_m of a hit and ended at it says something stood there, and the column is not
  // asked: only hits no earlier beam passed closely are left to the column.
  const Eigen::AlignedBox3d floating(Eigen::Vector3d(7.0, 0.3, 1.2),
                                     Eigen::Vector3d(7.4, 0.7, 1.8));
  Scene scene{true, std::nullopt, floating};
  Flight column_alone(column_only(0.1));  // no earlier beam passes a hit within 0 m
  column_alone.fly(21, scene);
  const auto [inside, fresh] = column_alone.new_points(21, scene, floating);
  ASSERT_GT(inside, 10);
  EXPECT_GE(fresh * 3, inside) << fresh << " of " << inside;  // measured: 9 of 18
  BackgroundRangeConfig wide = column_only(0.1);
  wide.moving_lateral_m = 1.0;  // every hit has an earlier beam this close
  Flight f(wide);
  f.fly(21, scene);
  EXPECT_LE(f.new_points(21, scene, floating).second, 1);  // measured: 1
}

TEST(RecentViews, OnlyScansAtTheLagsAnswerAndResetForgets) {
  Flight f;
  const Scene empty{true, std::nullopt, std::nullopt};
  Scene with_person = empty;
  with_person.person = kPersonBox;
  f.fly(4, empty);  // lag 5 is not there yet
  EXPECT_EQ(f.new_points(4, with_person, kPersonBox).second, 0);
  f.fly(10, empty);
  EXPECT_GT(f.new_points(10, with_person, kPersonBox).second, 0);
  f.views.reset();
  EXPECT_EQ(f.views.scans(), 0U);
  EXPECT_EQ(f.new_points(10, with_person, kPersonBox).second, 0);
}

TEST(RecentViews, RejectsOutOfRangeSettings) {
  BackgroundRangeConfig c;
  c.moving_lag_scans = 0;
  EXPECT_THROW(RecentViews(SensorModel::vlp16(), c), ConfigError);
  c = {};
  c.moving_lateral_m = -0.1;
  EXPECT_THROW(RecentViews(SensorModel::vlp16(), c), ConfigError);
  c = {};
  c.moving_clearance_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(RecentViews(SensorModel::vlp16(), c), ConfigError);
  c = {};
  c.moving_column_m = -0.1;
  EXPECT_THROW(RecentViews(SensorModel::vlp16(), c), ConfigError);
  c = {};
  c.moving_column_ground_m = std::numeric_limits<double>::infinity();
  EXPECT_THROW(RecentViews(SensorModel::vlp16(), c), ConfigError);
}

}  // namespace
}  // namespace ringtrack::core
