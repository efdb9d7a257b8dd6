#pragma once
/// Per-cell range of the static background seen by a static sensor, learned over scans.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/scene_memory.hpp"
#include "ringtrack/core/sensor_model.hpp"

namespace ringtrack::core {

/// Learns, per cell of a static sensor, the range of the static background. Cells are the
/// model's grid: ring * bins + bin, bin = the column azimuth rounded to the model's azimuth step,
/// so scans with a varying column count or start azimuth (real captures) update the same cells;
/// scans made with OrganizedScan::set_uniform_columns have cell == scan index.
class BackgroundRangeModel : public SceneMemory {
 public:
  /// An empty model for the sensor (BackgroundRangeConfig: config.hpp, the `background`
  /// section); throws ConfigError naming the parameter when out of range.
  explicit BackgroundRangeModel(const SensorModel& model, const BackgroundRangeConfig& config = {});

  /// Adds one scan (taken from the same static pose). Throws InputError on a ring-count mismatch.
  void update(const OrganizedScan& scan);
  /// Learned background range of a cell: NaN when not learned, +infinity when learned open.
  [[nodiscard]] float background_range(std::size_t cell) const { return background_[cell]; }
  /// True when range_m lies more than margin_m in front of the cell's learned background
  /// (evidence of a new object); false when nothing is learned.
  [[nodiscard]] bool is_in_front(std::size_t cell, double range_m, double margin_m) const;
  /// The model cell of a scan cell (by ring and column azimuth).
  [[nodiscard]] std::size_t cell_of(const OrganizedScan& scan, std::size_t scan_index) const;
  /// is_in_front for a scan cell's own return (false for invalid cells).
  [[nodiscard]] bool is_in_front(const OrganizedScan& scan, std::size_t scan_index,
                                 double margin_m) const;

  /// SceneMemory: is_in_front for the cell's own return (the world point is not needed: the
  /// model is kept in the resting sensor's frame).
  [[nodiscard]] bool seen_free_before(const OrganizedScan& scan, std::size_t cell,
                                      const Eigen::Vector3d& world_point,
                                      double margin_m) const override {
    static_cast<void>(world_point);
    return is_in_front(scan, cell, margin_m);
  }

  /// Number of rings.
  [[nodiscard]] int rings() const { return rings_; }
  /// Number of azimuth bins per ring.
  [[nodiscard]] int bins() const { return bins_; }
  /// Number of cells (rings * bins).
  [[nodiscard]] std::size_t size() const { return background_.size(); }
  /// Scans added so far.
  [[nodiscard]] std::int64_t scans() const { return scans_; }
  /// Cells with a learned background (finite or open).
  [[nodiscard]] std::size_t learned_count() const;
  /// Forgets everything learned.
  void reset();

 private:
  [[nodiscard]] int bin_of(double azimuth_rad) const;
  void map_columns(const OrganizedScan& scan);
  /// Two finite ranges are one surface (within the tolerances). update()'s per-cell loop
  /// repeats this test with the tolerances in locals (MatchesTheNaiveReferenceCellByCell).
  [[nodiscard]] bool same_surface(float a, float b) const {
    return std::abs(a - b) <= config_.tolerance_m + config_.relative_tolerance * std::min(a, b);
  }
  void observe(std::size_t cell, float range_m);

  BackgroundRangeConfig config_;
  int rings_;
  int bins_;
  double bin_width_rad_;
  std::int64_t scans_{0};
  std::vector<float> background_;  // NaN: not learned; +inf: open
  std::vector<float> candidate_;   // mean of the current streak of consistent ranges
  std::vector<std::uint16_t> streak_;
  std::vector<int> column_bin_;          // bin of each column (-1: a second column in a bin)
  std::vector<double> mapped_azimuths_;  // the column azimuths column_bin_ was made for
};

}  // namespace ringtrack::core
