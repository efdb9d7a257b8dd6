#pragma once
// The median of a tiny window (far points' noise windows span 1-5 cells) by comparisons only:
// cheaper than maintaining or bounding a histogram window for them.

#include <algorithm>
#include <utility>

namespace ringtrack::segmentation::detail {

/// Radius up to which a median is computed directly from the values (at most 5 of them).
inline constexpr int kDirectRadius = 2;

/// The median of the 2 r + 1 values around *centre, r <= kDirectRadius, by comparisons only.
inline float direct_median(const float* centre, int r) {
  const auto median3 = [](float a, float b, float c) {
    return std::max(std::min(a, b), std::min(std::max(a, b), c));
  };
  if (r == 0) return centre[0];
  if (r == 1) return median3(centre[-1], centre[0], centre[1]);
  // Of five values: order the outer pairs, a <= b and c <= d, so that a <= c. Then a is at most
  // b, c and d, so it can be dropped as one of the two values below the median: the median is
  // the second smallest of b, c, d and the centre e, i.e. of the ordered pairs (b, e) and (c, d).
  float a = centre[-2], b = centre[-1], c = centre[1], d = centre[2], e = centre[0];
  if (a > b) std::swap(a, b);
  if (c > d) std::swap(c, d);
  if (a > c) {  // swap the pairs; the new a is not needed further
    c = a;
    std::swap(b, d);
  }
  if (b > e) std::swap(b, e);
  return std::min(std::max(b, c), std::min(e, d));
}

}  // namespace ringtrack::segmentation::detail
