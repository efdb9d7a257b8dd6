// `ringtrack run INPUT --out DIR`: the whole pipeline over a recorded sequence, with its outputs.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <utility>

#include "commands.hpp"
#include "output_rows.hpp"
#include "plots.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/eval/statistics.hpp"
#include "ringtrack/io/bad_scans.hpp"
#include "ringtrack/io/csv_writers.hpp"
#include "ringtrack/io/foxglove_sink.hpp"
#include "ringtrack/io/output_file.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/ply.hpp"
#include "ringtrack/io/point_spill.hpp"
#include "ringtrack/io/poses.hpp"
#include "ringtrack/io/text.hpp"
#include "ringtrack/mapping/static_map.hpp"
#include "ringtrack/odometry/odometry.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/runner/run_input.hpp"
#include "ringtrack/version.hpp"
#include "stop_signals.hpp"

namespace ringtrack::cli {
namespace {

namespace fs = std::filesystem;

struct RunOptions {
  std::string input;
  std::string out;
  InputOptions source;  // --format, --topic, the decoder's options (shared with convert)
  std::string on_bad_scan{"skip"};
  std::string poses;
  std::string poses_format{"tum"};
  std::string mcap;
  std::string mcap_compression{"zstd"};
  std::uint32_t mcap_map_every{0};
  bool filtered_scans{false};
  bool no_deskew{false};
  std::string odometry{"auto"};
  std::string odometry_start;
  bool quiet{false};
  bool no_plots{false};
  ConfigOptions config;
};

io::TimingRow timing_row(std::uint64_t scan, std::int64_t stamp_ns, const pipeline::StageTimes& t,
                         bool odometry) {
  io::TimingRow row{scan, stamp_ns, {}, t.total_ms};
  row.stages.reserve(5);
  // Only runs that estimate their poses have the column: other runs' files stay as they were.
  if (odometry) row.stages.push_back({"odometry", t.odometry_ms});
  row.stages.push_back({"segmentation", t.segmentation_ms});
  row.stages.push_back({"detection", t.detection_ms});
  row.stages.push_back({"tracking", t.tracking_ms});
  row.stages.push_back({"mapping", t.mapping_ms});
  return row;
}

// Whether the odometry estimates the poses: --odometry on, or auto for a recording (pcap, bag,
// stream) without --poses. Folders without poses keep the documented static sensor under auto.
bool use_odometry(const std::string& mode, bool folder, const std::string& poses) {
  if (mode == "off") return false;
  if (!poses.empty()) {
    if (mode == "on") {
      throw core::InputError("--odometry on and --poses exclude each other: give one pose source");
    }
    return false;
  }
  if (mode == "on") return true;
  return !folder;
}

// Per-scan account of the odometry (odometry.csv) and its totals for the summary.
class OdometryLog {
 public:
  explicit OdometryLog(const fs::path& path) : file_(path) {
    file_.write(
        "scan,stamp,x,y,z,qx,qy,qz,qw,registered,degenerate,weakest_share,iterations,"
        "source_points,correspondences,excluded_points,threshold_m,odometry_ms\n");
  }
  void write(std::size_t index, const odometry::OdometryResult& r, double ms) {
    char line[512];
    const auto& t = r.pose.translation;
    const auto& q = r.pose.rotation;
    std::snprintf(line, sizeof line,
                  "%zu,%s,%.6f,%.6f,%.6f,%.9f,%.9f,%.9f,%.9f,%d,%d,%.5f,%d,%zu,%zu,%zu,%.4f,%.4f\n",
                  index, io::format_stamp(r.pose.stamp_ns).c_str(), t.x(), t.y(), t.z(), q.x(),
                  q.y(), q.z(), q.w(), r.registered ? 1 : 0, r.degenerate ? 1 : 0, r.weakest_share,
                  r.iterations, r.source_points, r.correspondences, r.excluded_points,
                  r.threshold_m, ms);
    file_.write(std::string_view(line));
    ++scans_;
    if (r.degenerate) ++degenerate_;
    times_ms_.push_back(ms);
  }
  void close() { file_.close(); }
  [[nodiscard]] std::size_t scans() const { return scans_; }
  [[nodiscard]] std::size_t degenerate() const { return degenerate_; }
  [[nodiscard]] const std::vector<double>& times_ms() const { return times_ms_; }

