#include "ringtrack/runner/run_input.hpp"

#include <algorithm>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/text.hpp"
#include "ringtrack/pipeline/deskew.hpp"

namespace ringtrack::runner {
namespace {

// The source options of the input: a folder reads the poses file in place of its poses.txt; a
// recording's poses are matched to its stamps by RunInput instead.
io::ScanSourceOptions source_options(const std::string& input, const RunInputOptions& o) {
  io::ScanSourceOptions options = o.source;
  if (options.format == io::ScanInputFormat::kAuto) {
    options.format = io::guess_scan_input_format(input);
  }
  options.poses.clear();
  if (options.format == io::ScanInputFormat::kFolder && !o.poses.empty()) {
    options.poses = o.poses;
    options.poses_format =
        o.poses_format == "kitti" ? io::PoseFileFormat::kKitti : io::PoseFileFormat::kTum;
  }
  return options;
}

}  // namespace

std::pair<std::int64_t, std::int64_t> column_time_span(const core::OrganizedScan& scan) {
  const auto& t = scan.column_stamp_ns;
  if (t.size() != static_cast<std::size_t>(scan.columns()) || t.empty()) {
    return {scan.stamp_ns, scan.stamp_ns};
  }
  const auto [first, last] = std::minmax_element(t.begin(), t.end());
  return {*first, *last};
}

RunInput::RunInput(const std::string& input, const RunInputOptions& options, SkipHandler on_skip)
    : name_(input),
      source_(io::open_source(input, source_options(input, options))),
      reader_(*source_, options.on_bad_scan, std::move(on_skip)),
      poses_(options.poses) {
  sequence_ = source_->sequence();
  if (sequence_ != nullptr) {
    plan_sequence_deskew(options);
  } else {
    plan_recording_deskew(options);
  }
}

void RunInput::use_odometry(bool odometry_deskew) {
  odometry_ = true;
  deskew_ = false;
  deskew_off_ = odometry_deskew ? "by the odometry (estimated velocity, from the second scan)"
                                : "off (odometry.deskew false)";
}

bool RunInput::next(std::size_t& index, core::OrganizedScan& scan, core::Pose& pose) {
  std::uint64_t number = 0;
  auto next_scan = reader_.next(number);
  if (!next_scan) return false;
  index = static_cast<std::size_t>(number);
  scan = std::move(*next_scan);
  pose = core::Pose{};
  pose.stamp_ns = scan.stamp_ns;
  if (const auto carried = source_->pose()) pose = *carried;
  ++scans_;
  if (odometry_) return true;
  if (sequence_ != nullptr) {
    deskew_sequence_scan(index, scan, pose);
  } else if (!trajectory_.empty()) {
    pose = recording_pose(index, scan);
  }
  return true;
}

std::optional<double> RunInput::stated_sensor_height() const {
  return sequence_ != nullptr ? sequence_->meta().sensor_height_m : std::nullopt;
}

std::string RunInput::summary() const {
  return sequence_ != nullptr ? sequence_->summary() : source_->summary();
}

std::string RunInput::pose_summary(const std::string& odometry_mode) const {
  if (odometry_) {
    return "odometry (--odometry " + odometry_mode +
           (odometry_mode == "auto" ? ": a recording without --poses)" : ")");
  }
  if (!poses_.empty()) return poses_ + " (--poses)";
  if (sequence_ != nullptr && sequence_->has_poses()) return "the sequence's poses.txt";
  return "none: static sensor at the origin (--odometry on estimates them)";
}

std::string RunInput::deskew_summary() const {
  if (!deskew_) return deskew_off_;
  std::string out = std::to_string(deskewed_) + " of " + std::to_string(scans_) + " scans (" +
                    deskew_method_ + ")";
  if (const std::size_t untimed = scans_ - deskewed_ - no_motion_; untimed > 0) {
    out += "; " + std::to_string(untimed) + " without per-column times left as they are";
  }
  if (no_motion_ > 0) {
    out += "; " + std::to_string(no_motion_) +
           " left as they are (no neighbouring scan with a later stamp: stamps going back)";
  }
  return out;
}

// A folder's scans are deskewed by its poses when it has some and its columns carry times.
void RunInput::plan_sequence_deskew(const RunInputOptions& options) {
  // A plain PCD folder's column times are the reader's guess (the files carry no time, and
  // such clouds may be motion-compensated by whoever wrote them): nothing to deskew by.
  if (options.no_deskew) {
    deskew_off_ = "off (--no-deskew)";
  } else if (!sequence_->has_poses()) {
    deskew_off_ = "off (no poses: static sensor)";
  } else if (!sequence_->is_sequence()) {
    deskew_off_ = "off (plain PCD folder: its columns carry no times)";
  } else if (sequence_->size() < 2) {
    deskew_off_ = "off (one scan: its motion is unknown)";
  } else {
    deskew_ = true;
    deskew_method_ = "poses of this and the next scan";
  }
}

// A recording's scans are deskewed by a TUM trajectory (the poses file) matched to their stamps.
void RunInput::plan_recording_deskew(const RunInputOptions& options) {
  if (!options.poses.empty()) {
    if (options.poses_format != "tum") {
      throw core::InputError(options.poses +
                             ": only TUM poses (with stamps) can be matched to a sensor recording");
    }
    trajectory_ = io::read_tum(options.poses);
  }
  if (options.no_deskew) {
    deskew_off_ = "off (--no-deskew)";
  } else if (trajectory_.empty()) {
    deskew_off_ = "off (no --poses: static sensor)";
  } else {
    deskew_ = true;
    deskew_method_ = "--poses at each scan's first and last column";
  }
}

// Motion between this scan's stamp and the next one's; the last scan extrapolates the motion
// between the previous scan and itself.
void RunInput::deskew_sequence_scan(std::size_t index, core::OrganizedScan& scan,
                                    core::Pose& pose) {
  const auto [first_ns, last_ns] = column_time_span(scan);
  if (!deskew_ || last_ns <= first_ns) return;
  if (const auto a = deskew_pair(index)) {
    pose = pipeline::deskew_scan(scan, sequence_->pose(*a), sequence_->pose(*a + 1));
    ++deskewed_;
  } else {
    ++no_motion_;
  }
}

// The trajectory's pose at a recording's scan, the scan deskewed by the poses at its first and
// last column when they cover them.
core::Pose RunInput::recording_pose(std::size_t index, core::OrganizedScan& scan) {
  if (!trajectory_.covers(scan.stamp_ns)) {
    throw core::InputError("--poses: no pose around scan " + std::to_string(index) + " at stamp " +
                           std::to_string(scan.stamp_ns) + " ns");
  }
  core::Pose pose = trajectory_.at(scan.stamp_ns);  // not const, so it is moved out
  const auto [first_ns, last_ns] = column_time_span(scan);
  if (!deskew_ || last_ns <= first_ns) return pose;
  if (!trajectory_.covers(first_ns) || !trajectory_.covers(last_ns)) {
    throw core::InputError(
        "--poses: no pose around scan " + std::to_string(index) + "'s columns (" +
        io::format_stamp(first_ns) + " to " + io::format_stamp(last_ns) + " s; the poses cover " +
        io::format_stamp(trajectory_.start_ns()) + " to " + io::format_stamp(trajectory_.end_ns()) +
        " s): motion compensation needs poses over the whole revolution (or give --no-deskew)");
  }
  ++deskewed_;
  return pipeline::deskew_scan(scan, trajectory_.at(first_ns), trajectory_.at(last_ns));
}

// The scans whose poses give scan i's motion: i and i + 1, or i - 1 and i for the last scan
// or when the stamps go back at i + 1 (a clock step: that scan is skipped); none when neither
// pair moves forward in time.
std::optional<std::size_t> RunInput::deskew_pair(std::size_t i) const {
  const auto forward = [this](std::size_t a) {
    return sequence_->pose(a + 1).stamp_ns > sequence_->pose(a).stamp_ns;
  };
  if (i + 1 < sequence_->size() && forward(i)) return i;
  if (i > 0 && forward(i - 1)) return i - 1;
  return std::nullopt;
}

}  // namespace ringtrack::runner
