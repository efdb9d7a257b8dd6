#pragma once
// Reference segmentation: the definition, computed the slow obvious way (nth_element per window).

#include <cstdint>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/core/organized_scan.hpp"

namespace ringtrack::testing {

/// Labels every cell exactly as paper III.B defines it; O(kernel) per point.
std::vector<std::uint8_t> naive_segment(const core::OrganizedScan& scan,
                                        const core::SegmentationConfig& config);

}  // namespace ringtrack::testing
