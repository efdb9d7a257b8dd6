#pragma once
/// A point cloud kept on disk while it grows: the static map's voxels that left memory
/// (mapping.map_radius_m), written out with the rest of the map at the end of a run.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>

#include "ringtrack/io/output_file.hpp"

namespace ringtrack::io {

/// Appends points (x y z intensity, 16 bytes each) to a scratch file and, at the end, writes them
/// followed by the points still in memory as one PLY (binary little endian) and optionally one
/// PCD (binary) file, copying the scratch file in blocks: memory stays independent of the
/// number of points. The scratch file is deleted by write() and by the destructor.
class PointSpill {
 public:
  /// Creates (truncates) the scratch file; throws core::Error when it cannot.
  explicit PointSpill(std::filesystem::path scratch);
  PointSpill(const PointSpill&) = delete;
  PointSpill& operator=(const PointSpill&) = delete;
  ~PointSpill();

  /// Appends one point.
  void append(const Eigen::Vector3f& position, float intensity);
  /// Points appended so far.
  [[nodiscard]] std::uint64_t size() const { return size_; }

  /// Writes the spilled points, then points[i] with intensities[i], to ply (and to pcd unless it
  /// is empty), each with comment as a header comment; then deletes the scratch file. I/O
  /// failures throw core::Error naming the file, and leave no partial output behind.
  void write(const std::filesystem::path& ply, const std::filesystem::path& pcd,
             std::span<const Eigen::Vector3f> points, std::span<const float> intensities,
             std::string_view comment);

 private:
  void copy_into(OutputFile& out, std::span<const Eigen::Vector3f> points,
                 std::span<const float> intensities) const;

  std::filesystem::path scratch_;
  OutputFile file_;
  std::uint64_t size_{0};
};

}  // namespace ringtrack::io