 private:
  io::OutputFile file_;
  std::size_t scans_{0}, degenerate_{0};
  std::vector<double> times_ms_;
};

// One status line on stderr: scans done, rate and, when the total is known, the time left.
void print_progress(std::size_t done, std::size_t total,
                    std::chrono::steady_clock::time_point start) {
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double rate = s > 0 ? static_cast<double>(done) / s : 0.0;
  if (total > 0) {
    const double eta = rate > 0 ? static_cast<double>(total - done) / rate : 0.0;
    std::fprintf(stderr, "\rscan %zu / %zu  %.0f scans/s  ETA %.0f s   ", done, total, rate, eta);
  } else {
    std::fprintf(stderr, "\rscan %zu  %.0f scans/s   ", done, rate);
  }
}

// Writes each scan without its dynamic-object points once the dynamic-object filter has made its
// final decision on it, i.e. when the scan leaves the filter's log (removals are retroactive, so
// a scan written earlier could still hold points of an object that turns dynamic later).
class FilteredScanWriter {
 public:
  explicit FilteredScanWriter(fs::path folder) : folder_(std::move(folder)) {}

  /// Keeps the scan as the pipeline processed it (sensor frame at its stamp, motion-compensated
  /// when deskewed: the points the map was built from) until the filter releases it.
  void hold(std::size_t index, const core::OrganizedScan& scan) {
    pending_.push_back({index, scan, next_sequence_++});
  }

  /// Writes the scans the filter released in its last call.
  void write_released(const mapping::DynamicObjectFilter& filter) {
    for (const auto& logged : filter.released()) {
      while (!pending_.empty() && pending_.front().sequence < logged.sequence) pending_.pop_front();
      if (pending_.empty() || pending_.front().sequence != logged.sequence) continue;
      auto& held = pending_.front();
      for (std::size_t k = 0; k < logged.cells.size(); ++k) {
        if (logged.removed[k] == 0) continue;
        const auto cell = logged.cells[k];
        held.scan.set_invalid(held.scan.ring_of(cell), held.scan.column_of(cell),
                              core::ReturnStatus::kNoReturn);
      }
      char name[32];
      std::snprintf(name, sizeof name, "%06zu.pcd", held.index);
      io::write_pcd(folder_ / name, held.scan, {});
      pending_.pop_front();
    }
  }

