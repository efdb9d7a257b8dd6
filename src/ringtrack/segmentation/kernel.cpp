#include "ringtrack/segmentation/kernel.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <optional>

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

namespace {

// Floats in order as integers (for bisection over every float between two values).
std::int64_t float_order(float f) {
  const auto bits = std::bit_cast<std::int32_t>(f);
  return bits >= 0 ? bits : -static_cast<std::int64_t>(bits & 0x7fffffff);
}
float float_at(std::int64_t order) {
  return order >= 0 ? std::bit_cast<float>(static_cast<std::int32_t>(order))
                    : std::bit_cast<float>(static_cast<std::int32_t>(-order) |
                                           std::numeric_limits<std::int32_t>::min());
}

// The first float, going from `from` towards `to`, where pred differs from pred(from); needs
// pred(from) != pred(to) and pred monotone in between.
template <class Pred>
float boundary(float from, float to, Pred pred) {
  std::int64_t a = float_order(from), b = float_order(to);  // pred(a) != pred(b)
  const bool at_a = pred(from);
  while (std::abs(b - a) > 1) {
    const std::int64_t mid = a + (b - a) / 2;
    (pred(float_at(mid)) == at_a ? a : b) = mid;
  }
  return float_at(b);
}

}  // namespace

DeltaRule delta_rule(const core::SegmentationConfig& c) {
  const auto reaches = [&c](float d) { return certainty(d, c) >= c.certainty_threshold; };
  // Conservative rule: certainty is 0 outside [delta_min, delta_max] and 1 on [low, high], taken
  // inwards to floats (the bounds are doubles).
  const auto float_at_least = [](double x) {
    float f = static_cast<float>(x);
    while (static_cast<double>(f) < x) f = std::nextafter(f, 1e30f);
    return f;
  };
  const auto float_at_most = [](double x) {
    float f = static_cast<float>(x);
    while (static_cast<double>(f) > x) f = std::nextafter(f, -1e30f);
    return f;
  };
  const DeltaRule rule{float_at_least(c.delta_min_m), float_at_least(c.delta_low_m),
                       float_at_most(c.delta_high_m), float_at_most(c.delta_max_m)};
  // A float where the threshold is reached, from the plateau: near delta_low or delta_high.
  std::optional<float> peak;
  for (const double anchor : {c.delta_low_m, c.delta_high_m}) {
    float f = std::nextafter(std::nextafter(static_cast<float>(anchor), -1e30f), -1e30f);
    for (int step = 0; step < 5 && !peak; ++step, f = std::nextafter(f, 1e30f)) {
      if (reaches(f)) peak = f;
    }
  }
  if (!peak) return rule;
  // Floats strictly outside [delta_min, delta_max], where certainty is 0.
  float below = static_cast<float>(c.delta_min_m);
  while (static_cast<double>(below) >= c.delta_min_m) below = std::nextafter(below, -1e30f);
  float above = static_cast<float>(c.delta_max_m);
  while (static_cast<double>(above) <= c.delta_max_m) above = std::nextafter(above, 1e30f);
  const float from = boundary(below, *peak, reaches);
  const float to = boundary(above, *peak, reaches);
  return {from, from, to, to};
}

}  // namespace ringtrack::segmentation
