#pragma once
/// Simulated actors: people (six-part bodies with a walking gait), small ground robots, drones and
/// static person-sized distractors; random walking between goals around obstacles, or scripted.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <vector>

#include "ringtrack/sim/geometry.hpp"
#include "ringtrack/sim/random.hpp"
#include "ringtrack/sim/scenario.hpp"

namespace ringtrack::sim {

/// Kinematic state of an actor at one instant (world frame).
struct ActorState {
  Eigen::Vector3d base_m{Eigen::Vector3d::Zero()};  ///< feet / wheels on the ground; drones: centre
  double yaw_rad{0.0};
  Eigen::Vector3d velocity_mps{Eigen::Vector3d::Zero()};
  double gait_phase_rad{0.0};  ///< people: leg swing phase
};

/// One actor with its body proportions and, for random walkers, its walking state.
struct Actor {
  std::uint32_t id{0};
  ObjectClass object_class{ObjectClass::kPerson};
  double height_m{1.75};
  double width_scale{1.0};
  float reflectivity{0.4f};
  int script{-1};             ///< index into Scenario::scripted, -1 = random walker
  bool cylinder_body{false};  ///< distractors: a post-like cylinder instead of a mannequin
  // Random-walker state (base.z is the altitude above ground for drones, else unused).
  Eigen::Vector3d position{Eigen::Vector3d::Zero()};
  Eigen::Vector3d goal{Eigen::Vector3d::Zero()};
  double yaw_rad{0.0};
  double speed_mps{0.0};
  double target_speed_mps{1.0};
  double pause_s{0.0};
  double gait_phase_rad{0.0};
  Rng rng{1};
};

/// All actors of a scenario, advanced in fixed 10 ms steps so that their paths do not depend on
/// when scans are taken.
class ActorWorld {
 public:
  /// Creates the scenario's random and scripted actors (ids 1.. for random ones, skipping
  /// scripted ids); throws core::ConfigError when the walking area has no free space.
  ActorWorld(const Scenario& scenario, std::uint64_t seed);
  /// Steps the simulation up to time t_ns (never backwards).
  void advance_to(std::int64_t t_ns);
  /// True when actor i exists at t_ns (scripted actors: between their first and last waypoint).
  [[nodiscard]] bool present(std::size_t i, std::int64_t t_ns) const;
  /// States at t_ns >= the current time (extrapolated from the last step).
  [[nodiscard]] ActorState state_at(std::size_t i, std::int64_t t_ns) const;
  /// The actors.
  [[nodiscard]] const std::vector<Actor>& actors() const { return actors_; }

 private:
  void step(Actor& a, double dt_s);
  void choose_goal(Actor& a);
  /// A person, robot or drone with its body, a free start and a goal, from its own seed.
  Actor random_actor(ObjectClass c, std::uint32_t id, std::uint64_t seed);
  /// A free start for a new actor of class c (500 tries), or nullopt.
  [[nodiscard]] std::optional<Eigen::Vector3d> random_start(ObjectClass c, Rng& rng) const;
  [[nodiscard]] bool free_at(const Eigen::Vector2d& p, double margin) const;
  [[nodiscard]] bool free_path(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                               double margin) const;
  [[nodiscard]] Eigen::Vector2d random_point(Rng& rng) const;

  const Scenario* scenario_;
  std::vector<Footprint> footprints_;
  std::vector<Actor> actors_;
  std::int64_t time_ns_{0};
};

/// Appends the solids of an actor's body in state st to out (label = actor id, mover = slot).
void append_body(const Actor& a, const ActorState& st, std::int32_t slot,
                 std::vector<Primitive>& out);
/// True centre of the actor's body (middle of its height above the base).
Eigen::Vector3d body_center(const Actor& a, const ActorState& st);
/// State of a scripted trajectory at time t_s (clamped to the first and last row; whether the
/// actor exists then is ScriptedActor::present_at).
ActorState scripted_state(const ScriptedActor& s, double t_s, const Ground& ground,
                          double stride_m);

}  // namespace ringtrack::sim