 private:
  struct Held {
    std::size_t index;
    core::OrganizedScan scan;
    std::uint64_t sequence;  // the filter's number for it: the order of processing
  };
  fs::path folder_;
  std::deque<Held> pending_;
  std::uint64_t next_sequence_{0};
};

// The run's input (runner::RunInput) from the command line: the input options, --poses,
// --no-deskew and --on-bad-scan; Ctrl-C stops a live input.
runner::RunInputOptions run_input_options(const RunOptions& o) {
  runner::RunInputOptions options;
  options.source = o.source.source_options();
  options.source.velodyne.interrupt = &StopSignals::stop_flag();
  options.poses = o.poses;
  options.poses_format = o.poses_format;
  options.no_deskew = o.no_deskew;
  options.on_bad_scan = io::parse_bad_scan_policy(o.on_bad_scan);
  return options;
}

// The MCAP sink (--mcap) with the run's metadata: what wrote it, from what, with which config.
std::unique_ptr<io::FoxgloveSink> open_mcap(const RunOptions& o, const core::Config& config) {
  io::FoxgloveSinkOptions options;
  options.mcap.compression = io::parse_mcap_compression(o.mcap_compression);
  options.mcap.library = std::string("ringtrack ") + kVersion;
  options.map_every_scans = o.mcap_map_every;
  auto sink = std::make_unique<io::FoxgloveSink>(o.mcap, options);
  sink->write_metadata("ringtrack", {{"version", kVersion},
                                     {"command", "run"},
                                     {"input", o.input},
                                     {"format", o.source.format},
                                     {"poses", o.poses},
                                     {"deskew", o.no_deskew ? "off" : "auto"}});
  sink->write_metadata("config", {{"config.yaml", core::dump_config(config)}});
  return sink;
}

// The maps' header line on their frame: float32 cannot hold UTM-scale coordinates to the
// centimetre, so the maps stay in the pipeline's local frame and say where it lies.
// Writes a voxel map's points as binary PLY (x y z intensity), and as PCD beside it when
// with_pcd, in the local frame with origin (origin_comment), after the voxels spilled while the
// run went on (mapping.map_radius_m; then the PCD is binary, streamed, not compressed);
// returns how many.
std::size_t write_map(const fs::path& path, const mapping::StaticMap& map, bool with_pcd,
                      const Eigen::Vector3d& origin, io::PointSpill* spill = nullptr) {
  const auto points = map.points();
  std::vector<Eigen::Vector3f> xyz;
  std::vector<float> intensity;
  xyz.reserve(points.size());
  intensity.reserve(points.size());
  for (const auto& p : points) {
    xyz.push_back(p.position);
    intensity.push_back(p.intensity);
  }
  const std::string comment = io::origin_comment(origin);
  if (spill != nullptr && spill->size() > 0) {
    const auto spilled = spill->size();
    spill->write(path, with_pcd ? fs::path(path).replace_extension(".pcd") : fs::path(), xyz,
                 intensity, comment);
    return points.size() + spilled;
  }
  io::write_ply(path, xyz, intensity, io::PlyEncoding::kBinaryLittleEndian, comment);
  if (with_pcd) {
    io::write_pcd_points(fs::path(path).replace_extension(".pcd"), xyz, intensity,
                         io::PcdEncoding::kBinaryCompressed, comment);
  }
  return points.size();
}

// Every point of the scans the dynamic-object filter released, removed or not: the raw side of
// the Fig. 7 pictures, voxelized as the static map is so that the two compare.
void accumulate_raw(const mapping::DynamicObjectFilter& filter, mapping::StaticMap& raw) {
  for (const auto& scan : filter.released()) raw.insert(scan.points, scan.intensities, {});
}

// The pose of the first scan in the world the odometry should estimate in: a TUM trajectory
// interpolated at its stamp (e.g. a simulated sequence's ground truth, to compare in its frame).
core::Pose odometry_start(const std::string& path, std::int64_t stamp_ns) {
  const io::Trajectory trajectory = io::read_tum(path);
  if (!trajectory.covers(stamp_ns)) {
    throw core::InputError("--odometry-start " + path + ": no pose at the first scan's stamp " +
                           io::format_stamp(stamp_ns) + " s");
  }
  return trajectory.at(stamp_ns);
}

// The odometry's lines of the run summary, and a warning when some poses are unreliable.
void print_odometry_summary(const OdometryLog& log) {
  std::printf(
      "odometry         %zu of %zu scans flagged unreliable (too little geometry or not "
      "registered); ms per scan median %.3f, p95 %.3f\n",
      log.degenerate(), log.scans(), eval::quantile(log.times_ms(), 0.5),
      eval::quantile(log.times_ms(), 0.95));
  if (log.degenerate() > 0) {
    std::fprintf(stderr,
                 "ringtrack: warning: odometry: %zu of %zu scans had too little geometry to fix "
                 "the pose (e.g. ground only): the estimated poses are unreliable there "
                 "(odometry.csv, column degenerate)\n",
                 log.degenerate(), log.scans());
  }
}

// Warnings about skipped scans on stderr: the first few, then one line saying the rest are only
// counted (run.json lists them), so a recording full of bad scans does not flood the terminal.
class SkipWarnings {
 public:
  explicit SkipWarnings(std::string input) : input_(std::move(input)) {}
  void warn(std::uint64_t index, const std::string& reason) {
    ++count_;
    if (count_ <= kShown) {
      std::fprintf(stderr, "ringtrack: warning: %s: scan %llu: %s\n", input_.c_str(),
                   static_cast<unsigned long long>(index), reason.c_str());
    } else if (count_ == kShown + 1) {
      std::fprintf(stderr,
                   "ringtrack: warning: %s: more scans skipped; they are counted in the summary "
                   "and listed in run.json\n",
                   input_.c_str());
    }
  }

