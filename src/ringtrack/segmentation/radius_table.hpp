#pragma once
// KernelRadius as a table lookup: per range bucket the radius at both ends, and for buckets
// where it changes, the exact float thresholds at which it steps. Same results, no atan.

#include <cstdint>
#include <vector>

#include "ringtrack/segmentation/kernel.hpp"
#include "ringtrack/segmentation/range_buckets.hpp"

namespace ringtrack::segmentation::detail {

class RadiusTable {
 public:
  RadiusTable() = default;
  explicit RadiusTable(const KernelRadius& formula);

  /// Equal to formula(v) for every finite v > 0 whose bucket is `key`.
  [[nodiscard]] int radius(float v, std::uint32_t key) const {
    int r = radius_at_lower_[key];
    const int r_min = radius_at_upper_[key];
    while (r > r_min && v > threshold_[static_cast<std::size_t>(r)]) --r;
    return r;
  }
  /// radius(v) <= k exactly when v > this bound (values are positive, so k >= the largest
  /// radius gives a bound below every value).
  [[nodiscard]] float radius_at_most_above(int k) const {
    const auto next = static_cast<std::size_t>(k) + 1;
    return next < threshold_.size() ? threshold_[next] : -1.0f;
  }
  /// radius(v) >= k exactly when v <= this bound (k >= 0).
  [[nodiscard]] float radius_at_least_up_to(int k) const {
    return static_cast<std::size_t>(k) < threshold_.size() ? threshold_[static_cast<std::size_t>(k)]
                                                           : -1.0f;
  }

 private:
  std::vector<std::uint16_t> radius_at_lower_;  // formula at the bucket's smallest value
  std::vector<std::uint16_t> radius_at_upper_;  // formula at the bucket's largest value
  std::vector<float> threshold_;                // [k]: largest float with formula >= k
};

}  // namespace ringtrack::segmentation::detail
