#include "ringtrack/sim/actors.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>

#include "ringtrack/core/error.hpp"

namespace ringtrack::sim {
namespace {

constexpr std::int64_t kStepNs = 10'000'000;  // 10 ms
constexpr double kPi = std::numbers::pi;

double wrap(double a) {
  while (a > kPi) a -= 2 * kPi;
  while (a < -kPi) a += 2 * kPi;
  return a;
}

double stride_of(double height_m, double speed_mps) {
  return 0.85 * height_m * std::clamp(1.0 + 0.25 * (speed_mps - 1.4), 0.8, 1.6);
}

double random_speed(ObjectClass c, Rng& rng) {
  switch (c) {
    case ObjectClass::kPerson:
      return rng.uniform(3.5, 12.5) / 3.6;  // the paper's 3.5-12.5 km/h
    case ObjectClass::kRobot:
      return rng.uniform(0.3, 1.5);
    case ObjectClass::kDrone:
      return rng.uniform(1.0, 5.0);
    case ObjectClass::kDistractor:
      return 0.0;
  }
  return 0.0;
}

Eigen::Matrix3d yaw_matrix(double yaw) {
  return Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

}  // namespace

namespace {

// Ids 1, 2, ... for the random actors and distractors, skipping the scripted actors' ids.
class IdSource {
 public:
  explicit IdSource(const Scenario& scenario) {
    for (const auto& s : scenario.scripted) taken_.push_back(s.id);
  }
  std::uint32_t next() {
    while (std::find(taken_.begin(), taken_.end(), next_) != taken_.end()) ++next_;
    return next_++;
  }

