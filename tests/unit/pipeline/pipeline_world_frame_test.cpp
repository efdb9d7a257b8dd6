// Issue 16, world frames: poses from GNSS or a georeferenced map put the sensor at UTM-scale
// coordinates and hundreds of metres up. The pipeline works in a local frame about its first
// pose, so the same scene gives the same tracks and the same map wherever its world frame lies
// (oracle: the same run near the origin).

#include <gtest/gtest.h>

#include <map>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/pipeline/deskew.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace ringtrack::pipeline {
namespace {

// Easting, northing and height of a georeferenced world (UTM zone scale, 100 m above the datum).
const Eigen::Vector3d kUtmShift{500'000.0, 5'000'000.0, 100.0};

struct TrackAt {
  std::uint64_t id{0};
  Eigen::Vector3d position;  // world frame of the poses
  Eigen::Vector3d box_min, box_max;
  bool dynamic{false};
};

struct RunOutput {
  std::vector<std::vector<TrackAt>> tracks;  // per scan, reported tracks
  std::vector<Eigen::Vector3d> map;          // voxel means, world frame of the poses
  Eigen::Vector3d origin{Eigen::Vector3d::Zero()};
};

// The scenario's scans with every pose moved by shift (deskewed like `ringtrack run` does).
RunOutput run(const sim::Scenario& scenario, const Eigen::Vector3d& shift) {
  sim::Simulator simulator(scenario, 7);
  Pipeline pipeline(core::Config{}, simulator.model());
  RunOutput out;
  const bool moving = scenario.sensor.motion != sim::SensorMotion::kStatic;
  for (std::int64_t k = 0; k < simulator.scan_count(); ++k) {
    sim::SimulatedScan scan = simulator.next();
    core::Pose pose = scan.pose;
    if (moving) {
      core::Pose next = simulator.sensor_pose_at(simulator.scan_stamp_ns(k + 1));
      core::Pose first = scan.pose;
      first.translation += shift;
      next.translation += shift;
      pose = deskew_scan(scan.scan, first, next);
    } else {
      pose.translation += shift;
    }
    const FrameResult& result = pipeline.process(scan.scan, pose);
    std::vector<TrackAt> reported;
    for (const tracking::Hypothesis& h : result.hypotheses) {
      if (!h.reported) continue;
      reported.push_back({h.id, h.reported_position + result.origin,
                          h.box.min.cast<double>() + result.origin,
                          h.box.max.cast<double>() + result.origin, h.dynamic});
    }
    out.tracks.push_back(std::move(reported));
  }
  pipeline.finish();
  out.origin = pipeline.origin();
  for (const mapping::MapPoint& p : pipeline.static_map().points()) {
    out.map.push_back(p.position.cast<double>() + out.origin);
  }
  return out;
}

sim::Scenario short_park(bool moving) {
  sim::Scenario s = sim::builtin_scenario("park");
  if (moving) s = sim::with_moving_sensor(s);
  s.duration_s = 8.0;
  return s;
}

// Tracks and map of the shifted run equal the near-origin run's once the shift is taken off.
void expect_same_outputs(const RunOutput& near, const RunOutput& far,
                         const Eigen::Vector3d& shift) {
  ASSERT_EQ(near.tracks.size(), far.tracks.size());
  std::size_t compared = 0;
  for (std::size_t k = 0; k < near.tracks.size(); ++k) {
    ASSERT_EQ(near.tracks[k].size(), far.tracks[k].size()) << "scan " << k;
    for (std::size_t i = 0; i < near.tracks[k].size(); ++i) {
      const TrackAt& a = near.tracks[k][i];
      const TrackAt& b = far.tracks[k][i];
      EXPECT_EQ(a.id, b.id);
      EXPECT_EQ(a.dynamic, b.dynamic);
      EXPECT_LT((b.position - shift - a.position).norm(), 1e-3) << "scan " << k << " id " << a.id;
      EXPECT_LT((b.box_min - shift - a.box_min).norm(), 1e-3);
      EXPECT_LT((b.box_max - shift - a.box_max).norm(), 1e-3);
      ++compared;
    }
  }
  EXPECT_GT(compared, 100u) << "the scene should give tracks to compare";
  ASSERT_EQ(near.map.size(), far.map.size());
  EXPECT_GT(near.map.size(), 1000u);
  for (std::size_t i = 0; i < near.map.size(); ++i) {
    ASSERT_LT((far.map[i] - shift - near.map[i]).norm(), 1e-3) << "map point " << i;
  }
}

TEST(PipelineWorldFrame, UtmScaleAndHighPosesGiveTheSameTracksAndMapAsNearTheOrigin) {
  const sim::Scenario scenario = short_park(false);
  const RunOutput near = run(scenario, Eigen::Vector3d::Zero());
  const RunOutput far = run(scenario, kUtmShift);
  EXPECT_EQ(near.origin, Eigen::Vector3d::Zero());
  EXPECT_EQ(far.origin, kUtmShift);  // the first pose (z 102.5 m) rounded to 100 m
  expect_same_outputs(near, far, kUtmShift);
}

// A moving sensor (figure 8, deskewed): its positions are not whole numbers, so the shifted run
// sees them rounded to 1e-10 m by the double subtraction; still the same outputs.
TEST(PipelineWorldFrame, MovingSensorInAUtmWorldGivesTheSameTracksAndMap) {
  const sim::Scenario scenario = short_park(true);
  expect_same_outputs(run(scenario, Eigen::Vector3d::Zero()), run(scenario, kUtmShift), kUtmShift);
}

// detection.max_altitude_m counts from the ground, sensor_height_m below the first sensor pose:
// a world 100 m up (or 1 km below the datum) keeps its people, and a wrong sensor height is what
// turns them away.
TEST(PipelineWorldFrame, AltitudeCountsFromTheGroundBelowTheFirstPose) {
  const auto people = [](double sensor_height_m, const Eigen::Vector3d& shift) {
    sim::Scenario s = short_park(false);
    s.duration_s = 1.0;
    sim::Simulator simulator(s, 3);
    core::Config config;
    config.detection.sensor_height_m = sensor_height_m;
    Pipeline pipeline(config, simulator.model());
    std::size_t detections = 0;
    for (std::int64_t k = 0; k < simulator.scan_count(); ++k) {
      sim::SimulatedScan scan = simulator.next();
      scan.pose.translation += shift;
      detections += pipeline.process(scan.scan, scan.pose).detections.size();
    }
    EXPECT_NEAR(pipeline.ground_z(), 2.5 - sensor_height_m, 1e-9);
    return detections;
  };
  const std::size_t near = people(2.5, Eigen::Vector3d::Zero());
  EXPECT_GT(near, 10u);
  EXPECT_EQ(people(2.5, kUtmShift), near);
  EXPECT_EQ(people(2.5, Eigen::Vector3d(0, 0, -1000.0)), near);
  // A sensor said to stand 7.5 m lower than it does puts the ground 7.5 m up: everything low
  // still passes (and tree crowns with it).
  EXPECT_GE(people(-5.0, kUtmShift), near);
  // One said to stand 20 m up puts the ground 17.5 m down: nobody's lowest point is within 3 m.
  EXPECT_EQ(people(20.0, kUtmShift), 0u);
}

// Float positions hold millimetres up to kMaxLocalDistanceM from the origin: a pose beyond is a
// clear error naming the distance, never a silently coarse or empty result. So is a NaN pose.
TEST(PipelineWorldFrame, PoseTooFarFromTheLocalOriginIsAClearError) {
  sim::Scenario s = short_park(false);
  s.duration_s = 0.3;
  sim::Simulator simulator(s, 3);
  Pipeline pipeline(core::Config{}, simulator.model());
  sim::SimulatedScan scan = simulator.next();
  scan.pose.translation += kUtmShift;
  pipeline.process(scan.scan, scan.pose);
  scan = simulator.next();
  scan.pose.translation += kUtmShift + Eigen::Vector3d(60'000.0, 0.0, 0.0);
  try {
    pipeline.process(scan.scan, scan.pose);
    FAIL() << "no error for a pose 60 km from the local origin";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("local origin (500000.000, 5000000.000, 100.000) m"), std::string::npos)
        << what;
    EXPECT_NE(what.find("at most 50000.000 m"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace ringtrack::pipeline
