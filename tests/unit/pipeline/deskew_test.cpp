// Motion compensation against the simulator's oracle: a sensor flying over flat empty ground.
// Every ground return, deskewed and mapped with the scan pose, must lie on z = 0 within the
// range noise; without compensation the scan is visibly skewed.

#include "ringtrack/pipeline/deskew.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "ringtrack/core/error.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace ringtrack {
namespace {

sim::Scenario flat_flight() {
  sim::Scenario s = sim::builtin_scenario("1");
  s.people = 0;
  s.duration_s = 2.0;
  s.sensor.range_noise_m = 0.0;  // exact geometry: any residual is a deskew error
  s.sensor.dropout_probability = 0.0;
  s.sensor.far_dropout_probability = 0.0;
  return sim::with_moving_sensor(s);
}

// Largest |world z| of the ground returns within 30 m (beyond, float rounding dominates).
double worst_ground_z(const core::OrganizedScan& scan, const core::Pose& pose) {
  double worst = 0.0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i) || scan.range_m(i) > 30.0f) continue;
    worst = std::max(worst, std::abs(static_cast<double>(pose.to_world(scan.point(i)).z())));
  }
  return worst;
}

TEST(Deskew, GroundOfAFlyingSensorLiesFlatAfterCompensation) {
  sim::Simulator simulator(flat_flight(), 3);
  double worst_raw = 0.0, worst_deskewed = 0.0;
  for (int k = 0; k < 15; ++k) {
    sim::SimulatedScan s = simulator.next();
    worst_raw = std::max(worst_raw, worst_ground_z(s.scan, s.pose));
    const core::Pose end = simulator.sensor_pose_at(simulator.scan_stamp_ns(k + 1));
    const core::Pose ref = pipeline::deskew_scan(s.scan, s.pose, end);
    EXPECT_EQ(ref.stamp_ns, s.scan.stamp_ns);
    EXPECT_NEAR((ref.translation - s.pose.translation).norm(), 0.0, 1e-9);
    worst_deskewed = std::max(worst_deskewed, worst_ground_z(s.scan, ref));
  }
  // Between two scan poses the figure 8 bends by millimetres; the tilt changes by < 1 degree.
  EXPECT_LT(worst_deskewed, 0.03);
  EXPECT_GT(worst_raw, 0.2);  // the uncompensated scan is skewed far beyond that
}

TEST(Deskew, StaticSensorLeavesPointsUnchanged) {
  sim::Scenario s = flat_flight();
  s.sensor.motion = sim::SensorMotion::kStatic;
  sim::Simulator simulator(s, 3);
  sim::SimulatedScan scan = simulator.next();
  const core::OrganizedScan before = scan.scan;
  const core::Pose end = simulator.sensor_pose_at(simulator.scan_stamp_ns(1));
  pipeline::deskew_scan(scan.scan, scan.pose, end);
  for (std::size_t i = 0; i < before.size(); ++i) {
    if (!before.valid(i)) continue;
    ASSERT_LT((scan.scan.point(i) - before.point(i)).norm(), 1e-5f) << i;
    ASSERT_EQ(scan.scan.range_m(i), before.range_m(i));
  }
}

TEST(Deskew, InterpolatesPosesLinearlyAndRejectsReversedStamps) {
  core::Pose a, b;
  a.stamp_ns = 100;
  b.stamp_ns = 300;
  b.translation = {2.0, 0.0, 0.0};
  b.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()));
  const core::Pose mid = pipeline::interpolate_pose(a, b, 200);
  EXPECT_NEAR(mid.translation.x(), 1.0, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(mid.rotation).angle(), 0.1, 1e-9);
  core::OrganizedScan scan(1, 4);
  EXPECT_THROW(pipeline::deskew_scan(scan, b, a), core::InputError);
}

}  // namespace
}  // namespace ringtrack
