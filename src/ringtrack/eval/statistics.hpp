#pragma once
/// Order statistics of per-scan series (times, errors) for reports.

#include <vector>

namespace ringtrack::eval {

/// Value at quantile q (0..1) by nearest rank on a copy; 0 for an empty series.
double quantile(std::vector<double> values, double q);

}  // namespace ringtrack::eval
