#pragma once
/// Sensor trajectories: TUM and KITTI pose files, and interpolation to a stamp.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/pose.hpp"

namespace ringtrack::io {

/// Poses of the sensor in the world frame with strictly increasing stamps, interpolated between
/// samples (linear translation, slerp rotation).
class Trajectory {
 public:
  Trajectory() = default;
  /// Takes poses in strictly increasing stamp order with finite values; throws core::InputError
  /// naming `source` and the offending index otherwise. Rotations are normalized.
  explicit Trajectory(std::vector<core::Pose> poses, std::string source = "trajectory");

  /// The samples, in stamp order.
  [[nodiscard]] const std::vector<core::Pose>& poses() const { return poses_; }
  /// True when there are no samples.
  [[nodiscard]] bool empty() const { return poses_.empty(); }
  /// Number of samples.
  [[nodiscard]] std::size_t size() const { return poses_.size(); }
  /// Stamp of the first sample (requires !empty()).
  [[nodiscard]] std::int64_t start_ns() const { return poses_.front().stamp_ns; }
  /// Stamp of the last sample (requires !empty()).
  [[nodiscard]] std::int64_t end_ns() const { return poses_.back().stamp_ns; }
  /// True when start_ns() <= stamp_ns <= end_ns().
  [[nodiscard]] bool covers(std::int64_t stamp_ns) const;
  /// The pose at stamp_ns, interpolated between the neighbouring samples; throws
  /// core::InputError naming the stamp and the covered range when it lies outside.
  [[nodiscard]] core::Pose at(std::int64_t stamp_ns) const;

 private:
  std::vector<core::Pose> poses_;
  std::string source_{"trajectory"};
};

/// Reads a TUM file: "t x y z qx qy qz qw" per line (t in seconds; spaces, tabs or commas;
/// '#' comments and blank lines ignored). Throws core::InputError naming file:line on malformed
/// lines, NaN or infinite values, non-unit quaternions (|q| outside 1 +- 0.01) and stamps that
/// do not strictly increase.
Trajectory read_tum(const std::filesystem::path& path);

/// Reads a KITTI pose file (12 numbers per line: the row-major 3x4 matrix [R | t]) without
/// stamps: every pose has stamp 0. Throws core::InputError naming file:line on malformed lines,
/// NaNs and matrices whose R is not a rotation (|R^T R - I| > 1e-3 or det R < 0).
std::vector<core::Pose> read_kitti_poses(const std::filesystem::path& path);

/// Reads a KITTI pose file and gives line i the stamp stamps_ns[i] (KITTI files carry no time:
/// the stamps come from times.txt, a stamps file or the scans); the counts must match.
Trajectory read_kitti(const std::filesystem::path& path, std::span<const std::int64_t> stamps_ns);

/// One TUM line (without the newline): seconds with 9 decimals, metres with 6, quaternion with 9.
std::string format_tum_line(const core::Pose& pose);

/// Writes poses as a TUM file; I/O failures throw core::Error and remove the partial file.
void write_tum(const std::filesystem::path& path, std::span<const core::Pose> poses);

}  // namespace ringtrack::io
