#include "ringtrack/eval/statistics.hpp"

#include <algorithm>
#include <cstddef>

namespace ringtrack::eval {

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(values.size() - 1) + 0.5);
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

}  // namespace ringtrack::eval
