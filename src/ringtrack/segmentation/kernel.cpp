#include "ringtrack/segmentation/kernel.hpp"

#include <algorithm>
#include <cmath>

namespace ringtrack::segmentation {

int KernelRadius::operator()(float range_m) const {
  const double angle_steps =
      2.0 * std::atan(width_m / (2.0 * static_cast<double>(range_m))) / azimuth_step_rad;
  const double r = round_up ? std::ceil(angle_steps) : std::floor(angle_steps);
  return static_cast<int>(std::min(r, static_cast<double>(cap)));
}

int effective_radius_cap(const core::SegmentationConfig& config, int columns) {
  return std::max(0, std::min(config.max_kernel_radius, (columns - 1) / 2));
}

double certainty(float delta_m, const core::SegmentationConfig& c) {
  const double d = delta_m;
  if (d < c.delta_min_m || d > c.delta_max_m) return 0.0;
  if (d < c.delta_low_m) return (d - c.delta_min_m) / (c.delta_low_m - c.delta_min_m);
  if (d <= c.delta_high_m) return 1.0;
  return (c.delta_max_m - d) / (c.delta_max_m - c.delta_high_m);
}

}  // namespace ringtrack::segmentation
