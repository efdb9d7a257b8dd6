#pragma once
/// Constant-velocity Kalman filter on 3-D position and velocity (world frame).

#include <Eigen/Core>

namespace ringtrack::tracking {

/// Kalman filter with state [position; velocity] (m, m/s). The process is white acceleration
/// of spectral density q per axis (the continuous-time constant-velocity model), which adds
/// q*[dt^3/3, dt^2/2; dt^2/2, dt] per axis on prediction.
class ConstantVelocityKalman {
 public:
  using State = Eigen::Matrix<double, 6, 1>;       ///< [x y z vx vy vz]
  using Covariance = Eigen::Matrix<double, 6, 6>;  ///< of the state

  ConstantVelocityKalman() = default;
  /// Starts at rest at position with the given position covariance and an isotropic velocity
  /// prior of standard deviation velocity_stddev_mps.
  ConstantVelocityKalman(const Eigen::Vector3d& position,
                         const Eigen::Matrix3d& position_covariance, double velocity_stddev_mps);

  /// Moves the state dt_s seconds ahead; q is the acceleration spectral density (m^2/s^3).
  void predict(double dt_s, double q);
  /// Corrects with a position measurement z of covariance r.
  void update(const Eigen::Vector3d& z, const Eigen::Matrix3d& r);
  /// Holds the vertical velocity at exactly zero (state and covariance): the constant-position
  /// model in z for objects that stay on the ground.
  void hold_vertical_velocity();
  /// Adds variance (m^2) to the vertical position: a random walk in z.
  void add_vertical_variance(double variance_m2) { p_(2, 2) += variance_m2; }
  /// Scales the velocity down to max_speed_mps when faster (its direction is kept).
  void cap_speed(double max_speed_mps);
  /// Puts the object at rest at position (velocity zero), keeping the covariance: the state a
  /// walker is in when it stopped where it was last measured.
  void stop_at(const Eigen::Vector3d& position);

  /// Position estimate (m).
  [[nodiscard]] Eigen::Vector3d position() const { return x_.head<3>(); }
  /// Velocity estimate (m/s), not truncated.
  [[nodiscard]] Eigen::Vector3d velocity() const { return x_.tail<3>(); }
  /// Covariance of the position estimate (m^2).
  [[nodiscard]] Eigen::Matrix3d position_covariance() const { return p_.topLeftCorner<3, 3>(); }
  /// Full state.
  [[nodiscard]] const State& state() const { return x_; }
  /// Full covariance.
  [[nodiscard]] const Covariance& covariance() const { return p_; }

 private:
  State x_{State::Zero()};
  Covariance p_{Covariance::Identity()};
};

}  // namespace ringtrack::tracking
