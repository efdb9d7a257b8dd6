#include "ringtrack/tracking/association_cost.hpp"

#include <Eigen/LU>
#include <cmath>

namespace ringtrack::tracking {

GaussianTerm make_gaussian_term(const Eigen::Vector3d& mean, const Eigen::Matrix3d& covariance) {
  return {mean, covariance, std::log(covariance.determinant()), covariance.trace()};
}

double bhattacharyya_distance(const GaussianTerm& a, const GaussianTerm& b) {
  const Eigen::Matrix3d s = 0.5 * (a.covariance + b.covariance);
  const Eigen::Vector3d m = a.mean - b.mean;
  const double det_s = s.determinant();
  const double mahalanobis2 = m.dot(s.inverse() * m);
  return mahalanobis2 / 8.0 + 0.5 * (std::log(det_s) - 0.5 * (a.log_det + b.log_det));
}

double bhattacharyya_distance(const Eigen::Vector3d& m1, const Eigen::Matrix3d& s1,
                              const Eigen::Vector3d& m2, const Eigen::Matrix3d& s2) {
  return bhattacharyya_distance(make_gaussian_term(m1, s1), make_gaussian_term(m2, s2));
}

double mahalanobis_distance(const Eigen::Vector3d& m1, const Eigen::Matrix3d& s1,
                            const Eigen::Vector3d& m2, const Eigen::Matrix3d& s2) {
  const Eigen::Vector3d m = m1 - m2;
  return std::sqrt(m.dot((s1 + s2).inverse() * m));
}

}  // namespace ringtrack::tracking
