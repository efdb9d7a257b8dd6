#include "ringtrack/core/organized_scan.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "ringtrack/core/error.hpp"

namespace ringtrack::core {
namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
}

OrganizedScan::OrganizedScan(int rings, int columns) : rings_(rings), columns_(columns) {
  if (rings <= 0 || columns <= 0) {
    throw Error("organized scan: expected positive rings and columns, got " +
                std::to_string(rings) + " x " + std::to_string(columns));
  }
  const auto n = static_cast<std::size_t>(rings) * static_cast<std::size_t>(columns);
  range_m_.assign(n, kNaN);
  intensity_.assign(n, 0.0f);
  x_.assign(n, kNaN);
  y_.assign(n, kNaN);
  z_.assign(n, kNaN);
  status_.assign(n, ReturnStatus::kNoReturn);
  column_azimuth_rad.assign(static_cast<std::size_t>(columns), 0.0);
  column_stamp_ns.assign(static_cast<std::size_t>(columns), 0);
}

void OrganizedScan::reset() {
  std::fill(range_m_.begin(), range_m_.end(), kNaN);
  std::fill(intensity_.begin(), intensity_.end(), 0.0f);
  std::fill(x_.begin(), x_.end(), kNaN);
  std::fill(y_.begin(), y_.end(), kNaN);
  std::fill(z_.begin(), z_.end(), kNaN);
  std::fill(status_.begin(), status_.end(), ReturnStatus::kNoReturn);
  std::fill(column_azimuth_rad.begin(), column_azimuth_rad.end(), 0.0);
  std::fill(column_stamp_ns.begin(), column_stamp_ns.end(), 0);
  stamp_ns = 0;
}

void OrganizedScan::set_return(int ring, int column, float range_m, float intensity,
                               const Eigen::Vector3f& xyz) {
  const auto i = index(ring, column);
  if (!std::isfinite(range_m) || !xyz.allFinite()) {
    set_invalid(ring, column, ReturnStatus::kNoReturn);
    return;
  }
  range_m_[i] = range_m;
  intensity_[i] = intensity;
  x_[i] = xyz.x();
  y_[i] = xyz.y();
  z_[i] = xyz.z();
  status_[i] = ReturnStatus::kValid;
}

void OrganizedScan::set_invalid(int ring, int column, ReturnStatus why) {
  const auto i = index(ring, column);
  range_m_[i] = kNaN;
  intensity_[i] = 0.0f;
  x_[i] = y_[i] = z_[i] = kNaN;
  status_[i] = why == ReturnStatus::kValid ? ReturnStatus::kNoReturn : why;
}

void OrganizedScan::set_range(const SensorModel& model, int ring, int column, float range_m,
                              float intensity) {
  if (!std::isfinite(range_m) || range_m <= 0.0f) {
    set_invalid(ring, column, ReturnStatus::kNoReturn);
  } else if (range_m < model.min_range_m) {
    set_invalid(ring, column, ReturnStatus::kTooClose);
  } else if (range_m > model.max_range_m) {
    set_invalid(ring, column, ReturnStatus::kTooFar);
  } else {
    set_return(ring, column, range_m, intensity,
               model.point(ring, column_azimuth_rad[static_cast<std::size_t>(column)], range_m));
  }
}

std::size_t OrganizedScan::valid_count() const {
  return static_cast<std::size_t>(std::count(status_.begin(), status_.end(), ReturnStatus::kValid));
}

void OrganizedScan::set_uniform_columns(const SensorModel& model, std::int64_t scan_stamp_ns) {
  stamp_ns = scan_stamp_ns;
  const double step = model.azimuth_step_rad();
  const double period_ns = model.firing_sequence_us * 1e3;
  for (int c = 0; c < columns_; ++c) {
    column_azimuth_rad[static_cast<std::size_t>(c)] = c * step;
    column_stamp_ns[static_cast<std::size_t>(c)] =
        scan_stamp_ns + static_cast<std::int64_t>(std::llround(c * period_ns));
  }
}

}  // namespace ringtrack::core