 private:
  static constexpr std::uint64_t kShown = 20;
  std::string input_;
  std::uint64_t count_{0};
};

// The "scans" line's note on skipped scans, "" when none.
std::string skipped_note(const io::RunStatus& s) {
  const std::uint64_t skipped = s.scans_skipped_unreadable + s.scans_skipped_stamp;
  if (skipped == 0) return "";
  std::string note = " (" + std::to_string(skipped) + " more skipped: ";
  if (s.scans_skipped_unreadable > 0 && s.scans_skipped_stamp > 0) {
    note += std::to_string(s.scans_skipped_unreadable) + " unreadable, " +
            std::to_string(s.scans_skipped_stamp) + " with a stamp not after the scan before";
  } else if (s.scans_skipped_unreadable > 0) {
    note += "unreadable";
  } else {
    note += "stamp not after the scan before";
  }
  return note + ")";
}

// A warning when the altitude test rejected clusters and nothing was detected: the heights of
// the poses' frame may not be what detection.sensor_height_m says (docs/detection.md).
void warn_about_heights(const core::Config& config, std::uint64_t too_high,
                        std::uint64_t detections) {
  if (too_high == 0 || detections > 0) return;
  std::fprintf(stderr,
               "ringtrack: warning: no detections, and %llu clusters had their lowest point "
               "more than detection.max_altitude_m = %g m above the ground, which is taken as "
               "detection.sensor_height_m = %g m below the first scan's sensor: check "
               "sensor_height_m (docs/detection.md)\n",
               static_cast<unsigned long long>(too_high), config.detection.max_altitude_m,
               config.detection.sensor_height_m);
}

// The run proper, once the output folder and its run.json exist; keeps `status` up to date.
void run_into(const RunOptions& o, core::Config& config, bool odometry, io::RunStatus& status,
              SkipWarnings& warnings, runner::RunInput& input) {
  const fs::path out = o.out;
  std::error_code ec;
  if (o.filtered_scans) fs::create_directories(out / "filtered", ec);
  {
    io::OutputFile config_file(out / "config.yaml");
    config_file.write(core::dump_config(config));
    config_file.close();
  }

  // Built at the first scan: a recording's sensor model is known once it was decoded.
  std::unique_ptr<pipeline::Pipeline> pipeline;
  std::unique_ptr<FilteredScanWriter> filtered;
  std::unique_ptr<io::FoxgloveSink> mcap;
  if (!o.mcap.empty()) mcap = open_mcap(o, config);
  if (o.filtered_scans) filtered = std::make_unique<FilteredScanWriter>(out / "filtered");
  io::TracksCsvWriter tracks(out / "tracks.csv");
  io::TimingCsvWriter timing(out / "timing.csv");
  std::unique_ptr<OdometryLog> odometry_log;
  if (odometry) odometry_log = std::make_unique<OdometryLog>(out / "odometry.csv");
  std::vector<double> total_ms;
  std::set<std::uint64_t> track_ids, dynamic_ids;
  const bool progress = !o.quiet && isatty(STDERR_FILENO);
  const auto start = std::chrono::steady_clock::now();
  std::size_t index = 0;
  core::OrganizedScan scan;
  core::Pose pose;
  std::vector<io::TrackRow> rows;
  std::vector<core::Pose> poses;
  // The raw map for the pictures has no bound: with mapping.map_radius_m there is none.
  const bool bounded_map = config.mapping.map_radius_m > 0.0;
  std::optional<mapping::StaticMap> raw_map;
  if (!o.no_plots && !bounded_map) raw_map.emplace(config.mapping.voxel_size_m);
  std::unique_ptr<io::PointSpill> spill;
  if (bounded_map) spill = std::make_unique<io::PointSpill>(out / "static_map.spill");
  // Clusters the altitude test turned away, and detections: "no tracks" is then explained.
  std::uint64_t too_high = 0, detections = 0;
  for (;;) {
    // Ctrl-C or SIGTERM: stop after the scan at hand; what follows closes every output.
    if (StopSignals::requested()) break;
    try {
      if (!input.next(index, scan, pose)) break;
      status.scans_read = input.read();
      if (!pipeline) {
        pipeline = std::make_unique<pipeline::Pipeline>(config, input.sensor_model());
        if (odometry && !o.odometry_start.empty()) {
          pipeline->set_odometry_start(odometry_start(o.odometry_start, scan.stamp_ns));
        }
      }
      const auto& result =
          odometry ? pipeline->process_with_odometry(scan) : pipeline->process(scan, pose);
      if (result.skipped) {  // counted by the pipeline; the run goes on
        ++status.scans_skipped_stamp;
        status.add_skipped(index, result.skip_reason);
        warnings.warn(index, result.skip_reason);
        continue;
      }
      if (odometry) {
        pose = result.pose;
        odometry_log->write(index, pipeline->odometry_result(), result.times.odometry_ms);
      }
      poses.push_back(pose);
      if (raw_map) accumulate_raw(pipeline->dynamic_filter(), *raw_map);
      if (spill) {
        for (const auto& v : pipeline->dynamic_filter().evicted()) {
          spill->append(v.position, v.intensity);
        }
      }
      rows.clear();
      for (const auto& h : result.hypotheses) {
        if (!h.reported) continue;  // unconfirmed or lost (docs/tracking.md, "What is reported")
        rows.push_back(track_row(index, scan.stamp_ns, h, result.origin));
        track_ids.insert(h.id);
        if (h.ever_dynamic) dynamic_ids.insert(h.id);
      }
      tracks.write(rows);
      timing.write(timing_row(index, scan.stamp_ns, result.times, odometry));
      total_ms.push_back(result.times.total_ms);
      too_high += pipeline->detector_stats().too_high;
      detections += pipeline->detector_stats().detections;
      ++status.scans_processed;
      const Eigen::Vector3d& origin = result.origin;
      status.origin_m = {origin.x(), origin.y(), origin.z()};
      if (mcap) mcap->write_pipeline_frame(scan, pose, result, pipeline->static_map());
      if (filtered) {
        filtered->hold(index, scan);
        filtered->write_released(pipeline->dynamic_filter());
      }
      if (progress) print_progress(index + 1, input.size(), start);
    } catch (...) {
      // The scan that stopped the run: unreadable (--on-bad-scan stop) or failing later.
      status.scans_read = input.read();
      status.scans_failed = 1;
      throw;
    }
  }
  status.scans_read = input.read();
  status.scans_skipped_unreadable = input.unreadable();
  if (total_ms.empty()) throw core::InputError(o.input + ": no scans found");
  if (const auto warning = input.warning(); !warning.empty()) {
    std::fprintf(stderr, "ringtrack: warning: %s\n", warning.c_str());
  }
  if (progress) std::fprintf(stderr, "\n");
  pipeline->finish();
  if (filtered) filtered->write_released(pipeline->dynamic_filter());
  if (raw_map) accumulate_raw(pipeline->dynamic_filter(), *raw_map);
  tracks.close();
  timing.close();
  if (odometry_log) odometry_log->close();

  const Eigen::Vector3d origin = pipeline->origin();
  const std::uint64_t spilled = spill ? spill->size() : 0;
  const std::size_t map_voxels =
      write_map(out / "static_map.ply", pipeline->static_map(), true, origin, spill.get());
  io::write_tum(out / "poses.txt", poses);
  if (mcap) mcap->finish(pipeline->static_map(), scan.stamp_ns);
  bool plotted = false;
  if (raw_map) {
    write_map(out / "raw_map.ply", *raw_map, false, origin);
    plotted = run_plot_script("plot_maps.py", {out, out / "maps.png"});
  }

  const std::string signal = StopSignals::signal_name();
  if (const auto summary = input.summary(); !summary.empty())
    std::printf("input            %s\n", summary.c_str());
  std::printf(
      "scans            %zu%s%s\n", total_ms.size(), skipped_note(status).c_str(),
      signal.empty()
          ? ""
          : (" (interrupted by " + signal + ": the outputs cover these scans only)").c_str());
  std::printf("poses            %s\n", input.pose_summary(o.odometry).c_str());
  if (!origin.isZero()) {
    std::printf(
        "frame            tracks.csv and poses.txt in the poses' frame; maps%s in the local frame "
        "at origin (%.3f, %.3f, %.3f) m (docs/inputs.md, \"Frames\")\n",
        mcap ? " and MCAP" : "", origin.x(), origin.y(), origin.z());
  }
  if (odometry_log) print_odometry_summary(*odometry_log);
  std::printf("deskew           %s\n", input.deskew_summary().c_str());
  std::printf("tracks           %zu (%zu ever dynamic)\n", track_ids.size(), dynamic_ids.size());
  if (bounded_map) {
    std::printf(
        "static map       %zu voxels (%llu written out during the run, beyond "
        "mapping.map_radius_m %g m of the sensor; no raw_map.ply or maps.png)\n",
        map_voxels, static_cast<unsigned long long>(spilled), config.mapping.map_radius_m);
  } else {
    std::printf("static map       %zu voxels\n", map_voxels);
  }
  warn_about_heights(config, too_high, detections);
  if (const std::size_t dropped = pipeline->static_map().dropped_points(); dropped > 0) {
    std::fprintf(stderr,
                 "ringtrack: warning: static map: %zu points lay outside its voxel index "
                 "(+-2^20 voxels of mapping.voxel_size_m about the local origin) and are not in "
                 "it\n",
                 dropped);
  }
  std::printf("ms per scan      median %.3f, p95 %.3f, max %.3f\n", eval::quantile(total_ms, 0.5),
              eval::quantile(total_ms, 0.95), *std::max_element(total_ms.begin(), total_ms.end()));
  std::printf(
      "outputs          "
      "%s/"
      "{tracks.csv,timing.csv,static_map.ply,static_map.pcd,poses.txt,config.yaml,run.json%s%s%s%s}"
      "\n",
      o.out.c_str(), odometry ? ",odometry.csv" : "", raw_map ? ",raw_map.ply" : "",
      plotted ? ",maps.png" : "", o.filtered_scans ? ",filtered/" : "");
  if (mcap) {
    std::printf("mcap             %s (%llu messages, %u chunks, %.1f MB)\n", o.mcap.c_str(),
                static_cast<unsigned long long>(mcap->mcap_stats().messages),
                mcap->mcap_stats().chunks,
                static_cast<double>(mcap->mcap_stats().file_bytes) / 1e6);
  }
}

void run(const RunOptions& o) {
  // For the whole command: a signal while the maps are written still lets them finish.
  const StopSignals stop_signals;
  // The two pose sources are checked before the configuration and the input are read.
  if (o.odometry == "on" && !o.poses.empty()) (void)use_odometry(o.odometry, false, o.poses);
  core::Config config = o.config.load();
  io::RunStatusFile status_file(fs::path(o.out) / "run.json", new_run_status("run", o.input));
  io::RunStatus& status = status_file.status();
  SkipWarnings warnings(o.input);
  runner::RunInput input(o.input, run_input_options(o),
                         [&status, &warnings](std::uint64_t index, const std::string& error) {
                           ++status.scans_skipped_unreadable;
                           status.add_skipped(index, "unreadable: " + error);
                           warnings.warn(index, "unreadable, skipped: " + error);
                         });
  const bool odometry = use_odometry(o.odometry, input.folder(), o.poses);
  if (odometry && o.no_deskew) config.odometry.deskew = false;
  if (odometry) input.use_odometry(config.odometry.deskew);
  // A simulated sequence knows how high its sensor stands; the user's configuration wins.
  const auto height = input.stated_sensor_height();
  if (height && !o.config.sets("detection.sensor_height_m")) {
    config.detection.sensor_height_m = *height;
  }

  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec) throw core::InputError(o.out + ": cannot create the output folder: " + ec.message());
  // From here on the folder holds outputs: run.json says whether they are whole.
  status_file.start();
  try {
    run_into(o, config, odometry, status, warnings, input);
  } catch (const std::exception& e) {
    status_file.fail(e.what());
    throw;
  }
  status_file.finish(StopSignals::signal_name());
}

}  // namespace

