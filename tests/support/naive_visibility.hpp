#pragma once
// Reference for VisibilityQuery's boxes: every cell of the scan, its beam (cell_ray) tested
// against the box by slabs. Slow and obvious on purpose.

#include <cstddef>
#include <vector>

#include "ringtrack/core/visibility.hpp"

namespace ringtrack::testing {

/// Counts of every beam through the box by kind; cells lists the scan indices of those beams.
core::VisibilityCounts naive_in_box(const core::VisibilityQuery& q, const core::Box3& box,
                                    double margin, std::vector<std::size_t>& cells);

}  // namespace ringtrack::testing
