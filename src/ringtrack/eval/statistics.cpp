#include "ringtrack/eval/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace ringtrack::eval {

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  // Nearest rank, halves up: q * (n - 1) >= 0 for the q of 0..1 the callers pass.
  const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(values.size() - 1)));
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace ringtrack::eval
