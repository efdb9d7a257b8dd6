#include "ringtrack/pipeline/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <string>
#include <utility>

#include "ringtrack/core/error.hpp"

namespace ringtrack::pipeline {
namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::milli>(to - from).count();
}

// Why a scan older than the previous one is skipped: both stamps and how far back it lies.
std::string older_than_previous(std::int64_t stamp_ns, std::int64_t previous_ns) {
  std::ostringstream text;
  text << "stamp " << stamp_ns << " ns is " << std::fixed << std::setprecision(9)
       << static_cast<double>(previous_ns - stamp_ns) * 1e-9 << " s older than the previous scan's "
       << previous_ns << " ns (a clock step or a corrupt stamp); skipped";
  return text.str();
}

// The farthest a pose may lie from the local origin: where float32 positions keep millimetres
// and the static map's voxel index (+-2^20 voxels) still holds every point the sensor returns.
double max_local_distance_m(const core::Config& config) {
  const double map_half_extent_m = std::ldexp(config.mapping.voxel_size_m, 20);
  return std::min(kMaxLocalDistanceM, map_half_extent_m - config.segmentation.invalid_range_m);
}

std::string format_m(double value) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(3) << value;
  return text.str();
}

std::string format_xyz(const Eigen::Vector3d& p) {
  std::ostringstream text;
  text << std::fixed << std::setprecision(3) << '(' << p.x() << ", " << p.y() << ", " << p.z()
       << ") m";
  return text.str();
}

}  // namespace

core::Pose Pipeline::to_local(const core::Pose& world) {
  if (!world.translation.allFinite()) {
    throw core::InputError("pipeline: the pose at " + std::to_string(world.stamp_ns) +
                           " ns has a non-finite position " + format_xyz(world.translation));
  }
  if (!framed_) {
    origin_ = (world.translation / kOriginGridM).array().round() * kOriginGridM;
    // The ground the altitude test counts from: under the sensor where the run starts, so the
    // test follows the data, not the datum of the world frame (sea level, a map's corner).
    ground_z_ = world.translation.z() - origin_.z() - config_.detection.sensor_height_m;
    detector_.set_ground_z(ground_z_);
    recent_views_.set_ground_z(ground_z_);
    filter_.set_ground_z(ground_z_);
    framed_ = true;
  }
  core::Pose local = world;
  local.translation -= origin_;
  const double reach_m = max_local_distance_m(config_);
  if (local.translation.norm() > reach_m) {
    throw core::InputError("pipeline: the pose at " + std::to_string(world.stamp_ns) + " ns, " +
                           format_xyz(world.translation) + ", lies " +
                           format_m(local.translation.norm()) + " m from the run's local origin " +
                           format_xyz(origin_) + " (the first pose rounded to " +
                           format_m(kOriginGridM) +
                           " m); positions are kept in float relative "
                           "to it, which allows at most " +
                           format_m(reach_m) + " m (docs/inputs.md, \"Frames\"): split the run");
  }
  return local;
}

const FrameResult& Pipeline::skip(const core::OrganizedScan& scan, std::string reason) {
  ++skipped_scans_;
  result_ = FrameResult{};
  result_.stamp_ns = scan.stamp_ns;
  result_.skipped = true;
  result_.skip_reason = std::move(reason);
  result_.origin = origin_;
  return result_;
}

Pipeline::Pipeline(const core::Config& config, core::SensorModel model)
    : config_(config),
      model_(std::move(model)),
      segmenter_(config.segmentation),
      detector_(config.detection),
      completer_(config.detection),
      tracker_(config.tracking),
      filter_(config.mapping),
      background_(model_, config.background),
      recent_views_(model_, config.background) {
  core::validate_config(config);
  model_.validate();
}

const FrameResult& Pipeline::process(const core::OrganizedScan& scan,
                                     const core::Pose& world_pose) {
  if (tracker_.stamp_ns() != 0 && scan.stamp_ns < tracker_.stamp_ns()) {
    return skip(scan, older_than_previous(scan.stamp_ns, tracker_.stamp_ns()));
  }
  if (tracker_.stamp_ns() != 0 && scan.stamp_ns == tracker_.stamp_ns()) {
    return skip(scan, "stamp " + std::to_string(scan.stamp_ns) +
                          " ns repeats the previous scan's (a repeated message or a clock that "
                          "stood still); skipped");
  }
  if (scan.rings() != model_.rings()) {
    throw core::InputError("pipeline: the scan at " + std::to_string(scan.stamp_ns) + " ns has " +
                           std::to_string(scan.rings()) + " rings, the sensor model " +
                           model_.name + " has " + std::to_string(model_.rings()));
  }
  // Every stage works in the local frame (class comment): float positions near zero.
  const core::Pose pose = to_local(world_pose);
  const auto t0 = Clock::now();
  segmenter_.segment(scan, labels_);
  const auto t1 = Clock::now();
  // The tracker's predictions for this scan let the detector relax its model near known objects;
  // the background learned from the earlier scans of a resting sensor lets it keep clusters too
  // small for the object model when they stand where the scene was seen free.
  const auto predictions = tracker_.predicted_positions(scan.stamp_ns);
  // (Nothing is learned when sparse detections are switched off: nothing would use it.)
  const bool sparse_on = config_.detection.sparse_min_points < config_.detection.min_cluster_points;
  const bool resting = sparse_on && track_rest(pose);
  const core::Motion motion = sweep_motion(scan, pose);
  const auto& detections = completer_.complete(
      scan, pose, detector_.detect(scan, labels_, pose, predictions, scene_memory(resting)));
  const auto& geometry = beam_geometry_.get(scan, model_);
  if (sparse_on) remember(scan, pose, motion, resting, geometry);
  const auto t2 = Clock::now();
  // What this scan sees of the space hypotheses occupied (free-space tests; docs/visibility.md).
  const core::VisibilityQuery visibility(scan, geometry, pose, motion);
  const auto& hypotheses = tracker_.update(detections, scan.stamp_ns, &visibility);
  const auto t3 = Clock::now();
  const auto& filtered =
      filter_.process(scan, pose, detections, hypotheses, {&visibility, &labels_});
  const auto t4 = Clock::now();

  result_.stamp_ns = scan.stamp_ns;
  result_.skipped = false;
  result_.skip_reason.clear();
  result_.segment_labels = labels_;
  result_.detections = detections;
  result_.hypotheses = hypotheses;
  result_.removed_cells = filtered.removed_cells;
  result_.retroactive_points = filtered.retroactive_points;
  result_.times = {elapsed_ms(t0, t1), elapsed_ms(t1, t2), elapsed_ms(t2, t3), elapsed_ms(t3, t4),
                   elapsed_ms(t0, t4)};
  result_.pose = world_pose;
  result_.origin = origin_;
  previous_pose_ = pose;  // local, as the motion of the next scan is taken in the local frame
  return result_;
}