 private:
  std::vector<std::uint32_t> taken_;
  std::uint32_t next_ = 1;
};

Actor distractor_actor(const Eigen::Vector2d& position, bool cylinder_body, std::uint32_t id,
                       std::uint64_t seed) {
  Actor a;
  a.id = id;
  a.object_class = ObjectClass::kDistractor;
  a.rng = Rng(seed);
  a.height_m = a.rng.uniform(1.6, 1.85);
  a.reflectivity = static_cast<float>(a.rng.uniform(0.3, 0.8));
  a.cylinder_body = cylinder_body;
  a.position = {position.x(), position.y(), 0.0};
  a.yaw_rad = a.rng.uniform(-kPi, kPi);
  a.target_speed_mps = 0.0;
  return a;
}

Actor scripted_actor(const ScriptedActor& s, int script, std::uint64_t seed) {
  Actor a;
  a.id = s.id;
  a.object_class = s.object_class;
  a.script = script;
  a.rng = Rng(seed);
  const bool has_body =
      s.object_class == ObjectClass::kPerson || s.object_class == ObjectClass::kDistractor;
  a.height_m =
      has_body ? s.height_m.value_or(1.75) : (s.object_class == ObjectClass::kRobot ? 0.42 : 0.2);
  a.width_scale = has_body && s.width_m ? *s.width_m / kPersonWidthM : 1.0;
  a.reflectivity = static_cast<float>(s.reflectivity.value_or(0.4));
  return a;
}

}  // namespace

ActorWorld::ActorWorld(const Scenario& scenario, std::uint64_t seed)
    : scenario_(&scenario), footprints_(ground_footprints(scenario)) {
  // Distractors are obstacles for walkers; their footprints came with ground_footprints().
  // One generator hands each actor the seed of its own, in this order.
  Rng rng(Rng::derive(seed, 11));
  IdSource ids(scenario);
  for (const auto& [kind, count] : {std::pair{ObjectClass::kPerson, scenario.people},
                                    std::pair{ObjectClass::kRobot, scenario.robots},
                                    std::pair{ObjectClass::kDrone, scenario.drones}}) {
    for (int i = 0; i < count; ++i) {
      const std::uint32_t id = ids.next();
      actors_.push_back(random_actor(kind, id, rng.next()));
    }
  }
  for (std::size_t i = 0; i < scenario.distractors.size(); ++i) {
    const std::uint32_t id = ids.next();
    actors_.push_back(distractor_actor(scenario.distractors[i], i % 2 == 1, id, rng.next()));
  }
  for (std::size_t i = 0; i < scenario.scripted.size(); ++i) {
    actors_.push_back(scripted_actor(scenario.scripted[i], static_cast<int>(i), rng.next()));
  }
}

Actor ActorWorld::random_actor(ObjectClass c, std::uint32_t id, std::uint64_t seed) {
  Actor a;
  a.id = id;
  a.object_class = c;
  a.rng = Rng(seed);
  a.height_m = c == ObjectClass::kPerson ? a.rng.uniform(1.5, 1.95)
                                         : (c == ObjectClass::kRobot ? 0.42 : 0.2);
  a.width_scale = a.rng.uniform(0.85, 1.15) * (a.height_m / 1.75 * 0.5 + 0.5);
  a.reflectivity = static_cast<float>(a.rng.uniform(0.15, 0.6));
  const std::optional<Eigen::Vector3d> start = random_start(c, a.rng);
  if (!start) {
    throw core::ConfigError("scenario " + scenario_->name + ": actors: no free space for " +
                            std::string(class_name(c)) + " " + std::to_string(a.id) +
                            " in the walking area");
  }
  a.position = *start;
  a.yaw_rad = a.rng.uniform(-kPi, kPi);
  a.gait_phase_rad = a.rng.uniform(0, 2 * kPi);
  a.target_speed_mps = random_speed(c, a.rng);
  choose_goal(a);
  return a;
}

std::optional<Eigen::Vector3d> ActorWorld::random_start(ObjectClass c, Rng& rng) const {
  for (int attempt = 0; attempt < 500; ++attempt) {
    const Eigen::Vector2d p = random_point(rng);
    if (c != ObjectClass::kDrone && !free_at(p, 0.6)) continue;
    // At least 1 m from every actor on the ground placed so far (drones fly above them).
    const bool clear = std::none_of(actors_.begin(), actors_.end(), [&](const Actor& o) {
      return o.object_class != ObjectClass::kDrone && (o.position.head<2>() - p).norm() < 1.0;
    });
    if (!clear) continue;
    return Eigen::Vector3d{p.x(), p.y(), c == ObjectClass::kDrone ? rng.uniform(3.0, 10.0) : 0.0};
  }
  return std::nullopt;
}

Eigen::Vector2d ActorWorld::random_point(Rng& rng) const {
  const Eigen::Vector2d h = 0.5 * scenario_->area_m - Eigen::Vector2d::Constant(0.5);
  return scenario_->area_center_m +
         Eigen::Vector2d{rng.uniform(-h.x(), h.x()), rng.uniform(-h.y(), h.y())};
}

bool ActorWorld::free_at(const Eigen::Vector2d& p, double margin) const {
  if ((p - scenario_->sensor.position_m.head<2>()).norm() < kSensorKeepOutM + margin) return false;
  return std::none_of(footprints_.begin(), footprints_.end(),
                      [&](const Footprint& f) { return f.contains(p, margin); });
}

bool ActorWorld::free_path(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                           double margin) const {
  const Footprint mast{
      scenario_->sensor.position_m.head<2>(), {kSensorKeepOutM, 0.0}, 0.0, true, "sensor"};
  if (mast.crosses(a, b, margin)) return false;
  return std::none_of(footprints_.begin(), footprints_.end(),
                      [&](const Footprint& f) { return f.crosses(a, b, margin); });
}

void ActorWorld::choose_goal(Actor& a) {
  if (a.object_class == ObjectClass::kDrone) {
    const Eigen::Vector2d p = random_point(a.rng);
    a.goal = {p.x(), p.y(), a.rng.uniform(3.0, 10.0)};
    return;
  }
  // A goal in free space that can be reached on a straight line: walkers go around obstacles by
  // chaining such legs.
  for (int attempt = 0; attempt < 100; ++attempt) {
    const Eigen::Vector2d p = random_point(a.rng);
    if (free_at(p, 0.6) && free_path(a.position.head<2>(), p, 0.45)) {
      a.goal = {p.x(), p.y(), 0.0};
      return;
    }
  }
  a.goal = a.position;  // boxed in for now: stand and try again after a pause
  a.pause_s = 1.0;
}

void ActorWorld::advance_to(std::int64_t t_ns) {
  while (time_ns_ + kStepNs <= t_ns) {
    for (auto& a : actors_) {
      if (a.script < 0 && a.object_class != ObjectClass::kDistractor) step(a, kStepNs * 1e-9);
    }
    // Walkers keep a personal distance: push overlapping pairs apart (never into obstacles).
    for (std::size_t i = 0; i < actors_.size(); ++i) {
      Actor& a = actors_[i];
      if (a.script >= 0 || a.object_class == ObjectClass::kDrone ||
          a.object_class == ObjectClass::kDistractor) {
        continue;
      }
      for (std::size_t j = i + 1; j < actors_.size(); ++j) {
        Actor& b = actors_[j];
        if (b.script >= 0 || b.object_class == ObjectClass::kDrone ||
            b.object_class == ObjectClass::kDistractor) {
          continue;
        }
        const Eigen::Vector2d d = b.position.head<2>() - a.position.head<2>();
        const double dist = d.norm();
        if (dist >= 0.55 || dist < 1e-9) continue;
        const Eigen::Vector2d push = 0.5 * (0.55 - dist) * d / dist;
        if (free_at(b.position.head<2>() + push, 0.25)) b.position.head<2>() += push;
        if (free_at(a.position.head<2>() - push, 0.25)) a.position.head<2>() -= push;
      }
    }
    time_ns_ += kStepNs;
  }
}

void ActorWorld::step(Actor& a, double dt) {
  const bool flying = a.object_class == ObjectClass::kDrone;
  const double accel = flying ? 2.0 : 1.5;
  if (a.pause_s > 0.0) {
    a.pause_s -= dt;
    a.speed_mps = std::max(0.0, a.speed_mps - 3.0 * dt);
    if (a.pause_s <= 0.0) {
      a.target_speed_mps = random_speed(a.object_class, a.rng);
      choose_goal(a);
    }
  } else {
    const Eigen::Vector3d to = a.goal - a.position;
    const double dist = flying ? to.norm() : to.head<2>().norm();
    if (dist < 0.3) {
      if (a.rng.chance(0.4))
        a.pause_s = a.rng.uniform(1.0, 6.0);  // pause now and then
      else
        choose_goal(a);
    } else {
      if (a.rng.chance(0.08 * dt)) a.target_speed_mps = random_speed(a.object_class, a.rng);
      const double want_yaw = std::atan2(to.y(), to.x());
      const double err = wrap(want_yaw - a.yaw_rad);
      const double max_turn = (flying ? 2.0 : 4.0) * dt;
      a.yaw_rad = wrap(a.yaw_rad + std::clamp(err, -max_turn, max_turn));
      // Slow down for sharp turns and when arriving.
      const double want = std::min(a.target_speed_mps * std::max(0.0, std::cos(err)), 1.5 * dist);
      a.speed_mps += std::clamp(want - a.speed_mps, -accel * dt, accel * dt);
    }
  }
  const Eigen::Vector2d heading{std::cos(a.yaw_rad), std::sin(a.yaw_rad)};
  Eigen::Vector3d next = a.position;
  next.head<2>() += a.speed_mps * dt * heading;
  if (flying) {
    const double dz = a.goal.z() - a.position.z();
    next.z() += std::clamp(dz, -1.0 * dt, 1.0 * dt);
  } else if (!free_at(next.head<2>(), 0.25)) {
    // Never walk into an obstacle: stop and pick another goal.
    a.speed_mps = 0.0;
    choose_goal(a);
    return;
  }
  a.position = next;
  if (a.object_class == ObjectClass::kPerson) {
    a.gait_phase_rad = std::fmod(
        a.gait_phase_rad + 2 * kPi * a.speed_mps * dt / stride_of(a.height_m, a.speed_mps),
        2 * kPi);
  }
}

bool ActorWorld::present(std::size_t i, std::int64_t t_ns) const {
  const Actor& a = actors_[i];
  if (a.script < 0) return true;
  return scenario_->scripted[static_cast<std::size_t>(a.script)].present_at(
      static_cast<double>(t_ns) * 1e-9);
}

ActorState ActorWorld::state_at(std::size_t i, std::int64_t t_ns) const {
  const Actor& a = actors_[i];
  const Ground& g = scenario_->ground;
  const auto ground_at = [&](double x, double y) { return g.enabled ? g.height_at(x, y) : 0.0; };
  if (a.script >= 0) {
    return scripted_state(scenario_->scripted[static_cast<std::size_t>(a.script)],
                          static_cast<double>(t_ns) * 1e-9, g, stride_of(a.height_m, 1.4));
  }
  ActorState st;
  const double dt = static_cast<double>(t_ns - time_ns_) * 1e-9;
  const Eigen::Vector2d heading{std::cos(a.yaw_rad), std::sin(a.yaw_rad)};
  st.yaw_rad = a.yaw_rad;
  st.velocity_mps = {a.speed_mps * heading.x(), a.speed_mps * heading.y(), 0.0};
  const Eigen::Vector2d p = a.position.head<2>() + dt * st.velocity_mps.head<2>();
  st.base_m = {
      p.x(), p.y(),
      ground_at(p.x(), p.y()) + (a.object_class == ObjectClass::kDrone ? a.position.z() : 0.0)};
  st.gait_phase_rad = a.gait_phase_rad;
  if (a.object_class == ObjectClass::kPerson && a.speed_mps > 0) {
    st.gait_phase_rad += 2 * kPi * a.speed_mps * dt / stride_of(a.height_m, a.speed_mps);
  }
  return st;
}

ActorState scripted_state(const ScriptedActor& s, double t_s, const Ground& g, double stride_m) {
  ActorState st;
  const auto& w = s.waypoints;
  const auto ground_at = [&](double x, double y) { return g.enabled ? g.height_at(x, y) : 0.0; };
  const double default_z = s.object_class == ObjectClass::kDrone ? 5.0 : 0.0;
  const auto z_of = [&](const Waypoint& p) {
    return std::isfinite(p.xyz_m.z()) ? p.xyz_m.z() : default_z;
  };
  Eigen::Vector3d pos;
  double travelled = 0.0;
  std::size_t seg = 0;  // segment whose heading applies
  if (t_s <= w.front().t_s || w.size() == 1) {
    pos = {w.front().xyz_m.x(), w.front().xyz_m.y(), z_of(w.front())};
  } else if (t_s >= w.back().t_s) {
    pos = {w.back().xyz_m.x(), w.back().xyz_m.y(), z_of(w.back())};
    for (std::size_t i = 1; i < w.size(); ++i)
      travelled += (w[i].xyz_m.head<2>() - w[i - 1].xyz_m.head<2>()).norm();
    seg = w.size() - 2;
  } else {
    while (w[seg + 1].t_s < t_s) {
      travelled += (w[seg + 1].xyz_m.head<2>() - w[seg].xyz_m.head<2>()).norm();
      ++seg;
    }
    const double u = (t_s - w[seg].t_s) / (w[seg + 1].t_s - w[seg].t_s);
    const Eigen::Vector3d a{w[seg].xyz_m.x(), w[seg].xyz_m.y(), z_of(w[seg])};
    const Eigen::Vector3d b{w[seg + 1].xyz_m.x(), w[seg + 1].xyz_m.y(), z_of(w[seg + 1])};
    pos = a + u * (b - a);
    st.velocity_mps = (b - a) / (w[seg + 1].t_s - w[seg].t_s);
    travelled += (pos - a).head<2>().norm();
  }
  // Heading: of the current segment, or of the nearest segment that moves.
  for (std::size_t k = 0; k + 1 < w.size(); ++k) {
    const std::size_t i = std::min(seg + k, w.size() - 2);
    const Eigen::Vector2d d = w[i + 1].xyz_m.head<2>() - w[i].xyz_m.head<2>();
    if (d.norm() > 1e-6) {
      st.yaw_rad = std::atan2(d.y(), d.x());
      break;
    }
  }
  st.base_m = {pos.x(), pos.y(), ground_at(pos.x(), pos.y()) + pos.z()};
  st.gait_phase_rad = 2 * kPi * travelled / stride_m;
  return st;
}

Eigen::Vector3d body_center(const Actor& a, const ActorState& st) {
  if (a.object_class == ObjectClass::kDrone) return st.base_m;
  return st.base_m + Eigen::Vector3d(0, 0, 0.5 * a.height_m);
}

void append_body(const Actor& a, const ActorState& st, std::int32_t slot,
                 std::vector<Primitive>& out) {
  const std::size_t first = out.size();
  const Eigen::Matrix3d ry = yaw_matrix(st.yaw_rad);
  const Eigen::Vector3d lateral = ry.col(1);
  const Eigen::Vector3d& b = st.base_m;
  const double h = a.height_m, w = a.width_scale;
  switch (a.object_class) {
    case ObjectClass::kPerson:
    case ObjectClass::kDistractor: {
      if (a.cylinder_body) {
        out.push_back(Primitive::cylinder(b.head<2>(), b.z(), 0.25, h));
        break;
      }
      // Six parts: legs and arms swing about hip and shoulder with the gait; the swing grows
      // with speed and vanishes when standing.
      const double speed = st.velocity_mps.head<2>().norm();
      const double amp = std::min(0.2 + 0.12 * speed, 0.6) * std::min(1.0, speed / 0.3);
      const double swing = amp * std::sin(st.gait_phase_rad);
      const double s = h / 1.75;
      const auto limb = [&](const Eigen::Vector3d& pivot, double angle, double half_len, double r) {
        const Eigen::Matrix3d rot =
            ry * Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
        out.push_back(Primitive::ellipsoid(pivot + rot * Eigen::Vector3d(0, 0, -half_len),
                                           {r, r, half_len}, rot));
      };
      const Eigen::Vector3d hip = b + Eigen::Vector3d(0, 0, 0.5 * h);
      limb(hip + 0.09 * w * lateral, swing, 0.25 * h, 0.08 * w);
      limb(hip - 0.09 * w * lateral, -swing, 0.25 * h, 0.08 * w);
      out.push_back(Primitive::ellipsoid(b + Eigen::Vector3d(0, 0, 0.67 * h),
                                         {0.12 * w, 0.2 * w, 0.18 * h}, ry));
      out.push_back(Primitive::ellipsoid(b + Eigen::Vector3d(0, 0, 0.935 * h),
                                         {0.1 * s, 0.08 * s, 0.115 * s}, ry));
      const Eigen::Vector3d shoulder = b + Eigen::Vector3d(0, 0, 0.82 * h);
      limb(shoulder + 0.25 * w * lateral, -0.7 * swing, 0.19 * h, 0.05 * w);
      limb(shoulder - 0.25 * w * lateral, 0.7 * swing, 0.19 * h, 0.05 * w);
      break;
    }
    case ObjectClass::kRobot: {
      out.push_back(Primitive::box(b.head<2>(), b.z() + 0.06, {0.55, 0.45, 0.24}, st.yaw_rad));
      out.push_back(Primitive::box(b.head<2>(), b.z() + 0.3, {0.25, 0.25, 0.12}, st.yaw_rad));
      break;
    }
    case ObjectClass::kDrone: {
      out.push_back(Primitive::ellipsoid(b, {0.18, 0.18, 0.07}, ry));
      for (const double dx : {-0.22, 0.22}) {
        for (const double dy : {-0.22, 0.22}) {
          out.push_back(Primitive::ellipsoid(b + ry * Eigen::Vector3d(dx, dy, 0.05),
                                             {0.12, 0.12, 0.015}, ry));
        }
      }
      break;
    }
  }
  for (std::size_t i = first; i < out.size(); ++i) {
    out[i].label = a.id;
    out[i].mover = slot;
    out[i].reflectivity = a.reflectivity;
  }
}

}  // namespace ringtrack::sim
