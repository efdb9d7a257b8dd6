#include "support/naive_segmentation.hpp"

#include <algorithm>
#include <numbers>

#include "ringtrack/segmentation/kernel.hpp"

namespace ringtrack::testing {

std::vector<std::uint8_t> naive_segment(const core::OrganizedScan& scan,
                                        const core::SegmentationConfig& config) {
  using namespace segmentation;
  const int n = scan.columns();
  const double step = 2.0 * std::numbers::pi / n;
  const int cap = effective_radius_cap(config, n);
  const KernelRadius noise_radius{config.min_width_m, step, false, cap};
  const KernelRadius background_radius{config.max_width_m, step, true, cap};
  const auto invalid = static_cast<float>(config.invalid_range_m);
  std::vector<std::uint8_t> labels(scan.size(), kBackground);
  std::vector<float> ring(static_cast<std::size_t>(n)), window;
  auto median = [&](int col, int r) {
    window.clear();
    for (int k = col - r; k <= col + r; ++k)
      window.push_back(ring[static_cast<std::size_t>((k % n + n) % n)]);
    std::nth_element(window.begin(), window.begin() + r, window.end());
    return window[static_cast<std::size_t>(r)];
  };
  for (int r = 0; r < scan.rings(); ++r) {
    for (int c = 0; c < n; ++c) {
      const auto i = scan.index(r, c);
      ring[static_cast<std::size_t>(c)] = filter_range(scan.range_m(i), scan.valid(i), invalid);
    }
    for (int c = 0; c < n; ++c) {
      const float v = ring[static_cast<std::size_t>(c)];
      if (!scan.valid(scan.index(r, c)) || !(v < invalid)) continue;
      const float noise = median(c, noise_radius(v));
      const float background = median(c, background_radius(v));
      if (is_segment(noise, background, config)) labels[scan.index(r, c)] = kSegment;
    }
  }
  return labels;
}

}  // namespace ringtrack::testing
