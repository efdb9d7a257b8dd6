#pragma once
/// One revolution of a spinning LiDAR as a rings x columns grid.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "ringtrack/core/sensor_model.hpp"

namespace ringtrack::core {

/// Why a grid cell holds or lacks a return. Invalid cells carry NaN range and coordinates.
enum class ReturnStatus : std::uint8_t {
  kNoReturn = 0,  ///< no echo (sky, absorbing surface, dropped packet)
  kValid = 1,     ///< a usable return
  kTooClose = 2,  ///< below the sensor's minimum range
  kTooFar = 3,    ///< beyond the sensor's maximum range
};

/// Organized scan: cell (ring, column) at index ring * columns + column; ring 0 is the bottom
/// ring. Per-cell data is stored as separate arrays so hot loops read one contiguous stream.
class OrganizedScan {
 public:
  OrganizedScan() = default;
  /// An all-invalid scan of the given size.
  OrganizedScan(int rings, int columns);

  [[nodiscard]] int rings() const { return rings_; }
  [[nodiscard]] int columns() const { return columns_; }
  [[nodiscard]] std::size_t size() const { return range_m_.size(); }
  [[nodiscard]] std::size_t index(int ring, int column) const {
    return static_cast<std::size_t>(ring) * static_cast<std::size_t>(columns_) +
           static_cast<std::size_t>(column);
  }
  [[nodiscard]] int ring_of(std::size_t i) const { return static_cast<int>(i / columns_); }
  [[nodiscard]] int column_of(std::size_t i) const { return static_cast<int>(i % columns_); }

  /// Makes every cell invalid (kNoReturn) and zeroes the column data and stamp, keeping the
  /// memory (for decoders that reuse a scan handed back by their consumer).
  void reset();

  /// Stores a valid return with its sensor-frame coordinates.
  void set_return(int ring, int column, float range_m, float intensity, const Eigen::Vector3f& xyz);
  /// Marks a cell invalid (range and coordinates become NaN, intensity 0).
  void set_invalid(int ring, int column, ReturnStatus why);
  /// Stores a range, classifying it against [min_range_m, max_range_m] of the model and computing
  /// the point from the model's geometry at the column's azimuth.
  void set_range(const SensorModel& model, int ring, int column, float range_m, float intensity);

  [[nodiscard]] bool valid(std::size_t i) const { return status_[i] == ReturnStatus::kValid; }
  [[nodiscard]] ReturnStatus status(std::size_t i) const { return status_[i]; }
  [[nodiscard]] float range_m(std::size_t i) const { return range_m_[i]; }
  [[nodiscard]] float intensity(std::size_t i) const { return intensity_[i]; }
  [[nodiscard]] Eigen::Vector3f point(std::size_t i) const { return {x_[i], y_[i], z_[i]}; }
  /// Number of valid cells.
  [[nodiscard]] std::size_t valid_count() const;

  /// Contiguous per-cell arrays (row-major by ring) for hot loops.
  [[nodiscard]] const std::vector<float>& ranges() const { return range_m_; }
  [[nodiscard]] const std::vector<float>& xs() const { return x_; }
  [[nodiscard]] const std::vector<float>& ys() const { return y_; }
  [[nodiscard]] const std::vector<float>& zs() const { return z_; }
  [[nodiscard]] const std::vector<float>& intensities() const { return intensity_; }
  [[nodiscard]] const std::vector<ReturnStatus>& statuses() const { return status_; }

  /// Writable views of the per-cell arrays (same layout as ranges() and the others).
  struct Cells {
    float* range_m;        ///< ranges() (NaN where not valid)
    float* intensity;      ///< intensities() (0 where not valid)
    float* x;              ///< xs() (NaN where not valid)
    float* y;              ///< ys()
    float* z;              ///< zs()
    ReturnStatus* status;  ///< statuses()
  };
  /// The per-cell arrays for a decoder's hot loop that writes cells without a call per cell.
  /// The writer keeps set_return's and set_invalid's invariants: a valid cell holds a finite
  /// range and point; any other cell a NaN range and point and intensity 0.
  [[nodiscard]] Cells cells() {
    return {range_m_.data(), intensity_.data(), x_.data(), y_.data(), z_.data(), status_.data()};
  }

  /// Azimuth of each column (radians, counter-clockwise from +x).
  std::vector<double> column_azimuth_rad;
  /// Time of each column's first firing (ns, same clock as the poses).
  std::vector<std::int64_t> column_stamp_ns;
  /// Time of the scan (its first column), ns.
  std::int64_t stamp_ns{0};

  /// Sets column azimuths to column * step and stamps to stamp_ns + column * period.
  void set_uniform_columns(const SensorModel& model, std::int64_t scan_stamp_ns);

 private:
  int rings_{0};
  int columns_{0};
  std::vector<float> range_m_, intensity_, x_, y_, z_;
  std::vector<ReturnStatus> status_;
};

}  // namespace ringtrack::core
