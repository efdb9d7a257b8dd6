#pragma once
/// The definitions both segmenters share: kernel radius per range and the certainty rule.
/// The fast segmenter must reproduce these exactly; the naive reference calls them directly.

#include <cstdint>

#include "ringtrack/core/config.hpp"

namespace ringtrack::segmentation {

/// Half width, in columns, of a median window that spans a given object width at a range:
/// r = floor or ceil(2 atan(width / 2 / range) / step), capped. floor for the noise filter (it
/// must not remove objects of the minimum width), ceil for the background filter (it must remove
/// objects up to the maximum width).
struct KernelRadius {
  double width_m{0.1};
  double azimuth_step_rad{0.0034906585};
  bool round_up{false};
  int cap{450};

  /// The radius for a point at range_m (> 0, finite).
  [[nodiscard]] int operator()(float range_m) const;
};

/// Half width cap for a ring of `columns` cells: the configured cap, at most (columns - 1) / 2
/// so that a window never covers a cell twice.
int effective_radius_cap(const core::SegmentationConfig& config, int columns);

/// Piecewise-linear certainty of a background-minus-noise median difference (paper III.B):
/// 0 below delta_min, rising to 1 at delta_low, 1 to delta_high, falling to 0 at delta_max.
double certainty(float delta_m, const core::SegmentationConfig& config);

/// The segment decision for one point from its two medians.
inline bool is_segment(float noise_median_m, float background_median_m,
                       const core::SegmentationConfig& config) {
  return certainty(background_median_m - noise_median_m, config) >= config.certainty_threshold;
}

/// The segment rule as intervals of the (float) median difference, so that bounds of the two
/// medians can settle a decision without the medians themselves: a difference below
/// background_below or above background_above is background, one in [segment_from, segment_to]
/// is a segment. Exact (the two intervals meet) whenever the certainty reaches the threshold at
/// some float; the fast segmenter relies on it only through these comparisons.
struct DeltaRule {
  float background_below{0};
  float segment_from{0};
  float segment_to{0};
  float background_above{0};
};

/// The rule for a configuration: the smallest and largest floats whose certainty reaches the
/// threshold, found by bisection over floats (certainty rises then falls, monotonically).
DeltaRule delta_rule(const core::SegmentationConfig& config);

/// Label values in a segmentation result.
enum SegmentLabel : std::uint8_t { kBackground = 0, kSegment = 1 };

}  // namespace ringtrack::segmentation

namespace ringtrack::segmentation {

/// The range the median filters see for a cell: its range when valid, else invalid_range_m
/// (invalid returns count as far background, so objects against the sky stand out).
inline float filter_range(float range_m, bool valid, float invalid_range_m) {
  return valid && range_m > 0.0f && range_m < invalid_range_m ? range_m : invalid_range_m;
}

}  // namespace ringtrack::segmentation
