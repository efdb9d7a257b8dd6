#pragma once
/// A sequence folder with ground truth (objects.csv) kept in memory, motion-compensated once, so
/// that the pipeline can be run on it many times (parameter tuning on recorded data).

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/eval/tracking_eval.hpp"

namespace ringtrack::experiment {

/// Every scan of a sequence folder (`ringtrack simulate` or `convert` output plus objects.csv)
/// with the pose to process it at, deskewed exactly as `ringtrack run` does (a sequence with
/// poses: this and the next scan's pose), and its ground truth.
class RecordedSequence {
 public:
  /// Reads the folder; throws core::InputError naming it when it has no scans or no
  /// objects.csv (tuning needs ground truth), or when a file is malformed.
  explicit RecordedSequence(const std::filesystem::path& folder);

  /// The folder's name.
  [[nodiscard]] const std::string& name() const { return name_; }
  /// The sensor the scans were taken with.
  [[nodiscard]] const core::SensorModel& model() const { return model_; }
  /// Whether the sensor moves (its poses differ).
  [[nodiscard]] bool moving() const { return moving_; }
  /// Number of scans.
  [[nodiscard]] std::size_t size() const { return scans_.size(); }
  /// Scan k, motion-compensated when the sensor moves.
  [[nodiscard]] const core::OrganizedScan& scan(std::size_t k) const { return scans_.at(k); }
  /// The pose to give the pipeline with scan k.
  [[nodiscard]] const core::Pose& pose(std::size_t k) const { return poses_.at(k); }
  /// The ground truth rows (objects.csv), scan numbers as in the sequence.
  [[nodiscard]] const std::vector<eval::GroundTruthObject>& ground_truth() const {
    return ground_truth_;
  }
  /// Bytes held by the scans (approximate).
  [[nodiscard]] std::size_t memory_bytes() const;

 private:
  std::string name_;
  core::SensorModel model_;
  bool moving_{false};
  std::vector<core::OrganizedScan> scans_;
  std::vector<core::Pose> poses_;
  std::vector<eval::GroundTruthObject> ground_truth_;
};

}  // namespace ringtrack::experiment
