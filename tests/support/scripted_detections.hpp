#pragma once
// Scripted detection streams for tracking and mapping tests and benchmarks: person-shaped
// detections placed by hand, with optional noise and partial occlusion, no simulator needed.

#include <Eigen/Core>
#include <cstdint>
#include <random>
#include <vector>

#include "ringtrack/core/detection.hpp"

namespace ringtrack::testing {

/// Shape and noise of a scripted person.
struct PersonShape {
  float radius_m{0.25f};         ///< half the footprint's side
  float height_m{1.75f};         ///< feet to head
  float visible_from_m{0.0f};    ///< lowest visible height above the feet (occluded below)
  float centroid_noise_m{0.0f};  ///< Gaussian noise on the centroid (box moves with it)
  float box_noise_m{0.0f};       ///< Gaussian noise on each box face independently
  std::uint32_t points{40};      ///< number of fake cell indices
};

/// A person standing with feet at foot (world): centroid at mid visible height, a box around
/// the visible part, covariance of points spread over that box (uniform distribution).
core::Detection person_detection(const Eigen::Vector3f& foot, const PersonShape& shape,
                                 std::mt19937_64* rng = nullptr);

/// Nanoseconds of scan k at rate_hz.
inline std::int64_t scan_stamp_ns(int k, double rate_hz = 10.0) {
  return static_cast<std::int64_t>(static_cast<double>(k) * 1e9 / rate_hz + 0.5);
}

}  // namespace ringtrack::testing
