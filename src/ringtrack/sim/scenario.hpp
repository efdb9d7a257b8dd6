#pragma once
/// Simulator scenarios: static world (ground, boxes, cylinders, ellipsoids, walls), actors (people,
/// robots, drones, static distractors, scripted trajectories) and the sensor set-up. The built-in
/// scenarios mirror Table I of the paper plus an indoor hall.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "ringtrack/core/pose.hpp"
#include "ringtrack/sim/geometry.hpp"

namespace ringtrack::sim {

/// Class of a simulated object.
enum class ObjectClass : std::uint8_t { kPerson, kRobot, kDrone, kDistractor };
/// "person", "robot", "drone", "distractor".
std::string_view class_name(ObjectClass c);
/// Inverse of class_name; throws core::InputError naming the text.
ObjectClass class_from_name(std::string_view name);

/// Upright box (buildings, containers, cars, benches) with its bottom at base_z_m.
struct BoxSpec {
  Eigen::Vector2d center_m{Eigen::Vector2d::Zero()};
  Eigen::Vector3d size_m{1, 1, 1};
  double base_z_m{0.0};
  double yaw_deg{0.0};
  double reflectivity{0.4};
};
/// Upright capped cylinder (poles, trunks, fountains).
struct CylinderSpec {
  Eigen::Vector2d center_m{Eigen::Vector2d::Zero()};
  double radius_m{0.2};
  double height_m{3.0};
  double base_z_m{0.0};
  double reflectivity{0.4};
};
/// Ellipsoid (tree crowns, bushes), yawed about z; center_m.z() is its centre height.
struct EllipsoidSpec {
  Eigen::Vector3d center_m{Eigen::Vector3d::Zero()};
  Eigen::Vector3d radii_m{1, 1, 1};
  double yaw_deg{0.0};
  double reflectivity{0.3};
};
/// A wall from one point to another (a thin box).
struct WallSpec {
  Eigen::Vector2d from_m{Eigen::Vector2d::Zero()};
  Eigen::Vector2d to_m{Eigen::Vector2d::UnitX()};
  double height_m{3.0};
  double thickness_m{0.2};
  double base_z_m{0.0};
  double reflectivity{0.5};
};

/// One row of a scripted trajectory; z is the height of the object's base above the ground
/// (drones: flight altitude), NaN when not given.
struct Waypoint {
  double t_s{0.0};
  Eigen::Vector3d xyz_m{Eigen::Vector3d::Zero()};
};
/// An actor that follows waypoints, linear between them. It exists only from its first to its
/// last waypoint time (enters and leaves the scene); before and after it is absent: not rendered,
/// no ground truth.
struct ScriptedActor {
  std::uint32_t id{0};
  ObjectClass object_class{ObjectClass::kPerson};
  std::vector<Waypoint> waypoints;       ///< sorted by time, at least two
  std::optional<double> height_m{};      ///< people, distractors: body height (default 1.75 m)
  std::optional<double> width_m{};       ///< people, distractors: shoulder width (default 0.6 m)
  std::optional<double> reflectivity{};  ///< 0..1 (default 0.4)
  /// True while the actor exists: first waypoint time <= t_s <= last waypoint time.
  [[nodiscard]] bool present_at(double t_s) const {
    return !waypoints.empty() && t_s >= waypoints.front().t_s && t_s <= waypoints.back().t_s;
  }
};

/// Body size limits of scripted people and distractors (checked by the CSV reader and validate).
inline constexpr double kMinBodyHeightM = 0.5, kMaxBodyHeightM = 2.5;
inline constexpr double kMinBodyWidthM = 0.2, kMaxBodyWidthM = 1.2;
/// Shoulder width (outer arm to outer arm) of a person body at width scale 1.
inline constexpr double kPersonWidthM = 0.6;
/// Radius about the sensor's position_m (its mast; the figure-8 centre) that walkers keep out of.
inline constexpr double kSensorKeepOutM = 0.6;

/// Upper bounds validate() enforces, so that a typo (`duration_s: 1e12`) is an error naming the
/// key instead of a simulation that never ends or exhausts memory.
inline constexpr double kMaxDurationS = 86'400.0;     ///< one day: 864,000 scans at 10 Hz
inline constexpr int kMaxActorsPerKind = 1000;        ///< people, robots and drones, each
inline constexpr double kMaxWorldExtentM = 10'000.0;  ///< area sides, world and figure-8 radius
inline constexpr double kMaxSensorSpeedMps = 100.0;   ///< figure-8 peak speed

/// How the sensor moves.
enum class SensorMotion : std::uint8_t { kStatic, kFigure8, kScripted };
/// Sensor keyframe of a scripted sensor trajectory (roll, pitch, yaw in degrees).
struct SensorKeyframe {
  double t_s{0.0};
  Eigen::Vector3d xyz_m{Eigen::Vector3d::Zero()};
  Eigen::Vector3d rpy_deg{Eigen::Vector3d::Zero()};
};
/// Sensor model, placement, motion and measurement errors.
struct SensorSpec {
  std::string model{"vlp16"};                 ///< core::SensorModel::by_name
  Eigen::Vector3d position_m{0.0, 0.0, 2.5};  ///< static position / figure-8 centre
  SensorMotion motion{SensorMotion::kStatic};
  double figure8_radius_m{4.0};           ///< half width of the figure 8
  double max_speed_mps{5.0};              ///< peak speed on the figure 8 (MAV: <= 5.6)
  double tilt_gain{0.5};                  ///< roll/pitch = gain * tilt a real MAV needs
  std::vector<SensorKeyframe> keyframes;  ///< kScripted only
  double range_noise_m{0.03};             ///< Gaussian range noise sigma
  double dropout_probability{0.002};      ///< random missing returns anywhere
  double far_dropout_probability{0.05};   ///< extra dropout reached at max range (quadratic)
};

/// A complete simulation set-up. Built-in scenarios fix the layout; the run seed drives actors
/// and noise only.
struct Scenario {
  int number{0};     ///< 1..7 for built-ins, 0 for files
  std::string name;  ///< e.g. "park"
  std::string description;
  double duration_s{60.0};
  Eigen::Vector2d area_m{100.0, 100.0};  ///< walking area size (x, y)
  Eigen::Vector2d area_center_m{Eigen::Vector2d::Zero()};
  double world_radius_m{140.0};  ///< nothing exists beyond this distance
  Ground ground;
  SensorSpec sensor;
  int people{0};                             ///< random walkers
  int robots{0};                             ///< small ground robots (about 0.4 m high)
  int drones{0};                             ///< drones flying at 3-10 m
  std::vector<Eigen::Vector2d> distractors;  ///< static person-sized objects
  std::vector<ScriptedActor> scripted;       ///< in addition to the random actors
  std::string trajectories_file;             ///< where `scripted` came from (informative)
  std::vector<BoxSpec> boxes;
  std::vector<CylinderSpec> cylinders;
  std::vector<EllipsoidSpec> ellipsoids;
  std::vector<WallSpec> walls;
};

/// Throws core::ConfigError naming the entry (e.g. "cylinders[3]: radius_m must be > 0") when
/// sizes are not positive, probabilities are out of range, a scripted actor's waypoints or the
/// path segments between them touch an obstacle or the sensor's keep-out zone, or a moving
/// sensor's path passes through a solid.
void validate(const Scenario& s, const std::string& source = "scenario");

/// Sensor-to-world pose of the sensor spec at time t_ns (static, figure 8 or keyframes).
core::Pose sensor_pose(const SensorSpec& sensor, std::int64_t t_ns);

/// Angular rate w (rad/s) of the figure 8 (figure8_radius_m, max_speed_mps): the path repeats
/// every 2 pi / w, its height and yaw every 4 pi / w.
double figure8_rate(const SensorSpec& sensor);

/// Number and name of each built-in scenario.
struct ScenarioInfo {
  int number;
  std::string name;
  std::string description;
};
/// The built-in scenarios in order 1..7.
std::vector<ScenarioInfo> builtin_scenarios();
/// A built-in scenario by number ("1".."7") or name (optionally suffixed "-moving"); throws
/// core::ConfigError listing the choices.
Scenario builtin_scenario(std::string_view number_or_name);
/// The same scenario with the sensor on its figure 8 (radius kept unless indoor).
Scenario with_moving_sensor(Scenario s);

/// Static solids of the scenario's world in the world frame (labels 0).
std::vector<Primitive> static_primitives(const Scenario& s);

/// A 2-D obstacle footprint actors walk around: circle (half.y() == 0) or yawed rectangle.
struct Footprint {
  Eigen::Vector2d center{Eigen::Vector2d::Zero()};
  Eigen::Vector2d half{Eigen::Vector2d::Zero()};  ///< rectangle half sizes; circle: (r, 0)
  double yaw_rad{0.0};
  bool circle{true};
  std::string entry;  ///< "boxes[2]" etc., for error messages
  /// True when p lies within margin of the footprint.
  [[nodiscard]] bool contains(const Eigen::Vector2d& p, double margin) const;
  /// True when the segment a-b passes within margin of the footprint.
  [[nodiscard]] bool crosses(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                             double margin) const;
};
/// Footprints of everything that stands on the ground and is lower than max_base_z_m at its
/// bottom (tree crowns high above do not block walkers).
std::vector<Footprint> ground_footprints(const Scenario& s);

}  // namespace ringtrack::sim
