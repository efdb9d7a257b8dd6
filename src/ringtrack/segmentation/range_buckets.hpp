#pragma once
// Monotone bucketing of non-negative floats by their bit pattern: 1024 buckets per doubling
// (0.1 % relative width, 1 mm at 1 m, 6 cm at 64 m), so a bucket brackets its values to
// [lower, upper). Finer buckets give tighter brackets but make the rank pointers walk more;
// 512-4096 per doubling were measured, 1024 was best on the hard, open-field and park scans.

#include <bit>
#include <cstdint>
#include <limits>

namespace ringtrack::segmentation::detail {

class RangeBuckets {
 public:
  static constexpr int kMantissaBits = 10;
  static constexpr int kShift = 23 - kMantissaBits;
  static constexpr float kLowest = 0.0625f;  // 2^-4: smaller values share bucket 0
  static constexpr float kHighest = 512.0f;  // 2^9: larger values share the last bucket
  static constexpr std::uint32_t kBase = std::bit_cast<std::uint32_t>(kLowest) >> kShift;
  static constexpr std::uint32_t kCount =
      (std::bit_cast<std::uint32_t>(kHighest) >> kShift) - kBase;

  /// Bucket of a value >= 0 (NaN-free); monotone non-decreasing in the value.
  static std::uint32_t key(float v) {
    const std::uint32_t bits = std::bit_cast<std::uint32_t>(v) >> kShift;
    if (bits <= kBase) return 0;
    return bits - kBase >= kCount ? kCount - 1 : bits - kBase;
  }
  /// Smallest value of a bucket (0 for the first).
  static float lower(std::uint32_t b) {
    return b == 0 ? 0.0f : std::bit_cast<float>((b + kBase) << kShift);
  }
  /// Bound above every value of a bucket (infinity for the last).
  static float upper(std::uint32_t b) {
    return b + 1 >= kCount ? std::numeric_limits<float>::infinity() : lower(b + 1);
  }
};

}  // namespace ringtrack::segmentation::detail
