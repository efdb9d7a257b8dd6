#include "ringtrack/core/visibility.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "ringtrack/core/error.hpp"
#include "support/naive_visibility.hpp"

namespace ringtrack::core {
namespace {

using testing::naive_in_box;

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

// Every cell returns at range_m: a cylinder-like "wall" at that distance along every beam.
OrganizedScan wall_scan(const SensorModel& m, float range_m) {
  OrganizedScan s(m.rings(), m.columns());
  s.set_uniform_columns(m, 0);
  for (int r = 0; r < m.rings(); ++r) {
    for (int c = 0; c < m.columns(); ++c) s.set_range(m, r, c, range_m, 1.0f);
  }
  return s;
}

Eigen::Vector3d beam_point(const SensorModel& m, int ring, double azimuth_rad, double d) {
  return m.point(ring, azimuth_rad, d).cast<double>();
}

// A point at distance d from ring's beam origin, at elevation el and firing azimuth az (double
// precision, unlike SensorModel::point).
Eigen::Vector3d exact_point(const SensorModel& m, int ring, double az, double el, double d) {
  const double a = az + m.azimuth_offset_rad[static_cast<std::size_t>(ring)];
  return {d * std::cos(el) * std::cos(a), d * std::cos(el) * std::sin(a),
          d * std::sin(el) + m.vertical_offset_m[static_cast<std::size_t>(ring)]};
}

Pose make_pose(const Eigen::Vector3d& t, const Eigen::Vector3d& axis, double angle_rad) {
  Pose p;
  p.translation = t;
  p.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, axis.normalized()));
  return p;
}

double circular_distance(double a, double b) {
  const double d = std::abs(std::remainder(a - b, 2.0 * kPi));
  return d;
}