void register_run(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "run", "run the pipeline over a sequence folder or a folder of organized PCD files");
  auto o = std::make_shared<RunOptions>();
  cmd->add_option(
         "input", o->input,
         "sequence folder or folder of organized PCD files (docs/formats.md), .pcap/.pcapng, "
         ".bag, rosbag2 folder (sqlite3 or mcap), .mcap, or udp://HOST:PORT (docs/inputs.md)")
      ->required();
  o->source.add_to(*cmd);
  cmd->add_option("--on-bad-scan", o->on_bad_scan,
                  "a scan that cannot be read or decoded (a truncated PCD, a corrupt bag "
                  "message): skip it (counted in the summary and run.json) or stop with an error")
      ->check(CLI::IsMember({"skip", "stop"}))
      ->capture_default_str();
  cmd->add_option("--out", o->out, "output folder (created)")->required();
  cmd->add_option("--poses", o->poses,
                  "sensor poses (sensor in world; replaces a sequence's poses.txt)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--poses-format", o->poses_format,
                  "tum (t x y z qx qy qz qw) or kitti (3x4 per scan)")
      ->check(CLI::IsMember({"tum", "kitti"}));
  cmd->add_flag("--filtered-scans", o->filtered_scans,
                "also write each scan (as processed: motion-compensated when deskewed) without its "
                "dynamic-object points as filtered/NNNNNN.pcd");
  cmd->add_flag("--no-deskew", o->no_deskew,
                "do not motion-compensate the scans (by default they are whenever poses give the "
                "sensor's motion, docs/inputs.md)");
  cmd->add_option("--odometry", o->odometry,
                  "estimate the sensor poses from the scans (docs/odometry.md): on; off (poses "
                  "from --poses or the sequence, else a static sensor); auto: on for a recording "
                  "(pcap, bag, udp) without --poses")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  cmd->add_option("--odometry-start", o->odometry_start,
                  "TUM trajectory whose pose at the first scan's stamp places the odometry's "
                  "world frame (default: the first scan's frame), e.g. a simulated sequence's "
                  "poses.txt to compare estimates with its ground truth")
      ->check(CLI::ExistingFile);
  cmd->add_option("--mcap", o->mcap,
                  "also write an MCAP file for Foxglove: scans with labels, detections, tracks, "
                  "poses, static map, metadata (docs/visualisation.md)");
  cmd->add_option("--mcap-compression", o->mcap_compression, "MCAP chunk compression")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}));
  cmd->add_option("--mcap-map-every", o->mcap_map_every,
                  "also write the static map to the MCAP every N scans (0: only at the end)");
  cmd->add_flag("--quiet", o->quiet, "no progress on stderr");
  cmd->add_flag("--no-plots", o->no_plots,
                "no raw_map.ply and maps.png (the accumulated raw points beside the static map, "
                "as the paper's Fig. 7; needs python3-matplotlib)");
  o->config.add_to(*cmd);
  cmd->callback([o] { run(*o); });
}

}  // namespace ringtrack::cli
