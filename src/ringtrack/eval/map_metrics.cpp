#include "ringtrack/eval/map_metrics.hpp"

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"

namespace ringtrack::eval {

double MapCounts::preservation_rate() const {
  return static_points == 0 ? std::numeric_limits<double>::quiet_NaN()
                            : static_cast<double>(static_kept) / static_cast<double>(static_points);
}

double MapCounts::rejection_rate() const {
  return dynamic_points == 0
             ? std::numeric_limits<double>::quiet_NaN()
             : static_cast<double>(dynamic_removed) / static_cast<double>(dynamic_points);
}

void MapCounts::add_point(std::int64_t label, bool object_dynamic, bool kept) {
  if (label < 0) {
    throw core::InputError("map metrics: point label must be >= 0 (0 = static background), got " +
                           std::to_string(label));
  }
  if (label > 0 && object_dynamic) {
    ++dynamic_points;
    if (!kept) ++dynamic_removed;
  } else {
    ++static_points;
    if (kept) ++static_kept;
  }
}

MapCounts& MapCounts::operator+=(const MapCounts& o) {
  static_points += o.static_points;
  static_kept += o.static_kept;
  dynamic_points += o.dynamic_points;
  dynamic_removed += o.dynamic_removed;
  return *this;
}

MapCounts count_map_points(std::span<const std::int64_t> labels, std::span<const std::uint8_t> kept,
                           std::span<const std::int64_t> dynamic_ids) {
  if (labels.size() != kept.size()) {
    throw core::InputError("map metrics: " + std::to_string(labels.size()) + " labels but " +
                           std::to_string(kept.size()) + " kept flags");
  }
  std::vector<std::int64_t> dynamic(dynamic_ids.begin(), dynamic_ids.end());
  std::sort(dynamic.begin(), dynamic.end());
  MapCounts counts;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const bool is_dynamic = std::binary_search(dynamic.begin(), dynamic.end(), labels[i]);
    counts.add_point(labels[i], is_dynamic, kept[i] != 0);
  }
  return counts;
}

}  // namespace ringtrack::eval
