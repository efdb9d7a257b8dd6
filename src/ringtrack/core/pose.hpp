#pragma once
/// Rigid pose of the sensor in the world frame at a time.

#include <Eigen/Geometry>
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

}  // namespace ringtrack::core
