// The Kalman filter's block-wise kernels against the textbook matrix formulas, and the
// association costs against closed forms.

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <cmath>
#include <random>

#include "ringtrack/tracking/association_cost.hpp"
#include "ringtrack/tracking/kalman.hpp"

namespace ringtrack::tracking {
namespace {

using Matrix6 = Eigen::Matrix<double, 6, 6>;

Eigen::Matrix3d random_spd(std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Matrix3d a;
  for (int i = 0; i < 9; ++i) a(i / 3, i % 3) = n(rng);
  return scale * (a * a.transpose() + 0.1 * Eigen::Matrix3d::Identity());
}

TEST(ConstantVelocityKalman, PredictMatchesFullMatrixFormula) {
  std::mt19937_64 rng(3);
  ConstantVelocityKalman kf(Eigen::Vector3d(1, 2, 3), random_spd(rng, 0.1), 1.5);
  kf.update(Eigen::Vector3d(1.1, 2.0, 2.9), random_spd(rng, 0.05));  // couples all blocks
  const double dt = 0.1, q = 0.7;
  Matrix6 f = Matrix6::Identity();
  f.topRightCorner<3, 3>() = dt * Eigen::Matrix3d::Identity();
  Matrix6 qm = Matrix6::Zero();
  qm.topLeftCorner<3, 3>() = q * dt * dt * dt / 3 * Eigen::Matrix3d::Identity();
  qm.topRightCorner<3, 3>() = qm.bottomLeftCorner<3, 3>() =
      q * dt * dt / 2 * Eigen::Matrix3d::Identity();
  qm.bottomRightCorner<3, 3>() = q * dt * Eigen::Matrix3d::Identity();
  const Matrix6 expected_p = f * kf.covariance() * f.transpose() + qm;
  const ConstantVelocityKalman::State expected_x = f * kf.state();
  kf.predict(dt, q);
  EXPECT_TRUE(kf.covariance().isApprox(expected_p, 1e-12));
  EXPECT_TRUE(kf.state().isApprox(expected_x, 1e-12));
}

TEST(ConstantVelocityKalman, UpdateMatchesTextbookFormula) {
  std::mt19937_64 rng(5);
  ConstantVelocityKalman kf(Eigen::Vector3d(0, 0, 0), random_spd(rng, 0.1), 1.0);
  kf.predict(0.1, 0.5);
  const Eigen::Vector3d z(0.3, -0.2, 0.1);
  const Eigen::Matrix3d r = random_spd(rng, 0.02);
  Eigen::Matrix<double, 3, 6> h = Eigen::Matrix<double, 3, 6>::Zero();
  h.leftCols<3>().setIdentity();
  const Matrix6 p = kf.covariance();
  const Eigen::Matrix<double, 6, 3> k = p * h.transpose() * (h * p * h.transpose() + r).inverse();
  const ConstantVelocityKalman::State x = kf.state() + k * (z - h * kf.state());
  const Matrix6 p_next = (Matrix6::Identity() - k * h) * p;
  kf.update(z, r);
  EXPECT_TRUE(kf.state().isApprox(x, 1e-12));
  EXPECT_TRUE(kf.covariance().isApprox(p_next, 1e-10));
  EXPECT_TRUE(kf.covariance().isApprox(kf.covariance().transpose(), 0.0));
}

TEST(ConstantVelocityKalman, CapSpeedKeepsDirection) {
  ConstantVelocityKalman kf(Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity() * 0.01, 1.0);
  // A far measurement after a prediction induces a velocity along +x.
  kf.predict(0.1, 0.2);
  kf.update(Eigen::Vector3d(3, 0, 0), Eigen::Matrix3d::Identity() * 0.01);
  ASSERT_GT(kf.velocity().norm(), 2.0);
  kf.cap_speed(2.0);
  EXPECT_NEAR(kf.velocity().norm(), 2.0, 1e-12);
  EXPECT_NEAR(kf.velocity().normalized().x(), 1.0, 1e-9);
  kf.cap_speed(5.0);  // slower than the cap: unchanged
  EXPECT_NEAR(kf.velocity().norm(), 2.0, 1e-12);
}

TEST(AssociationCost, BhattacharyyaClosedForms) {
  const Eigen::Vector3d a(1, 2, 3);
  const Eigen::Matrix3d s = Eigen::Matrix3d::Identity() * 0.04;
  EXPECT_NEAR(bhattacharyya_distance(a, s, a, s), 0.0, 1e-12);
  // Equal isotropic covariances: only the mean term, |m|^2 / (8 sigma^2).
  const Eigen::Vector3d b = a + Eigen::Vector3d(0.3, 0.4, 0.0);
  EXPECT_NEAR(bhattacharyya_distance(a, s, b, s), 0.25 / (8 * 0.04), 1e-12);
  // Diagonal covariances: a sum of one-dimensional distances.
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.01, 1.0);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Vector3d s1(u(rng), u(rng), u(rng)), s2(u(rng), u(rng), u(rng));
    const Eigen::Vector3d m(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5);
    double expected = 0;
    for (int i = 0; i < 3; ++i) {
      expected += m[i] * m[i] / (4 * (s1[i] + s2[i])) +
                  0.5 * std::log((s1[i] + s2[i]) / 2 / std::sqrt(s1[i] * s2[i]));
    }
    EXPECT_NEAR(bhattacharyya_distance(m, s1.asDiagonal().toDenseMatrix(), Eigen::Vector3d::Zero(),
                                       s2.asDiagonal().toDenseMatrix()),
                expected, 1e-10);
  }
}

TEST(AssociationCost, InvariantUnderRotationAndSymmetric) {
  std::mt19937_64 rng(13);
  for (int trial = 0; trial < 50; ++trial) {
    const Eigen::Matrix3d s1 = random_spd(rng, 0.05), s2 = random_spd(rng, 0.2);
    const Eigen::Vector3d m1(0.1, 0.2, 0.3), m2(-0.2, 0.5, 0.0);
    const Eigen::Matrix3d r =
        Eigen::AngleAxisd(0.3 * trial, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    const double d = bhattacharyya_distance(m1, s1, m2, s2);
    EXPECT_NEAR(d, bhattacharyya_distance(m2, s2, m1, s1), 1e-10);
    EXPECT_NEAR(
        d, bhattacharyya_distance(r * m1, r * s1 * r.transpose(), r * m2, r * s2 * r.transpose()),
        1e-9);
    EXPECT_GE(d, 0.0);
    const double mahalanobis = mahalanobis_distance(m1, s1, m2, s2);
    EXPECT_NEAR(mahalanobis * mahalanobis, (m1 - m2).dot((s1 + s2).inverse() * (m1 - m2)), 1e-9);
  }
}

}  // namespace
}  // namespace ringtrack::tracking
