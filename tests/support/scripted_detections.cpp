#include "support/scripted_detections.hpp"

namespace ringtrack::testing {

core::Detection person_detection(const Eigen::Vector3f& foot, const PersonShape& shape,
                                 std::mt19937_64* rng) {
  const auto noise = [&](float sigma) {
    if (rng == nullptr || sigma <= 0.0f) return 0.0f;
    return std::normal_distribution<float>(0.0f, sigma)(*rng);
  };
  const Eigen::Vector3f shift(noise(shape.centroid_noise_m), noise(shape.centroid_noise_m),
                              noise(shape.centroid_noise_m));
  core::Detection d;
  const float z0 = foot.z() + shape.visible_from_m;
  const float z1 = foot.z() + shape.height_m;
  d.box.min = Eigen::Vector3f(foot.x() - shape.radius_m, foot.y() - shape.radius_m, z0) + shift;
  d.box.max = Eigen::Vector3f(foot.x() + shape.radius_m, foot.y() + shape.radius_m, z1) + shift;
  for (int a = 0; a < 3; ++a) {
    d.box.min[a] += noise(shape.box_noise_m);
    d.box.max[a] += noise(shape.box_noise_m);
    if (d.box.min[a] > d.box.max[a]) std::swap(d.box.min[a], d.box.max[a]);
  }
  d.centroid = Eigen::Vector3f(foot.x(), foot.y(), 0.5f * (z0 + z1)) + shift;
  const Eigen::Vector3f size(2.0f * shape.radius_m, 2.0f * shape.radius_m, z1 - z0);
  d.covariance = (size.array().square() / 12.0f).matrix().asDiagonal();
  d.indices.resize(shape.points);
  for (std::uint32_t i = 0; i < shape.points; ++i) d.indices[i] = i;
  return d;
}

}  // namespace ringtrack::testing
