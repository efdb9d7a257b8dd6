#include "ringtrack/runner/run.hpp"

#include <cstdio>
#include <deque>
#include <set>
#include <string_view>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/foxglove_sink.hpp"
#include "ringtrack/io/output_file.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/ply.hpp"
#include "ringtrack/io/point_spill.hpp"
#include "ringtrack/io/poses.hpp"
#include "ringtrack/io/text.hpp"
#include "ringtrack/mapping/static_map.hpp"
#include "ringtrack/odometry/odometry.hpp"
#include "ringtrack/version.hpp"

namespace ringtrack::runner {
namespace {

namespace fs = std::filesystem;

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

// Per-scan account of the odometry (odometry.csv) and its totals for the summary.
class OdometryLog {
 public:
  explicit OdometryLog(const fs::path& path) : file_(path) {
    file_.write(
        "scan,stamp,x,y,z,qx,qy,qz,qw,registered,degenerate,weak,weakest_share,iterations,"
        "source_points,correspondences,excluded_points,threshold_m,odometry_ms\n");
  }
  void write(std::size_t index, const odometry::OdometryResult& r, double ms) {
    char line[512];
    const auto& t = r.pose.translation;
    const auto& q = r.pose.rotation;
    std::snprintf(
        line, sizeof line,
        "%zu,%s,%.6f,%.6f,%.6f,%.9f,%.9f,%.9f,%.9f,%d,%d,%d,%.5f,%d,%zu,%zu,%zu,%.4f,%.4f\n", index,
        io::format_stamp(r.pose.stamp_ns).c_str(), t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w(),
        r.registered ? 1 : 0, r.degenerate ? 1 : 0, r.weak ? 1 : 0, r.weakest_share, r.iterations,
        r.source_points, r.correspondences, r.excluded_points, r.threshold_m, ms);
    file_.write(std::string_view(line));
    ++scans_;
    if (r.degenerate) ++degenerate_;
    if (r.weak) ++weak_;
    times_ms_.push_back(ms);
  }
  void close() { file_.close(); }
  [[nodiscard]] std::size_t scans() const { return scans_; }
  [[nodiscard]] std::size_t degenerate() const { return degenerate_; }
  [[nodiscard]] std::size_t weak() const { return weak_; }
  [[nodiscard]] const std::vector<double>& times_ms() const { return times_ms_; }

 private:
  io::OutputFile file_;
  std::size_t scans_{0}, degenerate_{0}, weak_{0};
  std::vector<double> times_ms_;
};

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

// The MCAP sink with the run's metadata and the configuration it ran with.
std::unique_ptr<io::FoxgloveSink> open_mcap(const RunOptions& o, const core::Config& config) {
  io::FoxgloveSinkOptions options;
  options.mcap.compression = io::parse_mcap_compression(o.mcap_compression);
  options.mcap.library = std::string("ringtrack ") + kVersion;
  options.map_every_scans = o.mcap_map_every;
  auto sink = std::make_unique<io::FoxgloveSink>(o.mcap, options);
  sink->write_metadata("ringtrack", o.mcap_metadata);
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

void write_config(const fs::path& path, const core::Config& config) {
  io::OutputFile file(path);
  file.write(core::dump_config(config));
  file.close();
}

}  // namespace

io::TrackRow track_row(std::uint64_t scan, std::int64_t stamp_ns, const tracking::Hypothesis& h,
                       const Eigen::Vector3d& origin) {
  io::TrackRow row;
  row.scan = scan;
  row.stamp_ns = stamp_ns;
  row.id = h.id;
  row.position = h.reported_position + origin;
  row.velocity = h.velocity_mps;
  row.box = core::Box3d::shifted(h.box, origin);
  row.dynamic = h.dynamic;
  row.ever_dynamic = h.ever_dynamic;
  row.age = static_cast<std::uint32_t>(h.age_scans);
  row.points = static_cast<std::uint32_t>(h.points);
  row.person = h.person;
  return row;
}

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

bool prepare_run(RunInput& input, core::Config& config, const std::string& odometry_mode,
                 const std::string& poses, bool no_deskew, bool keep_sensor_height) {
  const bool odometry = use_odometry(odometry_mode, input.folder(), poses);
  if (odometry && no_deskew) config.odometry.deskew = false;
  if (odometry) input.use_odometry(config.odometry.deskew);
  const auto height = input.stated_sensor_height();
  if (height && !keep_sensor_height) config.detection.sensor_height_m = *height;
  return odometry;
}

// Everything a run holds between scans: the pipeline (built at the first scan: a recording's
// sensor model is known once it was decoded), the sinks and the summary's counters.
struct Run::State {
  State(RunInput& in, const core::Config& c, RunOptions o, io::RunStatus* s);
  void open_outputs();
  void process(std::size_t index);
  void write_scan_outputs(std::size_t index, const pipeline::FrameResult& result);
  void feed_maps();
  void write_maps();

