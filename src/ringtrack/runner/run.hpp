#pragma once
/// A whole run, as `ringtrack run` does it: each scan of a RunInput through pipeline::Pipeline,
/// into the run's outputs (tracks.csv, timing.csv, poses.txt, the static map, config.yaml and,
/// when asked, odometry.csv, filtered/NNNNNN.pcd, raw_map.ply, an MCAP file), with the figures
/// of its summary. Printing, the run's status file and the signals stay with the caller.

#include <Eigen/Core>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/io/mcap_writer.hpp"
#include "ringtrack/io/run_status.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/runner/run_input.hpp"
#include "ringtrack/tracking/tracker.hpp"

namespace ringtrack::runner {

/// What a run writes and how it is told to stop (ringtrack run's options past its input).
struct RunOptions {
  /// The output folder (must exist): tracks.csv, timing.csv, poses.txt, static_map.ply and .pcd,
  /// config.yaml, and the files below when asked for.
  std::filesystem::path out;
  /// The odometry estimates the poses (call RunInput::use_odometry first); writes odometry.csv.
  bool odometry{false};
  /// A TUM trajectory whose pose at the first scan's stamp places the odometry's world frame.
  std::string odometry_start;
  bool filtered_scans{false};  ///< each scan without its dynamic points as filtered/NNNNNN.pcd
  /// The accumulated raw points as raw_map.ply beside the static map (the paper's Fig. 7); never
  /// when mapping.map_radius_m bounds the map (the raw map would have no bound).
  bool raw_map{false};
  std::string mcap;                      ///< an MCAP file for Foxglove, "" for none
  std::string mcap_compression{"zstd"};  ///< zstd | lz4 | none
  std::uint32_t mcap_map_every{0};       ///< the static map every N scans too (0: at the end)
  /// The MCAP's "ringtrack" metadata record (what wrote it, from what); config.yaml follows it.
  io::McapStringMap mcap_metadata;
  /// Checked before each scan: once true, the run stops there and its outputs are completed.
  const std::atomic<bool>* stop{nullptr};
  /// Called for a scan the pipeline skipped (its stamp did not come after the scan before).
  std::function<void(std::uint64_t index, const std::string& reason)> on_skipped;
  /// Called after each processed scan with its tracks.csv rows (e.g. to show progress).
  std::function<void(std::size_t index, const pipeline::FrameResult& result,
                     const std::vector<io::TrackRow>& rows)>
      on_scan;
};

/// The figures of a finished run (`ringtrack run` prints them).
struct RunSummary {
  std::size_t scans{0};                     ///< processed (in the outputs)
  std::vector<double> total_ms;             ///< the pipeline's time per processed scan
  std::size_t tracks{0};                    ///< distinct reported track ids
  std::size_t dynamic_tracks{0};            ///< of which ever dynamic
  std::size_t map_voxels{0};                ///< in static_map.ply, spilled ones included
  std::uint64_t spilled_voxels{0};          ///< written out during the run (bounded map)
  bool bounded_map{false};                  ///< mapping.map_radius_m > 0
  bool raw_map{false};                      ///< raw_map.ply was written
  Eigen::Vector3d origin{0.0, 0.0, 0.0};    ///< the pipeline's local frame in the poses' frame
  std::uint64_t too_high{0};                ///< clusters the altitude test turned away
  std::uint64_t detections{0};              ///< detections over all scans
  std::size_t dropped_points{0};            ///< outside the static map's voxel index
  std::size_t odometry_scans{0};            ///< scans the odometry registered (odometry.csv rows)
  std::size_t odometry_degenerate{0};       ///< of which flagged unreliable
  std::size_t odometry_weak{0};             ///< of which flagged weak (may slide)
  std::vector<double> odometry_ms;          ///< the odometry's time per scan
  std::optional<io::McapWriterStats> mcap;  ///< when an MCAP file was written
  bool stopped{false};                      ///< RunOptions::stop ended the run early
};

/// One tracks.csv row: a hypothesis after the update of scan `scan`, moved from the pipeline's
/// local frame to the world frame by origin (pipeline::Pipeline::origin()).
io::TrackRow track_row(std::uint64_t scan, std::int64_t stamp_ns, const tracking::Hypothesis& h,
                       const Eigen::Vector3d& origin);

/// Whether the odometry estimates the poses for `mode` (on, off, auto): auto is on for a
/// recording without a poses file; a folder without poses keeps a static sensor. Throws
/// core::InputError for on with a poses file.
bool use_odometry(const std::string& mode, bool folder, const std::string& poses);

/// Prepares `input` and `config` for a run as `ringtrack run` does and returns whether the
/// odometry estimates the poses (use_odometry with the input's poses file): the odometry's own
/// motion compensation off under `no_deskew`, and the sensor height a sequence folder states
/// (simulated ones do) in config.detection.sensor_height_m unless `keep_sensor_height` (the
/// user's configuration gives it).
bool prepare_run(RunInput& input, core::Config& config, const std::string& odometry_mode,
                 const std::string& poses, bool no_deskew, bool keep_sensor_height);

/// A run in progress: step() processes the next scan, finish() completes the outputs.
class Run {
 public:
  /// Opens the outputs in options.out and writes config.yaml; `status` (optional) is kept up to
  /// date (scans read, processed, skipped, failed, origin) for the caller's run.json.
  Run(RunInput& input, const core::Config& config, RunOptions options,
      io::RunStatus* status = nullptr);
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;
  ~Run();

  /// Reads and processes the next scan; false at the end of the input or on a stop request.
  /// Throws what reading or processing throws (the status then counts the failed scan).
  bool step();
  /// Scans processed so far.
  [[nodiscard]] std::size_t scans() const;
  /// Completes every output (the filter's last decisions, the maps, poses.txt, the MCAP's end)
  /// and returns the figures; throws core::InputError "<input>: no scans found" for none. Call
  /// once, after step() returned false.
  RunSummary finish();

 private:
  struct State;
  std::unique_ptr<State> state_;
};

/// Runs every scan of `input` (Run::step until the end or a stop), then Run::finish.
RunSummary run(RunInput& input, const core::Config& config, const RunOptions& options,
               io::RunStatus* status = nullptr);

}  // namespace ringtrack::runner
