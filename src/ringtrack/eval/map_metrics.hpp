#pragma once
/// Map metrics of a dynamic-object filter from per-point labels (as ERASOR, Lim et al. 2021):
/// preservation rate = static points kept / static points, rejection rate = dynamic points removed
/// / dynamic points.

#include <cstdint>
#include <span>

namespace ringtrack::eval {

/// Summable point counts of a filter's result; rates are computed from the sums.
struct MapCounts {
  std::int64_t static_points = 0;    ///< background points and points of non-dynamic objects
  std::int64_t static_kept = 0;      ///< of those, kept by the filter
  std::int64_t dynamic_points = 0;   ///< points of dynamic (moving) objects
  std::int64_t dynamic_removed = 0;  ///< of those, removed by the filter

  /// static_kept / static_points; NaN without static points.
  [[nodiscard]] double preservation_rate() const;
  /// dynamic_removed / dynamic_points; NaN without dynamic points.
  [[nodiscard]] double rejection_rate() const;
  /// Adds one point: label 0 = static background, > 0 = object id; object_dynamic tells whether
  /// that object counts as dynamic (ignored for label 0). Throws core::InputError for label < 0.
  void add_point(std::int64_t label, bool object_dynamic, bool kept);
  /// Adds another scan's or sequence's counts.
  MapCounts& operator+=(const MapCounts& other);
};

/// Counts a whole cloud: labels[i] and kept[i] (non-zero = kept) per point; an object is dynamic
/// when its id is in dynamic_ids. Throws core::InputError when the spans differ in length or a
/// label is negative.
[[nodiscard]] MapCounts count_map_points(std::span<const std::int64_t> labels,
                                         std::span<const std::uint8_t> kept,
                                         std::span<const std::int64_t> dynamic_ids);

}  // namespace ringtrack::eval
