#pragma once
/// Rigid pose of the sensor in the world frame at a time.

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>

namespace ringtrack::core {

/// Sensor-to-world transform at stamp_ns; identity means the sensor sits at the world origin.
struct Pose {
  std::int64_t stamp_ns{0};
  Eigen::Vector3d translation{Eigen::Vector3d::Zero()};
  Eigen::Quaterniond rotation{Eigen::Quaterniond::Identity()};

  /// The transform as an isometry (world_T_sensor).
  [[nodiscard]] Eigen::Isometry3d isometry() const {
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = rotation.normalized().toRotationMatrix();
    t.translation() = translation;
    return t;
  }
  /// Maps a sensor-frame point into the world frame.
  [[nodiscard]] Eigen::Vector3f to_world(const Eigen::Vector3f& p) const {
    return (rotation.normalized() * p.cast<double>() + translation).cast<float>();
  }
  /// True when other lies within shift_m of this pose's position and turn_rad of its rotation
  /// (a resting sensor's pose noise).
  [[nodiscard]] bool near(const Pose& other, double shift_m, double turn_rad) const {
    return (translation - other.translation).norm() <= shift_m &&
           rotation.normalized().angularDistance(other.rotation.normalized()) <= turn_rad;
  }
  /// Pose interpolated between a (at t=0) and b (at t=1): linear translation, slerp rotation.
  [[nodiscard]] static Pose interpolate(const Pose& a, const Pose& b, double t) {
    Pose out;
    out.stamp_ns =
        a.stamp_ns + static_cast<std::int64_t>(t * static_cast<double>(b.stamp_ns - a.stamp_ns));
    out.translation = a.translation + t * (b.translation - a.translation);
    out.rotation = a.rotation.slerp(t, b.rotation);
    return out;
  }
};

/// A constant rigid motion of the sensor, both rates in the world frame: the pose dt seconds
/// after `pose` has its translation moved by velocity * dt and its rotation turned by the
/// rotation vector angular_velocity * dt (applied in the world frame, before pose's rotation).
/// Between two poses this is exactly what Pose::interpolate does (linear, slerp).
struct Motion {
  Eigen::Vector3d velocity_mps{Eigen::Vector3d::Zero()};
  Eigen::Vector3d angular_velocity_radps{Eigen::Vector3d::Zero()};

  /// True when the sensor does not move at all.
  [[nodiscard]] bool still() const {
    return velocity_mps.isZero(0.0) && angular_velocity_radps.isZero(0.0);
  }
  /// The motion that carries `earlier` into `later` at a constant rate; still when `later` is not
  /// later or either pose is not finite.
  [[nodiscard]] static Motion between(const Pose& earlier, const Pose& later) {
    Motion m;
    const double dt_s = 1e-9 * static_cast<double>(later.stamp_ns - earlier.stamp_ns);
    if (!(dt_s > 0.0)) return m;
    const Eigen::Quaterniond turn =
        later.rotation.normalized() * earlier.rotation.normalized().conjugate();
    const Eigen::AngleAxisd axis_angle(turn);  // angle in [0, pi]: the shorter way round
    m.velocity_mps = (later.translation - earlier.translation) / dt_s;
    m.angular_velocity_radps = axis_angle.axis() * (axis_angle.angle() / dt_s);
    if (!m.velocity_mps.allFinite() || !m.angular_velocity_radps.allFinite()) return Motion{};
    return m;
  }
  /// `pose` moved on by dt_s seconds of this motion (stamp included).
  [[nodiscard]] Pose advance(const Pose& pose, double dt_s) const {
    Pose out;
    out.stamp_ns = pose.stamp_ns + static_cast<std::int64_t>(std::llround(dt_s * 1e9));
    out.translation = pose.translation + dt_s * velocity_mps;
    const double rate = angular_velocity_radps.norm();
    out.rotation = pose.rotation.normalized();
    if (rate > 0.0) {
      out.rotation =
          Eigen::Quaterniond(Eigen::AngleAxisd(rate * dt_s, angular_velocity_radps / rate)) *
          out.rotation;
    }
    return out;
  }
};

}  // namespace ringtrack::core