  RunInput& input;
  const core::Config config;
  const RunOptions options;
  io::RunStatus own_status;
  io::RunStatus& status;
  std::unique_ptr<pipeline::Pipeline> pipeline;
  std::unique_ptr<FilteredScanWriter> filtered;
  std::unique_ptr<io::FoxgloveSink> mcap;
  std::optional<io::TracksCsvWriter> tracks;
  std::optional<io::TimingCsvWriter> timing;
  std::unique_ptr<OdometryLog> odometry_log;
  std::optional<mapping::StaticMap> raw_map;
  std::unique_ptr<io::PointSpill> spill;
  core::OrganizedScan scan;  // the last scan read: the MCAP's end carries its stamp
  core::Pose pose;
  std::vector<io::TrackRow> rows;
  std::vector<core::Pose> poses;
  std::set<std::uint64_t> track_ids, dynamic_ids;
  RunSummary summary;
};

Run::State::State(RunInput& in, const core::Config& c, RunOptions o, io::RunStatus* s)
    : input(in), config(c), options(std::move(o)), status(s != nullptr ? *s : own_status) {
  summary.bounded_map = config.mapping.map_radius_m > 0.0;
  open_outputs();
}

void Run::State::open_outputs() {
  const fs::path& out = options.out;
  std::error_code ec;
  if (options.filtered_scans) fs::create_directories(out / "filtered", ec);
  write_config(out / "config.yaml", config);
  if (!options.mcap.empty()) mcap = open_mcap(options, config);
  if (options.filtered_scans) filtered = std::make_unique<FilteredScanWriter>(out / "filtered");
  tracks.emplace(out / "tracks.csv");
  timing.emplace(out / "timing.csv");
  if (options.odometry) odometry_log = std::make_unique<OdometryLog>(out / "odometry.csv");
  // The raw map for the pictures has no bound: with mapping.map_radius_m there is none.
  if (options.raw_map && !summary.bounded_map) raw_map.emplace(config.mapping.voxel_size_m);
  if (summary.bounded_map) spill = std::make_unique<io::PointSpill>(out / "static_map.spill");
}

// The scan just read through the pipeline and into the outputs; a scan the pipeline skips is
// counted and reported, and the run goes on.
void Run::State::process(std::size_t index) {
  if (!pipeline) {
    pipeline = std::make_unique<pipeline::Pipeline>(config, input.sensor_model());
    if (options.odometry && !options.odometry_start.empty()) {
      pipeline->set_odometry_start(odometry_start(options.odometry_start, scan.stamp_ns));
    }
  }
  const auto& result =
      options.odometry ? pipeline->process_with_odometry(scan) : pipeline->process(scan, pose);
  if (result.skipped) {
    ++status.scans_skipped_stamp;
    status.add_skipped(index, result.skip_reason);
    if (options.on_skipped) options.on_skipped(index, result.skip_reason);
    return;
  }
  if (options.odometry) {
    pose = result.pose;
    odometry_log->write(index, pipeline->odometry_result(), result.times.odometry_ms);
  }
  poses.push_back(pose);
  feed_maps();
  write_scan_outputs(index, result);
  if (options.on_scan) options.on_scan(index, result, rows);
}

// What the filter released or evicted with the last scan goes to the raw map and the spill.
void Run::State::feed_maps() {
  if (raw_map) accumulate_raw(pipeline->dynamic_filter(), *raw_map);
  if (spill) {
    for (const auto& v : pipeline->dynamic_filter().evicted())
      spill->append(v.position, v.intensity);
  }
}

void Run::State::write_scan_outputs(std::size_t index, const pipeline::FrameResult& result) {
  rows.clear();
  for (const auto& h : result.hypotheses) {
    if (!h.reported) continue;  // unconfirmed or lost (docs/tracking.md, "What is reported")
    rows.push_back(track_row(index, scan.stamp_ns, h, result.origin));
    track_ids.insert(h.id);
    if (h.ever_dynamic) dynamic_ids.insert(h.id);
  }
  tracks->write(rows);
  timing->write(timing_row(index, scan.stamp_ns, result.times, options.odometry));
  summary.total_ms.push_back(result.times.total_ms);
  summary.too_high += pipeline->detector_stats().too_high;
  summary.detections += pipeline->detector_stats().detections;
  ++status.scans_processed;
  const Eigen::Vector3d& origin = result.origin;
  status.origin_m = {origin.x(), origin.y(), origin.z()};
  if (mcap) mcap->write_pipeline_frame(scan, pose, result, pipeline->static_map());
  if (filtered) {
    filtered->hold(index, scan);
    filtered->write_released(pipeline->dynamic_filter());
  }
}

// The maps, the poses and the MCAP's end, once the filter has decided on every scan.
void Run::State::write_maps() {
  const Eigen::Vector3d origin = pipeline->origin();
  summary.origin = origin;
  summary.spilled_voxels = spill ? spill->size() : 0;
  summary.map_voxels =
      write_map(options.out / "static_map.ply", pipeline->static_map(), true, origin, spill.get());
  io::write_tum(options.out / "poses.txt", poses);
  if (mcap) mcap->finish(pipeline->static_map(), scan.stamp_ns);
  if (raw_map) {
    write_map(options.out / "raw_map.ply", *raw_map, false, origin);
    summary.raw_map = true;
  }
}

Run::Run(RunInput& input, const core::Config& config, RunOptions options, io::RunStatus* status)
    : state_(std::make_unique<State>(input, config, std::move(options), status)) {}

Run::~Run() = default;

bool Run::step() {
  State& s = *state_;
  // A stop request ends the run after the scan at hand; finish() closes every output.
  if (s.options.stop != nullptr && s.options.stop->load()) {
    s.summary.stopped = true;
    return false;
  }
  std::size_t index = 0;
  try {
    if (!s.input.next(index, s.scan, s.pose)) return false;
    s.status.scans_read = s.input.read();
    s.process(index);
  } catch (...) {
    // The scan that stopped the run: unreadable (BadScanPolicy::kStop) or failing later.
    s.status.scans_read = s.input.read();
    s.status.scans_failed = 1;
    throw;
  }
  return true;
}

std::size_t Run::scans() const {
  return state_->summary.total_ms.size();
}

RunSummary Run::finish() {
  State& s = *state_;
  s.status.scans_read = s.input.read();
  s.status.scans_skipped_unreadable = s.input.unreadable();
  if (s.summary.total_ms.empty()) throw core::InputError(s.input.name() + ": no scans found");
  s.pipeline->finish();
  if (s.filtered) s.filtered->write_released(s.pipeline->dynamic_filter());
  if (s.raw_map) accumulate_raw(s.pipeline->dynamic_filter(), *s.raw_map);
  s.tracks->close();
  s.timing->close();
  if (s.odometry_log) s.odometry_log->close();
  s.write_maps();
  RunSummary& summary = s.summary;
  summary.scans = summary.total_ms.size();
  summary.tracks = s.track_ids.size();
  summary.dynamic_tracks = s.dynamic_ids.size();
  summary.dropped_points = s.pipeline->static_map().dropped_points();
  if (s.odometry_log) {
    summary.odometry_scans = s.odometry_log->scans();
    summary.odometry_degenerate = s.odometry_log->degenerate();
    summary.odometry_weak = s.odometry_log->weak();
    summary.odometry_ms = s.odometry_log->times_ms();
  }
  if (s.mcap) summary.mcap = s.mcap->mcap_stats();
  return summary;
}

RunSummary run(RunInput& input, const core::Config& config, const RunOptions& options,
               io::RunStatus* status) {
  Run r(input, config, options, status);
  while (r.step()) {
  }
  return r.finish();
}

}  // namespace ringtrack::runner
