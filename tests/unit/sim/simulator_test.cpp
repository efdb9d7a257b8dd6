// Simulator behaviour: ring ranges on flat ground, labels, occlusion, determinism, scripted
// trajectories, moving-sensor distortion, and the angular bins against the naive caster.

#include "ringtrack/sim/simulator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "ringtrack/core/error.hpp"

namespace ringtrack::sim {
namespace {

Scenario quiet_scenario() {
  Scenario s;
  s.name = "test";
  s.duration_s = 2.0;
  s.area_m = {40, 40};
  s.sensor.range_noise_m = 0.0;
  s.sensor.dropout_probability = 0.0;
  s.sensor.far_dropout_probability = 0.0;
  return s;
}

// Stands at (x, y) for the whole run (an actor exists from its first to its last waypoint).
ScriptedActor standing(std::uint32_t id, double x, double y, ObjectClass c = ObjectClass::kPerson) {
  return {id, c, {{0.0, {x, y, std::nan("")}}, {1000.0, {x, y, std::nan("")}}}};
}

TEST(Simulator, FlatGroundGivesEachRingItsRange) {
  const Scenario s = quiet_scenario();
  Simulator sim(s, 1);
  const auto out = sim.next();
  const auto& m = sim.model();
  for (int r = 0; r < m.rings(); ++r) {
    const double el = m.elevation_rad[static_cast<std::size_t>(r)];
    for (int c = 0; c < m.columns(); c += 7) {
      const std::size_t i = out.scan.index(r, c);
      if (el >= 0) {
        EXPECT_EQ(out.scan.status(i), core::ReturnStatus::kNoReturn);
        continue;
      }
      // The beam starts at the sensor height plus the ring's vertical offset.
      const double expected =
          (2.5 + m.vertical_offset_m[static_cast<std::size_t>(r)]) / std::sin(-el);
      if (expected > m.max_range_m) {
        EXPECT_NE(out.scan.status(i), core::ReturnStatus::kValid) << "ring " << r;
        continue;
      }
      ASSERT_TRUE(out.scan.valid(i)) << "ring " << r << " column " << c;
      EXPECT_NEAR(out.scan.range_m(i), expected, 1e-4 * expected) << "ring " << r;
      EXPECT_NEAR(out.pose.to_world(out.scan.point(i)).z(), 0.0, 1e-3);
      EXPECT_EQ(out.labels[i], 0u);
    }
  }
}

TEST(Simulator, HitPointsCarryTheirObjectsLabel) {
  Scenario s = quiet_scenario();
  s.scripted = {standing(3, 6.0, 0.0),
                standing(7, -9.5, 0.0, ObjectClass::kRobot),
                {9, ObjectClass::kDrone, {{0.0, {0.0, -5.0, 4.0}}, {9.0, {0.0, -5.0, 4.0}}}}};
  Simulator sim(s, 1);
  const auto out = sim.next();
  std::map<std::uint32_t, int> counts;
  for (std::size_t i = 0; i < out.scan.size(); ++i) {
    if (!out.scan.valid(i)) continue;
    const Eigen::Vector3f w = out.pose.to_world(out.scan.point(i));
    ++counts[out.labels[i]];
    if (out.labels[i] == 3) {
      EXPECT_LT((w.head<2>() - Eigen::Vector2f(6, 0)).norm(), 0.6f);
      EXPECT_GT(w.z(), -0.01f);
      EXPECT_LT(w.z(), 1.76f);
    } else if (out.labels[i] == 7) {
      EXPECT_LT((w.head<2>() - Eigen::Vector2f(-9.5, 0)).norm(), 0.4f);
      EXPECT_LT(w.z(), 0.45f);
    } else if (out.labels[i] == 9) {
      EXPECT_LT((w - Eigen::Vector3f(0, -5, 4)).norm(), 0.45f);
    } else {
      // Background points here are ground points.
      EXPECT_NEAR(w.z(), 0.0f, 1e-3f);
    }
  }
  EXPECT_GT(counts[3], 20);
  EXPECT_GT(counts[7], 3);  // seen by the -13 deg ring only: 0.42 m high at 9.5 m
  ASSERT_EQ(out.objects.size(), 3u);
  for (const auto& o : out.objects) {
    EXPECT_EQ(o.hit_points, counts[o.id]) << o.id;
    if (o.hit_points > 0) {
      EXPECT_TRUE(o.box.contains(o.centroid_m));
    }
  }
  EXPECT_EQ(out.objects[0].object_class, ObjectClass::kPerson);
  EXPECT_NEAR(out.objects[0].body_center_m.x(), 6.0f, 1e-4f);
  EXPECT_NEAR(out.objects[0].body_center_m.z(), 0.875f, 1e-4f);
  EXPECT_FALSE(out.objects[0].moving);
}

int hits_of(const SimulatedScan& s, std::uint32_t id) {
  for (const auto& o : s.objects) {
    if (o.id == id) return o.hit_points;
  }
  return -1;
}

TEST(Simulator, OcclusionHidesObjectsBehindOthers) {
  Scenario s = quiet_scenario();
  s.scripted = {standing(1, 10.0, 0.0)};
  const int alone = hits_of(Simulator(s, 1).next(), 1);
  EXPECT_GT(alone, 10);
  // A person in front takes part of the far one's points...
  Scenario people = s;
  people.scripted.push_back(standing(2, 5.0, 0.0));
  const auto both = Simulator(people, 1).next();
  EXPECT_LT(hits_of(both, 1), alone);
  EXPECT_GT(hits_of(both, 2), alone);
  // ...and a wall in front takes all of them.
  Scenario walled = s;
  walled.walls.push_back({{5.0, -2.0}, {5.0, 2.0}, 3.0, 0.2, 0.0, 0.5});
  EXPECT_EQ(hits_of(Simulator(walled, 1).next(), 1), 0);
}

TEST(Simulator, SameSeedSameScansOtherSeedOtherScans) {
  const Scenario s = builtin_scenario("crowd");
  Simulator a(s, 42), b(s, 42), c(s, 43);
  for (int k = 0; k < 3; ++k) {
    const auto x = a.next(), y = b.next(), z = c.next();
    ASSERT_EQ(x.labels, y.labels);
    for (std::size_t i = 0; i < x.scan.size(); ++i) {
      ASSERT_EQ(std::isnan(x.scan.range_m(i)), std::isnan(y.scan.range_m(i)));
      if (!std::isnan(x.scan.range_m(i))) {
        ASSERT_EQ(x.scan.range_m(i), y.scan.range_m(i));
      }
      ASSERT_EQ(x.scan.intensity(i), y.scan.intensity(i));
    }
    ASSERT_EQ(x.objects.size(), y.objects.size());
    for (std::size_t i = 0; i < x.objects.size(); ++i) {
      EXPECT_EQ(x.objects[i].hit_points, y.objects[i].hit_points);
      EXPECT_EQ(x.objects[i].body_center_m, y.objects[i].body_center_m);
    }
    EXPECT_NE(x.labels, z.labels);
  }
}

TEST(Simulator, ScriptedTrajectoryIsFollowed) {
  Scenario s = quiet_scenario();
  s.duration_s = 10.0;
  // 1 m/s along +y at x = 8, then standing still.
  s.scripted = {{5,
                 ObjectClass::kPerson,
                 {{0.0, {8.0, -4.0, std::nan("")}},
                  {8.0, {8.0, 4.0, std::nan("")}},
                  {10.0, {8.0, 4.0, std::nan("")}}}}};
  Simulator sim(s, 3);
  for (int k = 0; k < 100; ++k) {
    const auto out = sim.next();
    if (k % 10 != 0) continue;
    const auto& o = out.objects.at(0);
    const double t_mid = static_cast<double>(out.scan.stamp_ns) * 1e-9 + 0.05;
    const double y_mid = std::min(-4.0 + t_mid, 4.0);
    // The body centre is reported at the mean time of the hits, within the scan.
    EXPECT_NEAR(o.body_center_m.x(), 8.0f, 1e-4f);
    EXPECT_NEAR(o.body_center_m.y(), y_mid, 0.06) << "scan " << k;
    ASSERT_GT(o.hit_points, 0);
    EXPECT_NEAR(o.centroid_m.x(), 8.0f, 0.35f);
    EXPECT_NEAR(o.centroid_m.y(), o.body_center_m.y(), 0.3f);
    EXPECT_EQ(o.moving, t_mid < 8.0);
  }
}

TEST(Simulator, ScriptedActorsEnterAndLeave) {
  Scenario s = quiet_scenario();
  s.duration_s = 3.0;
  // Walks 1 m/s along +y at x = 7 from t = 0.8 s to t = 2.0 s; absent before and after.
  s.scripted = {{6,
                 ObjectClass::kPerson,
                 {{0.8, {7.0, -0.6, std::nan("")}}, {2.0, {7.0, 0.6, std::nan("")}}}},
                standing(2, -6.0, 3.0)};
  Simulator sim(s, 4);
  int present_scans = 0;
  for (std::int64_t k = 0; k < sim.scan_count(); ++k) {
    const auto out = sim.next();
    const double t_mid = static_cast<double>(out.scan.stamp_ns) * 1e-9 + 0.05;
    const bool should_exist = t_mid >= 0.8 && t_mid <= 2.0;
    const auto row = std::find_if(out.objects.begin(), out.objects.end(),
                                  [](const ObjectTruth& o) { return o.id == 6; });
    const bool labelled = std::find(out.labels.begin(), out.labels.end(), 6u) != out.labels.end();
    EXPECT_EQ(row != out.objects.end(), should_exist) << "scan " << k;
    EXPECT_EQ(labelled, should_exist) << "scan " << k;
    if (should_exist) {
      ++present_scans;
      ASSERT_NE(row, out.objects.end());
      EXPECT_GT(row->hit_points, 10) << "scan " << k;
    }
    // The one standing all the time is always there.
    EXPECT_TRUE(std::any_of(out.objects.begin(), out.objects.end(),
                            [](const ObjectTruth& o) { return o.id == 2; }))
        << "scan " << k;
  }
  EXPECT_GE(present_scans, 11);
  EXPECT_LE(present_scans, 13);
}

TEST(Simulator, ScriptedBodiesTakeTheirHeightWidthAndReflectivity) {
  Scenario s = quiet_scenario();
  ScriptedActor small = standing(1, 4.0, 0.0);
  small.height_m = 1.5;
  small.width_m = 0.4;
  ScriptedActor tall = standing(2, -4.0, 0.0);
  tall.height_m = 1.95;
  tall.width_m = 0.9;
  tall.reflectivity = 0.9;
  ScriptedActor plain = standing(3, 0.0, 4.0);  // 1.75 m default
  s.scripted = {small, tall, plain};
  Simulator sim(s, 1);
  std::map<std::uint32_t, float> max_z, min_y, max_y, intensity;
  for (int k = 0; k < 3; ++k) {
    const auto out = sim.next();
    for (std::size_t i = 0; i < out.scan.size(); ++i) {
      const std::uint32_t id = out.labels[i];
      if (!out.scan.valid(i) || id == 0) continue;
      const Eigen::Vector3f w = out.pose.to_world(out.scan.point(i));
      max_z[id] = std::max(max_z.count(id) ? max_z[id] : -1e9f, w.z());
      min_y[id] = std::min(min_y.count(id) ? min_y[id] : 1e9f, w.y());
      max_y[id] = std::max(max_y.count(id) ? max_y[id] : -1e9f, w.y());
      intensity[id] = std::max(intensity[id], out.scan.intensity(i));
    }
  }
  ASSERT_EQ(max_z.size(), 3u);
  // At 4 m the rings are 0.14 m apart: the top hit is within that of the head.
  EXPECT_LE(max_z[1], 1.5f + 0.01f);  // the head tops h by 0.07 %
  EXPECT_GT(max_z[1], 1.5f - 0.2f);
  EXPECT_LE(max_z[2], 1.95f + 0.01f);
  EXPECT_GT(max_z[2], 1.95f - 0.2f);
  EXPECT_GT(max_z[2], max_z[1] + 0.25f);
  EXPECT_LE(max_z[3], 1.75f + 0.01f);
  EXPECT_GT(max_z[3], 1.75f - 0.2f);
  // Facing +x (no motion), their shoulders span y: 0.4 m and 0.9 m.
  EXPECT_LE(max_y[1] - min_y[1], 0.4f + 0.01f);
  EXPECT_GT(max_y[2] - min_y[2], 0.7f);
  EXPECT_GT(intensity[2], intensity[1] + 60.0f);
}

TEST(Scenario, PathSegmentsMustClearObstaclesAndTheSensor) {
  const auto error_of = [](const Scenario& s) {
    try {
      validate(s, "v.yaml");
    } catch (const core::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  Scenario s = quiet_scenario();
  s.boxes.push_back({{10.0, 0.0}, {4.5, 1.8, 1.5}, 0.0, 0.0, 0.6});  // a parked car
  // Both waypoints are well clear of the car; the straight segment between them crosses it.
  s.scripted = {{3,
                 ObjectClass::kPerson,
                 {{0.0, {8.0, 5.0, std::nan("")}},
                  {2.0, {8.0, 3.0, std::nan("")}},
                  {6.0, {12.0, -3.0, std::nan("")}}}}};
  const std::string crossing = error_of(s);
  EXPECT_NE(crossing.find("v.yaml: trajectory of id 3: segment t=2-6 s from (8, 3) to (12, -3) "
                          "crosses boxes[0]"),
            std::string::npos)
      << crossing;
  // Around the car instead: accepted.
  s.scripted[0].waypoints[2].xyz_m = {13.0, 3.0, std::nan("")};
  s.scripted[0].waypoints.push_back({8.0, {13.0, -3.0, std::nan("")}});
  EXPECT_EQ(error_of(s), "(no error)");
  // Walking through the sensor's mast.
  s.scripted[0].waypoints.push_back({14.0, {-3.0, 0.3, std::nan("")}});
  const std::string mast = error_of(s);
  EXPECT_NE(mast.find("segment t=8-14 s"), std::string::npos) << mast;
  EXPECT_NE(mast.find("the sensor's keep-out zone"), std::string::npos) << mast;
  // Past a post (cylinder).
  s.scripted[0].waypoints.pop_back();
  s.cylinders.push_back({{15.0, 0.0}, 0.15, 4.0, 0.0, 0.6});
  s.scripted[0].waypoints.push_back({14.0, {17.0, 2.0, std::nan("")}});
  const std::string post = error_of(s);
  EXPECT_NE(post.find("segment t=8-14 s"), std::string::npos) << post;
  EXPECT_NE(post.find("crosses cylinders[0]"), std::string::npos) << post;
  // A single waypoint no longer means "stands all the time".
  s.scripted[0].waypoints.resize(1);
  EXPECT_NE(error_of(s).find("a single waypoint"), std::string::npos) << error_of(s);
  // Body values out of range, or on a class without a body.
  s.scripted = {standing(5, 20.0, 20.0)};
  s.scripted[0].height_m = 2.7;
  EXPECT_NE(error_of(s).find("id 5: height_m must be in [0.5, 2.5]"), std::string::npos)
      << error_of(s);
  s.scripted = {standing(5, 20.0, 20.0, ObjectClass::kRobot)};
  s.scripted[0].width_m = 0.5;
  EXPECT_NE(error_of(s).find("not to a robot"), std::string::npos) << error_of(s);
}

TEST(Scenario, MovingSensorPathMustClearSolids) {
  Scenario s = quiet_scenario();
  s.duration_s = 10.0;
  s.sensor.motion = SensorMotion::kScripted;
  s.sensor.keyframes = {{0.0, {0, 0, 2.5}, {0, 0, 0}}, {10.0, {20, 0, 2.5}, {0, 0, 0}}};
  s.boxes.push_back({{12.0, 0.0}, {2.0, 2.0, 2.3}, 0.0, 0.0, 0.5});  // just below the flight
  EXPECT_NO_THROW(validate(s, "f.yaml"));
  s.boxes[0].size_m.z() = 3.0;  // now in the way
  try {
    validate(s, "f.yaml");
    FAIL() << "no error";
  } catch (const core::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("f.yaml: sensor: scripted path at t="), std::string::npos) << what;
    EXPECT_NE(what.find("passes through boxes[0]"), std::string::npos) << what;
  }
  // A lamp post at the tip of the figure 8 (x = R = 4 m, y = 0).
  Scenario f = quiet_scenario();
  f.sensor.motion = SensorMotion::kFigure8;
  f.duration_s = 20.0;
  f.cylinders.push_back({{3.95, 0.0}, 0.12, 6.0, 0.0, 0.6});
  try {
    validate(f, "f.yaml");
    FAIL() << "no error";
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("figure8 path"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cylinders[0]"), std::string::npos) << e.what();
  }
  // Every built-in flies clear.
  for (const auto& info : builtin_scenarios()) {
    EXPECT_NO_THROW(validate(with_moving_sensor(builtin_scenario(info.name)), info.name));
  }
}

TEST(Simulator, MovingSensorDistortionFollowsFiringTimes) {
  Scenario s = quiet_scenario();
  s.ground.enabled = false;
  // Sensor flying along +x at 5 m/s, level; a large wall facing it at x = 30.
  s.sensor.motion = SensorMotion::kScripted;
  s.sensor.keyframes = {{0.0, {0, 0, 2.5}, {0, 0, 0}}, {10.0, {50, 0, 2.5}, {0, 0, 0}}};
  s.boxes.push_back({{30.5, 0.0}, {1.0, 80.0, 20.0}, -5.0, 0.0, 0.5});
  Simulator sim(s, 1);
  (void)sim.next();
  const auto out = sim.next();
  double worst_column_pose = 0.0, worst_scan_pose = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < out.scan.size(); ++i) {
    if (!out.scan.valid(i)) continue;
    const int c = out.scan.column_of(i);
    const auto pose = sim.sensor_pose_at(out.scan.column_stamp_ns[static_cast<std::size_t>(c)]);
    worst_column_pose =
        std::max(worst_column_pose, std::abs(pose.to_world(out.scan.point(i)).x() - 30.0));
    worst_scan_pose =
        std::max(worst_scan_pose, std::abs(out.pose.to_world(out.scan.point(i)).x() - 30.0));
    ++n;
  }
  ASSERT_GT(n, 1000);
  EXPECT_LT(worst_column_pose, 2e-3);                // each point is where its own firing saw it
  EXPECT_GT(worst_scan_pose, 0.2);                   // one pose for the whole scan leaves the skew
  EXPECT_NEAR(out.pose.translation.x(), 0.5, 1e-9);  // pose at the scan's first column
}

TEST(Simulator, BinsMatchNaiveCaster) {
  for (const char* name : {"crowd-moving", "park", "hall-moving", "town"}) {
    const Scenario s = builtin_scenario(name);
    Simulator fast(s, 9), naive(s, 9);
    naive.set_use_bins(false);
    for (int k = 0; k < 2; ++k) {
      const auto a = fast.next(), b = naive.next();
      ASSERT_EQ(a.labels, b.labels) << name;
      for (std::size_t i = 0; i < a.scan.size(); ++i) {
        ASSERT_EQ(a.scan.status(i), b.scan.status(i)) << name << " cell " << i;
        if (a.scan.valid(i)) {
          ASSERT_EQ(a.scan.range_m(i), b.scan.range_m(i)) << name << " cell " << i;
        }
      }
    }
  }
}

TEST(Simulator, EveryBuiltinRunsAndSeesPeople) {
  for (const auto& info : builtin_scenarios()) {
    for (const bool moving : {false, true}) {
      Scenario s = builtin_scenario(std::to_string(info.number));
      if (moving) s = with_moving_sensor(s);
      Simulator sim(s, 5);
      EXPECT_NEAR(static_cast<double>(sim.scan_count()), s.duration_s * 10, 1.0);
      int seen = 0;
      const auto out = sim.next();
      for (const auto& o : out.objects) seen += o.hit_points > 0 ? 1 : 0;
      EXPECT_GT(seen, 0) << info.name;
      EXPECT_GT(out.scan.valid_count(), 5000u) << info.name;
    }
  }
}

TEST(Simulator, PeopleWalkAtTheirSpeedsAndAvoidObstacles) {
  const Scenario s = builtin_scenario("industrial");
  Simulator sim(s, 2);
  const auto footprints = ground_footprints(s);
  double max_speed = 0.0;
  for (int k = 0; k < 300; ++k) {
    const auto out = sim.next();
    for (const auto& o : out.objects) {
      if (o.object_class != ObjectClass::kPerson) continue;
      max_speed = std::max(max_speed, static_cast<double>(o.velocity_mps.norm()));
      for (const auto& f : footprints) {
        ASSERT_FALSE(f.contains(o.body_center_m.head<2>().cast<double>(), 0.1))
            << "person " << o.id << " inside " << f.entry << " in scan " << k;
      }
    }
  }
  EXPECT_LE(max_speed, 12.5 / 3.6 + 1e-6);
  EXPECT_GT(max_speed, 1.0);
}

TEST(Scenario, BadEntriesAreNamed) {
  Scenario s = quiet_scenario();
  s.cylinders.push_back({{3, 3}, -0.2, 2.0, 0.0, 0.4});
  try {
    validate(s, "bad.yaml");
    FAIL();
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cylinders[0]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("radius_m"), std::string::npos) << e.what();
  }
  Scenario w = quiet_scenario();
  w.walls.push_back({{5.0, -2.0}, {5.0, 2.0}, 3.0, 0.4, 0.0, 0.5});
  w.scripted = {standing(4, 5.05, 0.5)};
  try {
    validate(w, "bad.yaml");
    FAIL();
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("id 4"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("walls[0]"), std::string::npos) << e.what();
  }
  EXPECT_THROW(builtin_scenario("nope"), core::ConfigError);
  EXPECT_EQ(builtin_scenario("6").name, "park");
  EXPECT_EQ(builtin_scenario("park-moving").sensor.motion, SensorMotion::kFigure8);
}

}  // namespace
}  // namespace ringtrack::sim
