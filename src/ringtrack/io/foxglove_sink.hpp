#pragma once
/// The pipeline's results as an MCAP file for Foxglove: each scan as a foxglove.PointCloud with
/// per-point segment, detection and track labels, detections and tracks as foxglove.SceneUpdate,
/// the sensor pose as foxglove.FrameTransform, the static map as a point cloud, run metadata as
/// Metadata records. Protobuf encoding. See docs/visualisation.md.

#include <cstdint>
#include <deque>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/io/mcap_writer.hpp"
#include "ringtrack/io/protobuf_writer.hpp"
#include "ringtrack/mapping/static_map.hpp"
#include "ringtrack/pipeline/pipeline.hpp"

namespace ringtrack::io {

/// Topic of the scans (foxglove.PointCloud, sensor frame).
inline constexpr const char* kMcapScanTopic = "/ringtrack/scan";
/// Topic of the reported tracks (foxglove.SceneUpdate, world frame).
inline constexpr const char* kMcapTracksTopic = "/ringtrack/tracks";
/// Topic of each scan's detections (foxglove.SceneUpdate, world frame).
inline constexpr const char* kMcapDetectionsTopic = "/ringtrack/detections";
/// Topic of the sensor pose (foxglove.FrameTransform world -> sensor).
inline constexpr const char* kMcapTransformTopic = "/tf";
/// Topic of the static map (foxglove.PointCloud, world frame).
inline constexpr const char* kMcapMapTopic = "/ringtrack/static_map";

/// Bytes per point of the scan clouds: x y z intensity (float32), track_id (uint32), detection
/// (uint16), segment and removed (uint8).
inline constexpr std::uint32_t kMcapScanPointStride = 24;
/// Bytes per point of the map cloud: x y z intensity (float32).
inline constexpr std::uint32_t kMcapMapPointStride = 16;

/// What the sink writes and how.
struct FoxgloveSinkOptions {
  McapWriterOptions mcap;              ///< container options (compression, chunk size, thread)
  std::string world_frame{"world"};    ///< frame of poses, tracks and map
  std::string sensor_frame{"sensor"};  ///< frame of the scans
  std::uint32_t map_every_scans{0};    ///< also write the static map every N scans (0: at the end)
  std::size_t trajectory_points{50};   ///< recent positions in each track's trajectory line
};

/// Counts of what was written.
struct FoxgloveSinkStats {
  std::uint64_t scans{0};           ///< scan clouds
  std::uint64_t points{0};          ///< points in them
  std::uint64_t track_entities{0};  ///< track entities over all scene updates
  std::uint64_t maps{0};            ///< static map clouds
};

/// Writes one MCAP file from the pipeline's per-scan results.
class FoxgloveSink {
 public:
  /// Creates the file and declares the schemas and channels; throws core::Error naming it.
  FoxgloveSink(const std::filesystem::path& path, FoxgloveSinkOptions options = {});

  /// Writes a Metadata record (e.g. the effective config, the version, the input).
  void write_metadata(const std::string& name, const McapStringMap& entries);
  /// Writes one processed scan: its cloud (valid cells, sensor frame) labelled from `result`,
  /// its pose, its detections and the reported tracks; and the map when one is due.
  void write_frame(const core::OrganizedScan& scan, const core::Pose& pose,
                   const pipeline::FrameResult& result, const mapping::StaticMap& map);
  /// Writes one scan the pipeline processed at `world_pose` (the poses' frame) as `run --mcap`
  /// and the Python package do: in the pipeline's local frame (result.origin subtracted, so the
  /// float32 clouds keep their precision), with the origin as the metadata record "frame"
  /// (origin_m) before the first scan, and the pipeline's map for the periodic map.
  void write_pipeline_frame(const core::OrganizedScan& scan, const core::Pose& world_pose,
                            const pipeline::FrameResult& result, const mapping::StaticMap& map);
  /// Writes the final static map at `stamp_ns` and closes the file (complete only then).
  void finish(const mapping::StaticMap& map, std::int64_t stamp_ns);
  /// Waits until the writer's worker thread has written what it was handed (benchmarks).
  void wait_idle() { writer_.wait_idle(); }

  /// Counts so far.
  [[nodiscard]] const FoxgloveSinkStats& stats() const { return stats_; }
  /// The container's counts.
  [[nodiscard]] const McapWriterStats& mcap_stats() const { return writer_.stats(); }

 private:
  void label_cells(const pipeline::FrameResult& result, std::size_t cells);
  void clear_labels();
  void write_cloud(const core::OrganizedScan& scan, const pipeline::FrameResult& result);
  void write_transform(const core::Pose& pose);
  void write_tracks(const pipeline::FrameResult& result);
  void write_detections(const pipeline::FrameResult& result);
  void write_map(const mapping::StaticMap& map, std::int64_t stamp_ns);

  FoxgloveSinkOptions options_;
  McapWriter writer_;
  std::uint16_t scan_channel_{0}, tracks_channel_{0}, detections_channel_{0};
  std::uint16_t transform_channel_{0}, map_channel_{0};
  ProtoWriter message_;                    // reused for every message
  std::vector<std::uint32_t> cell_track_;  // per cell of the current scan
  std::vector<std::uint16_t> cell_detection_;
  std::vector<std::uint8_t> cell_removed_;
  std::vector<std::uint32_t> labelled_;  // cells whose labels are set (reset after each cloud)
  std::unordered_map<std::uint64_t, std::deque<Eigen::Vector3d>> trajectories_;
  std::int64_t stamp_ns_{0};
  FoxgloveSinkStats stats_;
};

}  // namespace ringtrack::io
