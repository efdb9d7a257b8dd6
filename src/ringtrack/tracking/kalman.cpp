#include "ringtrack/tracking/kalman.hpp"

#include <Eigen/LU>

namespace ringtrack::tracking {

ConstantVelocityKalman::ConstantVelocityKalman(const Eigen::Vector3d& position,
                                               const Eigen::Matrix3d& position_covariance,
                                               double velocity_stddev_mps) {
  x_.head<3>() = position;
  p_.setZero();
  p_.topLeftCorner<3, 3>() = position_covariance;
  p_.bottomRightCorner<3, 3>() =
      Eigen::Matrix3d::Identity() * (velocity_stddev_mps * velocity_stddev_mps);
}

void ConstantVelocityKalman::predict(double dt_s, double q) {
  if (dt_s <= 0.0) return;
  x_.head<3>() += dt_s * x_.tail<3>();
  // F P F^T on the 3x3 blocks [A B; B^T C] of P, with F = [I dt*I; 0 I].
  const Eigen::Matrix3d a = p_.topLeftCorner<3, 3>();
  const Eigen::Matrix3d b = p_.topRightCorner<3, 3>();
  const Eigen::Matrix3d c = p_.bottomRightCorner<3, 3>();
  const Eigen::Matrix3d b_next = b + dt_s * c;
  const double dt2 = dt_s * dt_s;
  p_.topLeftCorner<3, 3>() = a + dt_s * (b + b.transpose()) + dt2 * c;
  p_.topRightCorner<3, 3>() = b_next;
  p_.bottomLeftCorner<3, 3>() = b_next.transpose();
  const Eigen::Vector3d qpp = Eigen::Vector3d::Constant(q * dt2 * dt_s / 3.0);
  const Eigen::Vector3d qpv = Eigen::Vector3d::Constant(q * dt2 / 2.0);
  const Eigen::Vector3d qvv = Eigen::Vector3d::Constant(q * dt_s);
  p_.topLeftCorner<3, 3>().diagonal() += qpp;
  p_.topRightCorner<3, 3>().diagonal() += qpv;
  p_.bottomLeftCorner<3, 3>().diagonal() += qpv;
  p_.bottomRightCorner<3, 3>().diagonal() += qvv;
}

void ConstantVelocityKalman::update(const Eigen::Vector3d& z, const Eigen::Matrix3d& r) {
  const Eigen::Matrix3d s = p_.topLeftCorner<3, 3>() + r;
  // P H^T is the first three columns of P; K = P H^T S^-1.
  const Eigen::Matrix<double, 6, 3> pht = p_.leftCols<3>();
  const Eigen::Matrix<double, 6, 3> k = pht * s.inverse();
  x_ += k * (z - x_.head<3>());
  p_ -= k * pht.transpose();
  p_ = 0.5 * (p_ + p_.transpose()).eval();  // keep it symmetric against rounding
}

void ConstantVelocityKalman::hold_vertical_velocity() {
  x_(5) = 0.0;
  p_.row(5).setZero();
  p_.col(5).setZero();
}

void ConstantVelocityKalman::cap_speed(double max_speed_mps) {
  const double speed = x_.tail<3>().norm();
  if (speed > max_speed_mps && speed > 0.0) x_.tail<3>() *= max_speed_mps / speed;
}

void ConstantVelocityKalman::stop_at(const Eigen::Vector3d& position) {
  x_.head<3>() = position;
  x_.tail<3>().setZero();
}

}  // namespace ringtrack::tracking