const core::SceneMemory* Pipeline::scene_memory(bool resting) const {
  if (resting) return background_.scans() > 0 ? &background_ : nullptr;
  return config_.background.moving_memory && recent_views_.scans() > 0 ? &recent_views_ : nullptr;
}

void Pipeline::remember(const core::OrganizedScan& scan, const core::Pose& pose,
                        const core::Motion& motion, bool resting,
                        const std::shared_ptr<const core::BeamGeometry>& geometry) {
  if (resting) {
    background_.update(scan);
    // What the sensor saw before it came to rest is stale by the time it moves on.
    recent_views_.reset();
  } else if (config_.background.moving_memory) {
    recent_views_.add(scan, pose, motion, geometry);
  }
}

core::Motion Pipeline::sweep_motion(const core::OrganizedScan& scan, const core::Pose& pose) const {
  // A scan without column times was measured all at once (or its times are lost): nothing to
  // spread over the sweep. After a long gap (skipped scans) the old motion says little.
  constexpr std::int64_t kLongestGapNs = 1'000'000'000;
  if (!previous_pose_ || scan.column_stamp_ns.empty() ||
      pose.stamp_ns - previous_pose_->stamp_ns > kLongestGapNs) {
    return {};
  }
  return core::Motion::between(*previous_pose_, pose);
}

void Pipeline::predicted_track_boxes(std::int64_t stamp_ns) {
  excluded_boxes_.clear();
  if (!config_.odometry.exclude_tracks) return;
  const double dt_s =
      tracker_.stamp_ns() == 0 ? 0.0 : 1e-9 * static_cast<double>(stamp_ns - tracker_.stamp_ns());
  const auto margin =
      Eigen::Vector3f::Constant(static_cast<float>(config_.odometry.exclude_margin_m));
  for (const auto& h : tracker_.hypotheses()) {
    if (!h.reported || h.box.empty()) continue;
    const Eigen::Vector3f shift = (dt_s * h.filter.velocity()).cast<float>();
    core::Box3 box;
    box.min = h.box.min + shift - margin;
    box.max = h.box.max + shift + margin;
    excluded_boxes_.push_back(box);
  }
}

const FrameResult& Pipeline::process_with_odometry(core::OrganizedScan& scan) {
  if (tracker_.stamp_ns() != 0 && scan.stamp_ns < tracker_.stamp_ns()) {
    return skip(scan, older_than_previous(scan.stamp_ns, tracker_.stamp_ns()));
  }
  if (odometry_ && odometry_->scans() > 0 && scan.stamp_ns == tracker_.stamp_ns()) {
    return skip(scan,
                "stamp " + std::to_string(scan.stamp_ns) +
                    " ns repeats the previous scan's: the odometry needs time to pass; skipped");
  }
  if (!odometry_) {
    // Its map is float too: it starts from the start pose in the local frame.
    odometry_ = std::make_unique<odometry::Odometry>(config_.odometry,
                                                     to_local(odometry_start_).isometry());
  }
  const auto t0 = Clock::now();
  predicted_track_boxes(scan.stamp_ns);
  odometry_result_ = odometry_->process(scan, excluded_boxes_);
  odometry_result_.pose.translation += origin_;  // callers (and process()) take world poses
  const double odometry_ms = elapsed_ms(t0, Clock::now());
  process(scan, odometry_result_.pose);
  result_.times.odometry_ms = odometry_ms;
  result_.times.total_ms += odometry_ms;
  return result_;
}

bool Pipeline::track_rest(const core::Pose& pose) {
  const auto& limits = config_.background;
  if (rest_pose_ && pose.near(*rest_pose_, limits.static_shift_m,
                              limits.static_turn_deg * std::numbers::pi / 180.0)) {
    return true;
  }
  // A new resting pose candidate: what was learned belongs to another viewpoint. The model is
  // reset once when the sensor leaves, not on every scan of a moving sensor.
  if (background_.scans() > 0) background_.reset();
  rest_pose_ = pose;
  return false;
}

void Pipeline::finish() {
  filter_.flush();
  result_ = {};
}

}  // namespace ringtrack::pipeline
