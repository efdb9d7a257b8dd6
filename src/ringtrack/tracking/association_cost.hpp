#pragma once
/// Distances between two Gaussian position distributions, used as assignment costs.

#include <Eigen/Core>

namespace ringtrack::tracking {

/// Bhattacharyya distance between N(m1, s1) and N(m2, s2): with S = (s1 + s2) / 2 and
/// m = m1 - m2, d = m^T S^-1 m / 8 + ln(det S / sqrt(det s1 det s2)) / 2. Zero for identical
/// distributions; both terms are non-negative.
double bhattacharyya_distance(const Eigen::Vector3d& m1, const Eigen::Matrix3d& s1,
                              const Eigen::Vector3d& m2, const Eigen::Matrix3d& s2);

/// Mahalanobis distance of m1 - m2 under s1 + s2 (e.g. predicted and measurement covariance).
double mahalanobis_distance(const Eigen::Vector3d& m1, const Eigen::Matrix3d& s1,
                            const Eigen::Vector3d& m2, const Eigen::Matrix3d& s2);

/// Precomputed form of one distribution for fast repeated Bhattacharyya distances.
struct GaussianTerm {
  Eigen::Vector3d mean;
  Eigen::Matrix3d covariance;
  double log_det{0.0};        ///< ln det covariance
  double max_eig_bound{0.0};  ///< trace of the covariance, an upper bound of its eigenvalues
};

/// Prepares a distribution for bhattacharyya_distance(GaussianTerm, GaussianTerm).
GaussianTerm make_gaussian_term(const Eigen::Vector3d& mean, const Eigen::Matrix3d& covariance);

/// Same value as the matrix form, reusing the precomputed determinants.
double bhattacharyya_distance(const GaussianTerm& a, const GaussianTerm& b);

}  // namespace ringtrack::tracking