int naive_nearest_column(const OrganizedScan& s, double az) {
  int best = 0;
  double best_d = std::numeric_limits<double>::infinity();
  for (int c = 0; c < s.columns(); ++c) {
    const double d = circular_distance(az, s.column_azimuth_rad[static_cast<std::size_t>(c)]);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

std::optional<int> naive_ring(const SensorModel& m, const Eigen::Vector3d& p) {
  const int n = m.rings();
  const double nominal = (m.elevation_rad.back() - m.elevation_rad.front()) / (n - 1);
  std::optional<int> best;
  double best_dev = 1e9;
  for (int r = 0; r < n; ++r) {
    const auto i = static_cast<std::size_t>(r);
    const double below = r == 0 ? nominal : m.elevation_rad[i] - m.elevation_rad[i - 1];
    const double above = r == n - 1 ? nominal : m.elevation_rad[i + 1] - m.elevation_rad[i];
    const double el = std::atan2(p.z() - m.vertical_offset_m[i], std::hypot(p.x(), p.y()));
    const double dev = el - m.elevation_rad[i];
    if (dev < -below / 2 || dev > above / 2) continue;
    if (std::abs(dev) < best_dev) {
      best_dev = std::abs(dev);
      best = r;
    }
  }
  return best;
}

// ---------------------------------------------------------------------------------------------

TEST(Visibility, WallAtTenMetresFreeOccupiedOccluded) {
  const auto m = SensorModel::generic({-10, -5, 0, 5, 10}, 360);
  const auto scan = wall_scan(m, 10.0f);
  const VisibilityQuery q(scan, m, Pose{});
  const double az = 37 * kDeg;
  EXPECT_EQ(q.at(beam_point(m, 2, az, 5.0), 0.3), Visibility::kFree);
  EXPECT_EQ(q.at(beam_point(m, 2, az, 10.0), 0.3), Visibility::kOccupied);
  EXPECT_EQ(q.at(beam_point(m, 2, az, 10.25), 0.3), Visibility::kOccupied);
  EXPECT_EQ(q.at(beam_point(m, 2, az, 9.75), 0.3), Visibility::kOccupied);
  EXPECT_EQ(q.at(beam_point(m, 2, az, 10.5), 0.3), Visibility::kOccluded);
  EXPECT_EQ(q.at(beam_point(m, 2, az, 9.5), 0.3), Visibility::kFree);
  EXPECT_EQ(q.at(beam_point(m, 2, az, 15.0), 0.3), Visibility::kOccluded);
  EXPECT_EQ(q.cell_of(beam_point(m, 2, az, 5.0)), scan.index(2, 37));
  EXPECT_NEAR(*q.beam_distance(beam_point(m, 2, az, 5.0)), 5.0, 1e-5);
  // Between beams, the nearest beam answers.
  EXPECT_EQ(q.at(exact_point(m, 4, 200.3 * kDeg, 11 * kDeg, 5.0), 0.3), Visibility::kFree);
  EXPECT_EQ(q.cell_of(exact_point(m, 4, 200.3 * kDeg, 11 * kDeg, 5.0)), scan.index(4, 200));
  EXPECT_THROW((void)q.at(Eigen::Vector3d(5, 0, 0), -0.1), Error);
  EXPECT_STREQ(to_string(Visibility::kOccluded), "occluded");
}

TEST(Visibility, ProbeGivesTheBeamsLateralDistance) {
  const auto m = SensorModel::generic({-10, -5, 0, 5, 10}, 360);
  const auto scan = wall_scan(m, 10.0f);
  const Pose pose = make_pose({1, 2, 0.5}, {0, 0, 1}, 0.4);
  const VisibilityQuery q(scan, m, pose);
  const auto world = [&](const Eigen::Vector3d& p) { return pose.isometry() * p; };
  // On a beam: no lateral offset, the verdict of at().
  const auto on = q.probe(world(beam_point(m, 2, 37 * kDeg, 5.0)), 0.3);
  EXPECT_EQ(on.visibility, Visibility::kFree);
  EXPECT_NEAR(on.lateral_m, 0.0, 1e-5);
  // 2 degrees above ring 2 (elevation 0) at 5 m: the nearest beam (ring 2) passes
  // 5 sin(2 deg) = 0.1745 m below the point.
  const auto off = q.probe(world(exact_point(m, 2, 37 * kDeg, 2 * kDeg, 5.0)), 0.3);
  EXPECT_EQ(off.visibility, Visibility::kFree);
  EXPECT_NEAR(off.lateral_m, 5.0 * std::sin(2 * kDeg), 1e-4);
  // The world point of a cell is the scan's point moved by the pose.
  const auto i = scan.index(3, 100);
  EXPECT_NEAR((q.world_point(i) - world(scan.point(i).cast<double>())).norm(), 0.0, 1e-6);
  EXPECT_EQ(q.probe(world(Eigen::Vector3d(0, 0, 20)), 0.3).visibility, Visibility::kUnknown);
}

TEST(Visibility, AboveTopAndBelowBottomRingAreUnknown) {
  const auto m = SensorModel::vlp16();
  const auto scan = wall_scan(m, 10.0f);
  const VisibilityQuery q(scan, m, Pose{});
  const double az = 1.0;
  // Top ring at +15 deg: accepted up to 16 deg (half the 2-degree gap), seen from its origin.
  EXPECT_EQ(q.at(exact_point(m, 15, az, 15.9 * kDeg, 5.0), 0.1), Visibility::kFree);
  EXPECT_EQ(q.ring_of_sensor_point(exact_point(m, 15, az, 15.9 * kDeg, 5.0)), 15);
  EXPECT_EQ(q.at(exact_point(m, 15, az, 16.1 * kDeg, 5.0), 0.1), Visibility::kUnknown);
  EXPECT_FALSE(q.cell_of(exact_point(m, 15, az, 16.1 * kDeg, 5.0)).has_value());
  EXPECT_EQ(q.ring_of_sensor_point(exact_point(m, 0, az, -15.9 * kDeg, 5.0)), 0);
  EXPECT_EQ(q.at(exact_point(m, 0, az, -16.1 * kDeg, 5.0), 0.1), Visibility::kUnknown);
  EXPECT_EQ(q.at(Eigen::Vector3d(0, 0, 3), 0.1), Visibility::kUnknown);   // straight up
  EXPECT_EQ(q.at(Eigen::Vector3d(0, 0, -3), 0.1), Visibility::kUnknown);  // straight down
}

// Each cell has its own range, so a ring or column off by one changes the verdict.
TEST(Visibility, RingAndColumnBoundariesAreExact) {
  const auto m = SensorModel::generic({-6, -4, -2, 0, 2, 4, 6}, 720);  // 2 deg, 0.5 deg
  OrganizedScan scan(m.rings(), m.columns());
  scan.set_uniform_columns(m, 0);
  auto range_of = [](int r, int c) {
    return 5.0f + 2.0f * static_cast<float>(r) + 0.1f * static_cast<float>(c % 5);
  };
  for (int r = 0; r < m.rings(); ++r) {
    for (int c = 0; c < m.columns(); ++c) scan.set_range(m, r, c, range_of(r, c), 1.0f);
  }
  const VisibilityQuery q(scan, m, Pose{});
  const double step = 0.5 * kDeg;
  for (int r : {0, 3, 5}) {
    for (int c : {0, 11, 719}) {
      const double az = c * step;
      const double el = m.elevation_rad[static_cast<std::size_t>(r)];
      auto check = [&](double d_az, double d_el, int want_r, int want_c) {
        want_c = (want_c + 720) % 720;
        const double d = range_of(want_r, want_c);
        const auto p = exact_point(m, r, az + d_az, el + d_el, d);
        EXPECT_EQ(q.cell_of(p), scan.index(want_r, want_c))
            << r << " " << c << " " << d_az << " " << d_el;
        EXPECT_EQ(q.at(p, 0.01), Visibility::kOccupied) << r << " " << c;
      };
      check(0.0, 0.0, r, c);
      check(0.45 * step, 0.0, r, c);
      check(0.55 * step, 0.0, r, c + 1);
      check(-0.45 * step, 0.0, r, c);
      check(-0.55 * step, 0.0, r, c - 1);
      check(0.0, 0.9 * kDeg, r, c);
      check(0.0, -0.9 * kDeg, r, c);
      if (r + 1 < m.rings()) check(0.0, 1.1 * kDeg, r + 1, c);
      if (r > 0) check(0.0, -1.1 * kDeg, r - 1, c);
    }
  }
}

TEST(Visibility, NoReturnCellsAreReportedSeparately) {
  const auto m = SensorModel::generic({-2, 0, 2}, 360);
  auto scan = wall_scan(m, 10.0f);
  scan.set_invalid(1, 10, ReturnStatus::kNoReturn);
  scan.set_invalid(1, 11, ReturnStatus::kTooFar);
  scan.set_invalid(1, 12, ReturnStatus::kTooClose);
  const VisibilityQuery q(scan, m, Pose{});
  EXPECT_EQ(q.at(beam_point(m, 1, 10 * kDeg, 5.0), 0.2), Visibility::kNoReturn);
  EXPECT_EQ(q.at(beam_point(m, 1, 11 * kDeg, 5.0), 0.2), Visibility::kNoReturn);
  EXPECT_EQ(q.at(beam_point(m, 1, 12 * kDeg, 5.0), 0.2), Visibility::kUnknown);
  EXPECT_EQ(q.at(beam_point(m, 1, 13 * kDeg, 5.0), 0.2), Visibility::kFree);
  EXPECT_EQ(q.cell_of(beam_point(m, 1, 12 * kDeg, 5.0)), scan.index(1, 12));
}

TEST(Visibility, SeamNearZeroAndNearPi) {
  const auto m = SensorModel::generic({-1, 1}, 360);
  // Columns from 0: the seam between column 359 (359 deg) and column 0 (0 deg).
  {
    const auto scan = wall_scan(m, 10.0f);
    const VisibilityQuery q(scan, m, Pose{});
    EXPECT_EQ(q.column_of_azimuth(-0.4 * kDeg), 0);
    EXPECT_EQ(q.column_of_azimuth(-0.6 * kDeg), 359);
    EXPECT_EQ(q.column_of_azimuth(359.6 * kDeg), 0);
    EXPECT_EQ(q.column_of_azimuth(4 * kPi + 0.3 * kDeg), 0);
    EXPECT_EQ(q.cell_of(exact_point(m, 1, -0.3 * kDeg, 1 * kDeg, 5)), scan.index(1, 0));
  }
  // Columns from -pi (a capture starting behind the sensor): the seam sits at +-pi.
  {
    auto scan = wall_scan(m, 10.0f);
    for (int c = 0; c < 360; ++c)
      scan.column_azimuth_rad[static_cast<std::size_t>(c)] = -kPi + c * kDeg;
    for (int r = 0; r < 2; ++r) {
      for (int c = 0; c < 360; ++c)
        scan.set_range(m, r, c, 5.0f + 0.1f * static_cast<float>(c % 3), 1.0f);
    }
    const VisibilityQuery q(scan, m, Pose{});
    EXPECT_EQ(q.column_of_azimuth(kPi - 0.3 * kDeg), 0);
    EXPECT_EQ(q.column_of_azimuth(-kPi + 0.3 * kDeg), 0);
    EXPECT_EQ(q.column_of_azimuth(kPi - 0.7 * kDeg), 359);
    EXPECT_EQ(q.column_of_azimuth(-kPi + 0.7 * kDeg), 1);
    const auto p = exact_point(m, 0, kPi - 0.7 * kDeg, -1 * kDeg, 5.0f + 0.1f * (359 % 3));
    EXPECT_EQ(q.cell_of(p), scan.index(0, 359));
    EXPECT_EQ(q.at(p, 0.01), Visibility::kOccupied);
  }
}

// A real capture: columns count firing sequences from an arbitrary start, azimuths jitter and
// wrap past 2 pi; a run of columns is missing (dropped packets).
TEST(Visibility, NonUniformColumnsMatchNearestColumn) {
  const auto m = SensorModel::vlp16();
  const int n = 1809;
  OrganizedScan scan(m.rings(), n);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  const double step = m.azimuth_step_rad();
  for (int c = 0; c < n; ++c) {
    scan.column_azimuth_rad[static_cast<std::size_t>(c)] = 0.7 + (c + jitter(rng)) * step;
  }
  const VisibilityQuery q(scan, m, Pose{});
  EXPECT_NEAR(q.nominal_column_step_rad(), step, 0.2 * step);
  std::uniform_real_distribution<double> any(-10.0, 10.0);
  for (int k = 0; k < 4000; ++k) {
    const double az = any(rng);
    ASSERT_EQ(q.column_of_azimuth(az), naive_nearest_column(scan, az)) << az;
  }
  // The exact azimuth of every column maps to itself.
  for (int c = 0; c < n; ++c) {
    ASSERT_EQ(q.column_of_azimuth(scan.column_azimuth_rad[static_cast<std::size_t>(c)]), c);
  }

  // Drop columns 100..119: inside the gap unknown, within half a step of its ends the end column.
  OrganizedScan gappy(m.rings(), n - 20);
  for (int c = 0, k = 0; c < n; ++c) {
    if (c >= 100 && c < 120) continue;
    gappy.column_azimuth_rad[static_cast<std::size_t>(k++)] = 0.7 + c * step;
  }
  const VisibilityQuery g(gappy, m, Pose{});
  EXPECT_NEAR(g.nominal_column_step_rad(), step, 1e-9);
  EXPECT_EQ(g.column_of_azimuth(0.7 + 99.4 * step), 99);
  EXPECT_FALSE(g.column_of_azimuth(0.7 + 99.6 * step).has_value());
  EXPECT_FALSE(g.column_of_azimuth(0.7 + 110 * step).has_value());
  EXPECT_FALSE(g.column_of_azimuth(0.7 + 119.4 * step).has_value());
  EXPECT_EQ(g.column_of_azimuth(0.7 + 119.6 * step), 100);  // column 120 is stored at 100
}

TEST(Visibility, PartialRevolutionLeavesTheRestUnknown) {
  const auto m = SensorModel::generic({-1, 1}, 360);
  OrganizedScan scan(2, 90);  // 0..89 degrees only
  for (int c = 0; c < 90; ++c) {
    scan.column_azimuth_rad[static_cast<std::size_t>(c)] = c * kDeg;
    for (int r = 0; r < 2; ++r) scan.set_range(m, r, c, 10.0f, 1.0f);
  }
  const VisibilityQuery q(scan, m, Pose{});
  EXPECT_EQ(q.at(exact_point(m, 0, 45 * kDeg, -1 * kDeg, 5), 0.1), Visibility::kFree);
  EXPECT_EQ(q.at(exact_point(m, 0, 89.4 * kDeg, -1 * kDeg, 5), 0.1), Visibility::kFree);
  EXPECT_EQ(q.at(exact_point(m, 0, 89.6 * kDeg, -1 * kDeg, 5), 0.1), Visibility::kUnknown);
  EXPECT_EQ(q.at(exact_point(m, 0, 180 * kDeg, -1 * kDeg, 5), 0.1), Visibility::kUnknown);
  EXPECT_EQ(q.at(exact_point(m, 0, -0.4 * kDeg, -1 * kDeg, 5), 0.1), Visibility::kFree);
}

TEST(Visibility, MovedAndRotatedSensor) {
  const auto m = SensorModel::vlp16();
  OrganizedScan scan(m.rings(), m.columns());
  scan.set_uniform_columns(m, 0);
  for (int r = 0; r < m.rings(); ++r) {
    for (int c = 0; c < m.columns(); ++c)
      scan.set_range(m, r, c,
                     4.0f + 0.5f * static_cast<float>(r) + 0.01f * static_cast<float>(c % 3), 1.0f);
  }
  const Pose pose = make_pose({3.0, -2.0, 1.5}, {0.1, -0.2, 1.0}, 1.1);
  const VisibilityQuery q(scan, m, pose);
  const Eigen::Isometry3d w_T_s = pose.isometry();
  const double step = m.azimuth_step_rad();
  for (int r : {0, 7, 8, 15}) {
    for (int c : {0, 5, 903, 1807}) {
      const auto i = scan.index(r, c);
      const double range = scan.range_m(i);
      const Eigen::Vector3d at_range = w_T_s * beam_point(m, r, c * step, range);
      EXPECT_EQ(q.cell_of(at_range), i);
      EXPECT_EQ(q.at(at_range, 0.005), Visibility::kOccupied);
      EXPECT_EQ(q.at(w_T_s * beam_point(m, r, c * step, range - 0.5), 0.005), Visibility::kFree);
      EXPECT_EQ(q.at(w_T_s * beam_point(m, r, c * step, range + 0.5), 0.005),
                Visibility::kOccluded);
      // The sensor-frame point given as a world point is a different place.
      EXPECT_NE(q.cell_of(beam_point(m, r, c * step, range)), std::optional<std::size_t>(i));
      // cell_ray reproduces the scan's own points in the world.
      const BeamRay ray = q.cell_ray(r, c);
      EXPECT_NEAR(ray.direction.norm(), 1.0, 1e-12);
      const Eigen::Vector3d end = ray.origin + range * ray.direction;
      EXPECT_LT((end - w_T_s * scan.point(i).cast<double>()).norm(), 1e-5);
    }
  }
}

TEST(Visibility, Vlp16VerticalOffsetsAtShortRange) {
  const auto m = SensorModel::vlp16();
  const auto scan = wall_scan(m, 10.0f);  // only the geometry matters here
  const VisibilityQuery q(scan, m, Pose{});
  const double step = m.azimuth_step_rad();
  for (int r = 0; r < 16; ++r) {
    for (double d : {0.35, 0.5, 1.0, 5.0, 60.0}) {
      const int c = 3 * r + 100;
      const auto p = exact_point(m, r, c * step, m.elevation_rad[static_cast<std::size_t>(r)], d);
      ASSERT_EQ(q.cell_of(p), scan.index(r, c)) << r << " " << d;
      EXPECT_NEAR(*q.beam_distance(p), d, 1e-9);
    }
  }
  // Ring 0 (offset +11.2 mm) at 0.4 m: seen from the sensor origin the point is 1.6 deg above
  // the ring (nearer ring 1, which has no return here); from its own origin it is on the beam.
  OrganizedScan close(m.rings(), m.columns());
  close.set_uniform_columns(m, 0);
  close.set_range(m, 0, 50, 0.4f, 1.0f);
  const VisibilityQuery qc(close, m, Pose{});
  const Eigen::Vector3d p = close.point(close.index(0, 50)).cast<double>();
  EXPECT_EQ(qc.at(p, 0.001), Visibility::kOccupied);
  EXPECT_EQ(qc.at(exact_point(m, 0, 50 * step, -15 * kDeg, 0.39), 0.001), Visibility::kFree);

  // Pruned ring search equals evaluating every ring, also very close to the sensor.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < 20000; ++k) {
    const double scale = k % 2 ? 0.05 : 3.0;
    const Eigen::Vector3d s(scale * u(rng), scale * u(rng), 0.4 * scale * u(rng));
    ASSERT_EQ(q.ring_of_sensor_point(s), naive_ring(m, s)) << s.transpose();
  }
}

TEST(Visibility, Vlp32cAzimuthOffsets) {
  const auto m = SensorModel::vlp32c();
  OrganizedScan scan(m.rings(), m.columns());
  scan.set_uniform_columns(m, 0);
  for (int r = 0; r < m.rings(); ++r) {
    for (int c = 0; c < m.columns(); ++c)
      scan.set_range(m, r, c, 6.0f + 0.01f * static_cast<float>(c % 5), 1.0f);
  }
  const VisibilityQuery q(scan, m, Pose{});
  const double step = m.azimuth_step_rad();
  for (int r = 0; r < m.rings(); ++r) {
    const int c = 50 * r + 7;
    const auto i = scan.index(r, c);
    const Eigen::Vector3d p = scan.point(i).cast<double>();
    ASSERT_EQ(q.cell_of(p), i) << r;
    EXPECT_EQ(q.at(p, 0.003), Visibility::kOccupied);
    const BeamRay ray = q.cell_ray(r, c);
    EXPECT_LT((ray.origin + scan.range_m(i) * ray.direction - p).norm(), 1e-5);
  }
  (void)step;
}

TEST(Visibility, BoxesAgainstAWall) {
  const auto m = SensorModel::vlp16();
  const auto scan = wall_scan(m, 10.0f);
  const VisibilityQuery q(scan, m, Pose{});
  auto person = [](double x) {
    return Box3{Eigen::Vector3f(static_cast<float>(x) - 0.25f, -0.3f, -0.8f),
                Eigen::Vector3f(static_cast<float>(x) + 0.25f, 0.3f, 0.9f)};
  };
  std::vector<std::size_t> ref;
  const auto near = q.in_box(person(5.0), 0.2);
  EXPECT_GT(near.total(), 50);
  EXPECT_EQ(near.free, near.total());
  const auto at_wall = q.in_box(person(9.9), 0.2);
  EXPECT_GT(at_wall.occupied, 0);
  EXPECT_EQ(at_wall.occluded, 0);
  const auto behind = q.in_box(person(15.0), 0.2);
  EXPECT_EQ(behind.occluded, behind.total());
  EXPECT_GT(behind.total(), 0);
  for (double x : {5.0, 9.9, 15.0}) {
    EXPECT_EQ(q.in_box(person(x), 0.2), naive_in_box(q, person(x), 0.2, ref));
  }
  // A box around the sensor: every beam starts inside it.
  const Box3 around{Eigen::Vector3f(-1, -1, -1), Eigen::Vector3f(1, 1, 1)};
  const auto all = q.in_box(around, 0.2);
  EXPECT_EQ(all.total(), m.rings() * m.columns());
  EXPECT_EQ(all.free, all.total());
  EXPECT_EQ(q.in_box(Box3{}, 0.2).total(), 0);
  // Straddling the seam behind... and in front (azimuth 0 is column 0's side).
  const Box3 seam{Eigen::Vector3f(4.8f, -0.3f, -0.5f), Eigen::Vector3f(5.2f, 0.3f, 0.5f)};
  std::vector<BoxBeam> beams;
  q.cells_in_box(seam, 0.2, beams);
  bool low = false;
  bool high = false;
  for (const auto& b : beams) {
    low |= scan.column_of(b.cell) < 10;
    high |= scan.column_of(b.cell) > m.columns() - 10;
    EXPECT_GE(b.exit_m, b.entry_m);
  }
  EXPECT_TRUE(low && high);
  EXPECT_EQ(q.in_box(seam, 0.2), naive_in_box(q, seam, 0.2, ref));
  EXPECT_EQ(beams.size(), ref.size());
}

struct RandomCase {
  SensorModel model;
  bool jitter_columns;
  double first_azimuth_rad;
};

OrganizedScan random_scan(const SensorModel& m, bool jitter, double first_az, std::mt19937& rng) {
  const int n = m.columns() + (jitter ? 1 : 0);
  OrganizedScan s(m.rings(), n);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double step = m.azimuth_step_rad();
  for (int c = 0; c < n; ++c) {
    s.column_azimuth_rad[static_cast<std::size_t>(c)] =
        first_az + (c + (jitter ? 0.6 * (u(rng) - 0.5) : 0.0)) * step;
  }
  for (int r = 0; r < m.rings(); ++r) {
    for (int c = 0; c < n; ++c) {
      const double x = u(rng);
      if (x < 0.1) {
        s.set_invalid(r, c, ReturnStatus::kNoReturn);
      } else if (x < 0.15) {
        s.set_invalid(r, c, ReturnStatus::kTooFar);
      } else if (x < 0.2) {
        s.set_invalid(r, c, ReturnStatus::kTooClose);
      } else {
        s.set_range(m, r, c, static_cast<float>(0.5 + 25.0 * u(rng)), 1.0f);
      }
    }
  }
  return s;
}

TEST(Visibility, RandomBoxesMatchTheNaiveReference) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::vector<RandomCase> cases{
      {SensorModel::vlp16(), false, 0.0},
      {SensorModel::vlp16(), true, -kPi},
      {SensorModel::vlp32c(), false, 1.3},
      {SensorModel::generic({-20, -7, -3, 0, 2, 9, 30}, 90), true, 2.0}};
  int boxes = 0;
  int nonempty = 0;
  for (const auto& rc : cases) {
    for (int s = 0; s < 3; ++s) {
      const auto scan = random_scan(rc.model, rc.jitter_columns, rc.first_azimuth_rad, rng);
      const Eigen::Vector3d axis(u(rng) - 0.5, u(rng) - 0.5, 3.0 + u(rng));
      const Pose pose =
          make_pose({10 * (u(rng) - 0.5), 10 * (u(rng) - 0.5), 2 * u(rng)}, axis, 6 * u(rng));
      const VisibilityQuery q(scan, rc.model, pose);
      std::vector<std::size_t> ref_cells;
      std::vector<BoxBeam> beams;
      for (int b = 0; b < 60; ++b) {
        // Sensor-frame centre: mostly around the sensor, some on the seam, some around it.
        Eigen::Vector3d c;
        const double kind = u(rng);
        const double dist = 0.3 + 20.0 * u(rng);
        double az = 2 * kPi * u(rng);
        if (kind < 0.3) az = rc.first_azimuth_rad + 0.01 * (u(rng) - 0.5);  // the seam
        c = Eigen::Vector3d(dist * std::cos(az), dist * std::sin(az), 4 * (u(rng) - 0.5));
        if (kind > 0.9) c = Eigen::Vector3d(0.3 * (u(rng) - 0.5), 0.3 * (u(rng) - 0.5), 0.0);
        const Eigen::Vector3d world_c = pose.isometry() * c;
        const Eigen::Vector3d half(0.05 + 1.5 * u(rng), 0.05 + 1.5 * u(rng), 0.05 + 1.5 * u(rng));
        const Box3 box{(world_c - half).cast<float>(), (world_c + half).cast<float>()};
        const double margin = 0.5 * u(rng);
        const auto want = naive_in_box(q, box, margin, ref_cells);
        const auto got = q.in_box(box, margin);
        ASSERT_EQ(got, want) << rc.model.name << " box " << b << " total " << want.total()
                             << " got " << got.total();
        q.cells_in_box(box, margin, beams);
        std::vector<std::size_t> got_cells;
        for (const auto& beam : beams) got_cells.push_back(beam.cell);
        std::sort(got_cells.begin(), got_cells.end());
        ASSERT_EQ(got_cells, ref_cells);
        ++boxes;
        nonempty += want.total() > 0 ? 1 : 0;
      }
    }
  }
  EXPECT_GT(nonempty, boxes / 2);
}

