#include "ringtrack/segmentation/radius_table.hpp"

#include <bit>
#include <cmath>
#include <limits>

namespace ringtrack::segmentation::detail {
namespace {

// Largest positive finite float d with formula(d) >= k; formula is non-increasing in d.
float largest_with_radius_at_least(const KernelRadius& formula, int k) {
  std::uint32_t lo = std::bit_cast<std::uint32_t>(std::numeric_limits<float>::denorm_min());
  std::uint32_t hi = std::bit_cast<std::uint32_t>(std::numeric_limits<float>::max());
  if (formula(std::bit_cast<float>(lo)) < k) return 0.0f;
  if (formula(std::bit_cast<float>(hi)) >= k) return std::bit_cast<float>(hi);
  while (hi - lo > 1) {  // invariant: formula(lo) >= k > formula(hi)
    const std::uint32_t mid = lo + (hi - lo) / 2;
    (formula(std::bit_cast<float>(mid)) >= k ? lo : hi) = mid;
  }
  return std::bit_cast<float>(lo);
}

}  // namespace

RadiusTable::RadiusTable(const KernelRadius& formula) {
  const auto buckets = RangeBuckets::kCount;
  radius_at_lower_.resize(buckets);
  radius_at_upper_.resize(buckets);
  const float smallest = std::numeric_limits<float>::denorm_min();
  for (std::uint32_t b = 0; b < buckets; ++b) {
    const float lo = b == 0 ? smallest : RangeBuckets::lower(b);
    const float hi_excl = RangeBuckets::upper(b);
    const float hi =
        std::isinf(hi_excl) ? std::numeric_limits<float>::max() : std::nextafter(hi_excl, 0.0f);
    radius_at_lower_[b] = static_cast<std::uint16_t>(formula(lo));
    radius_at_upper_[b] = static_cast<std::uint16_t>(formula(hi));
  }
  const int max_radius = formula(smallest);
  threshold_.resize(static_cast<std::size_t>(max_radius) + 1);
  for (int k = 0; k <= max_radius; ++k) {
    threshold_[static_cast<std::size_t>(k)] = largest_with_radius_at_least(formula, k);
  }
}

}  // namespace ringtrack::segmentation::detail