TEST(Visibility, RejectsMismatchedScansAndBadPoses) {
  const auto m = SensorModel::vlp16();
  const OrganizedScan wrong_rings(32, m.columns());
  EXPECT_THROW(VisibilityQuery(wrong_rings, m, Pose{}), InputError);
  OrganizedScan scan(16, m.columns());
  scan.column_azimuth_rad.pop_back();
  EXPECT_THROW(VisibilityQuery(scan, m, Pose{}), InputError);
  scan.column_azimuth_rad.push_back(std::nan(""));
  EXPECT_THROW(VisibilityQuery(scan, m, Pose{}), InputError);
  scan.column_azimuth_rad.back() = 0.0;
  Pose bad;
  bad.translation.x() = std::numeric_limits<double>::infinity();
  EXPECT_THROW(VisibilityQuery(scan, m, bad), InputError);
  bad = Pose{};
  bad.rotation.w() = std::nan("");
  EXPECT_THROW(VisibilityQuery(scan, m, bad), InputError);
  try {
    VisibilityQuery q(wrong_rings, m, Pose{});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("VLP-16"), std::string::npos);
  }
  EXPECT_NO_THROW(VisibilityQuery(scan, m, Pose{}));
}

// A query over a shared geometry (built for an earlier scan with the same column azimuths) gives
// every answer a query building its own gives; the cache rebuilds when the azimuths change.
TEST(Visibility, SharedBeamGeometryAnswersAsAFreshOne) {
  const auto m = SensorModel::vlp16();
  OrganizedScan earlier = wall_scan(m, 12.0f);
  OrganizedScan scan = wall_scan(m, 7.0f);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> range(1.0f, 30.0f);
  for (int r = 0; r < m.rings(); ++r) {
    for (int c = 0; c < m.columns(); c += 3) scan.set_range(m, r, c, range(rng), 1.0f);
  }
  BeamGeometryCache cache;
  const auto geometry = cache.get(earlier, m);
  EXPECT_EQ(cache.get(scan, m), geometry);  // same azimuths: not rebuilt
  const Pose pose = make_pose({1.0, -2.0, 0.5}, {0.1, 0.2, 1.0}, 0.7);
  const VisibilityQuery fresh(scan, m, pose);
  const VisibilityQuery shared(scan, geometry, pose);
  std::uniform_real_distribution<double> coord(-25.0, 25.0);
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d p(coord(rng), coord(rng), 0.2 * coord(rng));
    ASSERT_EQ(fresh.at(p, 0.2), shared.at(p, 0.2)) << i;
    ASSERT_EQ(fresh.cell_of(p), shared.cell_of(p)) << i;
    const Box3 box{p.cast<float>(), (p + Eigen::Vector3d(0.6, 0.6, 1.8)).cast<float>()};
    ASSERT_EQ(fresh.in_box(box, 0.2), shared.in_box(box, 0.2)) << i;
  }
  EXPECT_EQ(fresh.nominal_column_step_rad(), shared.nominal_column_step_rad());

  OrganizedScan turned = scan;
  for (auto& az : turned.column_azimuth_rad) az += 0.001;
  EXPECT_NE(cache.get(turned, m), geometry);
  const OrganizedScan other_size(16, m.columns() - 1);
  EXPECT_THROW(VisibilityQuery(other_size, geometry, pose), InputError);
  EXPECT_THROW(VisibilityQuery(scan, nullptr, pose), InputError);
}

}  // namespace
}  // namespace ringtrack::core
