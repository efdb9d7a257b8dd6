#include "ringtrack/detection/detector.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <string>

#include "ringtrack/core/error.hpp"

namespace ringtrack::detection {
namespace {

constexpr std::uint8_t kNone = 0;       // not a segment point (or already reset)
constexpr std::uint8_t kUnvisited = 1;  // segment point not yet in a cluster
constexpr std::uint8_t kVisited = 2;    // segment point already in a cluster

}  // namespace

struct Detector::Frame {
  int rings{0};
  int columns{0};
  Eigen::Matrix3d rotation{Eigen::Matrix3d::Identity()};
  Eigen::Vector3d translation{Eigen::Vector3d::Zero()};
  const std::vector<Eigen::Vector3f>* predictions{nullptr};
  const core::SceneMemory* memory{nullptr};  // what earlier scans saw, or none
  double azimuth_step_rad{0.0};              // column spacing, for the split's bin width
};

Detector::Detector(const core::DetectionConfig& config) : config_(config) {
  if (config_.neighbor_radius < 0) {
    throw core::ConfigError("key 'detection.neighbor_radius' must not be negative, got " +
                            std::to_string(config_.neighbor_radius));
  }
  if (config_.min_cluster_points < 1) {
    throw core::ConfigError("key 'detection.min_cluster_points' must be at least 1, got " +
                            std::to_string(config_.min_cluster_points));
  }
  if (!(config_.join_distance_m >= 0.0)) {
    throw core::ConfigError("key 'detection.join_distance_m' must not be negative");
  }
  if (!(config_.min_height_ring_gap_deg >= 0.0 && config_.min_height_ring_gap_deg < 90.0)) {
    throw core::ConfigError("key 'detection.min_height_ring_gap_deg' must lie in [0, 90)");
  }
  if (!(config_.split_min_width_m >= 0.0)) {
    throw core::ConfigError("key 'detection.split_min_width_m' must not be negative");
  }
  if (!(config_.split_bin_m > 0.0)) {
    throw core::ConfigError("key 'detection.split_bin_m' must be positive");
  }
  if (!(config_.split_valley_ratio >= 0.0 && config_.split_valley_ratio < 1.0)) {
    throw core::ConfigError("key 'detection.split_valley_ratio' must lie in [0, 1)");
  }
  const auto theta = static_cast<float>(config_.join_distance_m);
  join_threshold_ = config_.join_rule == core::JoinRule::kEuclidean ? theta * theta : theta;
  min_height_gap_tan_ =
      static_cast<float>(std::tan(config_.min_height_ring_gap_deg * std::numbers::pi / 180.0));
}

void Detector::build_offsets(int columns) {
  // Window offsets with the column offset reduced into (-columns, columns), so one conditional
  // add or subtract wraps a column; duplicates (windows wider than the ring) are dropped.
  offsets_.clear();
  const int r = config_.neighbor_radius;
  for (int dr = -r; dr <= r; ++dr) {
    const int rem = r - std::abs(dr);
    for (int dc = -rem; dc <= rem; ++dc) {
      const int reduced = dc % columns;
      const int canonical = (reduced + columns) % columns;
      if (dr == 0 && canonical == 0) continue;
      const bool seen = std::any_of(offsets_.begin(), offsets_.end(), [&](const Offset& o) {
        return o.d_ring == dr && (o.d_column + columns) % columns == canonical;
      });
      if (!seen) offsets_.push_back({dr, reduced});
    }
  }
  offsets_columns_ = columns;
}

void Detector::collect_segment_points(const core::OrganizedScan& scan,
                                      const std::vector<std::uint8_t>& labels) {
  seeds_.clear();
  const std::size_t n = scan.size();
  const std::uint8_t* label = labels.data();
  const core::ReturnStatus* status = scan.statuses().data();
  std::uint8_t* state = state_.data();
  auto check = [&](std::size_t i) {
    if (label[i] == kSegmentLabel && status[i] == core::ReturnStatus::kValid) {
      seeds_.push_back(static_cast<std::uint32_t>(i));
      state[i] = kUnvisited;
    }
  };
  // Segment points are a few percent of the cells: skip eight background labels at a time.
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    std::uint64_t word = 0;
    std::memcpy(&word, label + i, sizeof word);
    if (word == 0) continue;
    for (std::size_t k = i; k < i + 8; ++k) check(k);
  }
  for (; i < n; ++i) check(i);
}

template <core::JoinRule kRule>
void Detector::grow_clusters(const core::OrganizedScan& scan, const Frame& frame) {
  const int rings = frame.rings;
  const int columns = frame.columns;
  const float* range = scan.ranges().data();
  const float* x = scan.xs().data();
  const float* y = scan.ys().data();
  const float* z = scan.zs().data();
  const float threshold = join_threshold_;
  std::uint8_t* state = state_.data();
  const Offset* offsets_begin = offsets_.data();
  const Offset* offsets_end = offsets_begin + offsets_.size();

  for (const std::uint32_t seed : seeds_) {
    if (state[seed] != kUnvisited) continue;
    // Breadth-first growth with the cluster vector as the queue: each cluster ends up as one
    // contiguous run, and nothing is popped or reallocated once capacity has grown.
    cluster_.clear();
    cluster_.push_back(seed);
    state[seed] = kVisited;
    for (std::size_t head = 0; head < cluster_.size(); ++head) {
      const std::uint32_t p = cluster_[head];
      const int ring = static_cast<int>(p / static_cast<std::uint32_t>(columns));
      const int column = static_cast<int>(p) - ring * columns;
      for (const Offset* o = offsets_begin; o != offsets_end; ++o) {
        const int rr = ring + o->d_ring;
        if (rr < 0 || rr >= rings) continue;
        int cc = column + o->d_column;
        if (cc < 0) {
          cc += columns;
        } else if (cc >= columns) {
          cc -= columns;
        }
        const auto q = static_cast<std::uint32_t>(rr * columns + cc);
        if (state[q] != kUnvisited) continue;
        bool joins = false;
        if constexpr (kRule == core::JoinRule::kEuclidean) {
          const float dx = x[p] - x[q], dy = y[p] - y[q], dz = z[p] - z[q];
          joins = dx * dx + dy * dy + dz * dz < threshold;
        } else {
          joins = std::abs(range[p] - range[q]) < threshold;
        }
        if (!joins) continue;
        state[q] = kVisited;
        cluster_.push_back(q);
      }
    }
    evaluate_cluster(scan, frame);
  }
}

core::Detection& Detector::next_detection() {
  // Reuses the Detection objects (and their index buffers) of earlier calls.
  if (spare_.empty()) {
    detections_.emplace_back();
  } else {
    detections_.push_back(std::move(spare_.back()));
    spare_.pop_back();
  }
  return detections_.back();
}

void Detector::evaluate_cluster(const core::OrganizedScan& scan, const Frame& frame) {
  const std::size_t n = cluster_.size();
  // Parts of a split are smaller still, so a cluster that cannot be a small detection is not
  // examined further.
  if (n < static_cast<std::size_t>(config_.min_cluster_points) && !may_be_small(n, frame)) {
    ++stats_.too_small;
    return;
  }

  const float* x = scan.xs().data();
  const float* y = scan.ys().data();
  const float* z = scan.zs().data();
  world_.resize(n);
  double lo_x = std::numeric_limits<double>::infinity(), hi_x = -lo_x;
  double lo_y = lo_x, hi_y = -lo_x;
  for (std::size_t k = 0; k < n; ++k) {
    const std::uint32_t i = cluster_[k];
    const Eigen::Vector3d w =
        frame.rotation * Eigen::Vector3d(x[i], y[i], z[i]) + frame.translation;
    world_[k] = w;
    lo_x = std::min(lo_x, w.x());
    hi_x = std::max(hi_x, w.x());
    lo_y = std::min(lo_y, w.y());
    hi_y = std::max(hi_y, w.y());
  }
  // The extent along any horizontal axis is at most the box diagonal: person-sized clusters
  // (nearly all of them) skip the split without computing an axis.
  if (config_.split_min_width_m > 0.0 &&
      std::hypot(hi_x - lo_x, hi_y - lo_y) > config_.split_min_width_m) {
    split_cluster(frame);
    for (const Range& part : parts_) evaluate_part(scan, frame, part.begin, part.end);
  } else {
    evaluate_part(scan, frame, 0, n);
  }
}

void Detector::split_cluster(const Frame& frame) {
  // Depth-first over the parts with an explicit stack; a cut partitions the part's run of
  // cluster_ and world_ in place, so the parts stay contiguous runs.
  parts_.clear();
  split_stack_.clear();
  split_stack_.push_back({0, cluster_.size(), 0});
  while (!split_stack_.empty()) {
    const Range r = split_stack_.back();
    split_stack_.pop_back();
    double cut = 0.0;
    if (r.depth >= kMaxSplitDepth || !find_split(frame, r.begin, r.end, cut)) {
      parts_.push_back(r);
      continue;
    }
    std::size_t mid = r.begin;
    for (std::size_t k = r.begin; k < r.end; ++k) {
      if (projection_[k - r.begin] < cut) {
        std::swap(world_[mid], world_[k]);
        std::swap(cluster_[mid], cluster_[k]);
        std::swap(projection_[mid - r.begin], projection_[k - r.begin]);
        ++mid;
      }
    }
    ++stats_.splits;
    split_stack_.push_back({mid, r.end, r.depth + 1});
    split_stack_.push_back({r.begin, mid, r.depth + 1});
  }
}

Detector::SplitAxis Detector::project_on_principal_axis(std::size_t begin, std::size_t end) {
  const std::size_t m = end - begin;
  SplitAxis axis;
  for (std::size_t k = begin; k < end; ++k) {
    axis.mx += world_[k].x();
    axis.my += world_[k].y();
  }
  axis.mx /= static_cast<double>(m);
  axis.my /= static_cast<double>(m);
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (std::size_t k = begin; k < end; ++k) {
    const double dx = world_[k].x() - axis.mx, dy = world_[k].y() - axis.my;
    sxx += dx * dx;
    sxy += dx * dy;
    syy += dy * dy;
  }
  // Principal axis of the 2x2 covariance in closed form; the angle lies in (-pi/2, pi/2], so
  // the axis points to +x (a canonical sign: the profile and its tie-breaks do not depend on
  // how the axis was found).
  const double angle = 0.5 * std::atan2(2.0 * sxy, sxx - syy);
  axis.ax = std::cos(angle);
  axis.ay = std::sin(angle);
  projection_.resize(m);
  axis.p_min = std::numeric_limits<double>::infinity();
  axis.p_max = -axis.p_min;
  for (std::size_t k = begin; k < end; ++k) {
    const double p = axis.ax * (world_[k].x() - axis.mx) + axis.ay * (world_[k].y() - axis.my);
    projection_[k - begin] = p;
    axis.p_min = std::min(axis.p_min, p);
    axis.p_max = std::max(axis.p_max, p);
  }
  return axis;
}

void Detector::fill_coverage(const Frame& frame, const SplitAxis& axis, std::size_t begin,
                             std::size_t m, double sub, std::size_t sub_bins) {
  // Coverage profile along the axis: each point stands for the stretch of surface between it
  // and its neighbouring columns, its footprint (horizontal distance * azimuth step, longer as
  // the axis turns away from the tangential direction, at most 4x), and spreads its unit mass
  // evenly over it. A uniformly sampled surface then has a flat profile whatever the range,
  // angle and bin width (point counts per bin alias: 1 column next to 2), and a gap between two
  // people is a hole as wide as the columns missing there.
  const double tx = frame.translation.x(), ty = frame.translation.y();
  coverage_.assign(sub_bins, 0.0);
  for (std::size_t k = 0; k < m; ++k) {
    const double dx = world_[begin + k].x() - tx, dy = world_[begin + k].y() - ty;
    const double h = std::hypot(dx, dy);
    const double footprint =
        h * h * frame.azimuth_step_rad / std::max(std::abs(axis.ay * dx - axis.ax * dy), 0.25 * h);
    const double u = (projection_[k] - axis.p_min) / sub;
    const double half = 0.5 * footprint / sub;
    if (!(half > 1e-9)) {
      coverage_[std::min(static_cast<std::size_t>(u), sub_bins - 1)] += 1.0;
      continue;
    }
    const double u0 = std::max(u - half, 0.0);
    const double u1 = std::min(u + half, static_cast<double>(sub_bins));
    const double density = 1.0 / (2.0 * half);
    for (auto j = static_cast<std::size_t>(u0); j < sub_bins && static_cast<double>(j) < u1; ++j) {
      const double overlap =
          std::min(u1, static_cast<double>(j + 1)) - std::max(u0, static_cast<double>(j));
      if (overlap > 0.0) coverage_[j] += overlap * density;
    }
  }
}

std::size_t Detector::deepest_valley() {
  // Sliding windows of one bin (kSubBins sub-bins), one sub-bin apart; a valley window's peaks
  // are the highest windows entirely left and entirely right of it.
  const std::size_t windows = coverage_.size() - kSubBins + 1;
  window_.resize(windows);
  for (std::size_t j = 0; j < windows; ++j) {
    double w = 0.0;
    for (std::size_t q = 0; q < kSubBins; ++q) w += coverage_[j + q];
    window_[j] = w;
  }
  left_max_.assign(windows, 0.0);
  for (std::size_t j = kSubBins; j < windows; ++j) {
    left_max_[j] = std::max(left_max_[j - 1], window_[j - kSubBins]);
  }
  // Deepest valley: the smallest window / (smaller peak); ties (within 1e-9) to the first.
  // Scanning right to left with right_max over windows j + kSubBins.. .
  std::size_t best = windows;
  double best_score = 2.0;
  double right_max = 0.0;
  for (std::size_t j = windows - kSubBins; j-- > kSubBins;) {
    right_max = std::max(right_max, window_[j + kSubBins]);
    const double peak = std::min(left_max_[j], right_max);
    const double w = window_[j];
    if (!(w < peak) || w > config_.split_valley_ratio * peak) continue;
    const double score = w / peak;
    if (score <= best_score + 1e-9) {
      best = j;
      best_score = std::min(score, best_score);
    }
  }
  return best;
}

bool Detector::find_split(const Frame& frame, std::size_t begin, std::size_t end, double& cut) {
  const std::size_t m = end - begin;
  if (m < 2) return false;
  const SplitAxis axis = project_on_principal_axis(begin, end);
  const double extent = axis.p_max - axis.p_min;
  if (!(extent > config_.split_min_width_m)) return false;
  // People side by side spread across the line of sight. Along it, the points are spaced by
  // the rings, not the columns: sparse samples of sloped or deep structures that the footprint
  // profile cannot model, and people one behind the other are the join rule's business.
  const double cx = axis.mx - frame.translation.x(), cy = axis.my - frame.translation.y();
  const double centre_distance = std::hypot(cx, cy);
  if (!(std::abs(axis.ay * cx - axis.ax * cy) >= kSplitMinAxisCos * centre_distance)) return false;

  const double sub = config_.split_bin_m / kSubBins;
  const auto sub_bins = static_cast<std::size_t>(extent / sub) + 1;
  if (sub_bins < 3 * kSubBins) return false;  // no window with a full window either side
  fill_coverage(frame, axis, begin, m, sub, sub_bins);
  const std::size_t best = deepest_valley();
  if (best == window_.size()) return false;
  cut = axis.p_min + (static_cast<double>(best) + 0.5 * kSubBins) * sub;
  // Both parts must be clusters in their own right.
  std::size_t left = 0;
  for (std::size_t k = 0; k < m; ++k) left += projection_[k] < cut ? 1 : 0;
  const auto min_points = static_cast<std::size_t>(config_.min_cluster_points);
  return left >= min_points && m - left >= min_points;
}

bool Detector::may_confirm(std::size_t n, const Frame& frame) const {
  // Near a prediction a small cluster may confirm a track (a far person hit by one or two beams).
  return n >= static_cast<std::size_t>(config_.relaxed_min_cluster_points) &&
         !frame.predictions->empty();
}

bool Detector::may_be_small(std::size_t n, const Frame& frame) const {
  // ... and where earlier scans saw free space it may start one.
  return may_confirm(n, frame) ||
         (frame.memory != nullptr && n >= static_cast<std::size_t>(config_.sparse_min_points));
}

bool Detector::new_to_the_scene(const core::OrganizedScan& scan, const Frame& frame,
                                std::size_t begin, std::size_t end) const {
  if (frame.memory == nullptr ||
      end - begin < static_cast<std::size_t>(config_.sparse_min_points)) {
    return false;
  }
  for (std::size_t k = begin; k < end; ++k) {
    if (!frame.memory->seen_free_before(scan, cluster_[k], world_[k],
                                        config_.background_margin_m)) {
      return false;
    }
  }
  return true;
}

// The object model's view of a part: its extent and where it stands (world frame).
struct Detector::PartShape {
  Eigen::Vector3d mean;
  Eigen::Vector3d lo;
  Eigen::Vector3d hi;
  double diagonal{0.0};
  bool too_high{false};
  bool too_tall{false};
  bool too_wide{false};
  bool too_short{false};
  [[nodiscard]] bool strict() const { return !(too_high || too_tall || too_wide || too_short); }
};

Detector::PartShape Detector::measure_part(const core::OrganizedScan& scan, const Frame& frame,
                                           std::size_t begin, std::size_t end) const {
  const float* range = scan.ranges().data();
  const auto columns = static_cast<std::uint32_t>(frame.columns);
  const auto top_ring_start = static_cast<std::uint32_t>(frame.rings - 1) * columns;
  PartShape shape;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  shape.lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  shape.hi = -shape.lo;
  double range_sum = 0.0;
  bool touches_top_or_bottom = false;
  for (std::size_t k = begin; k < end; ++k) {
    const std::uint32_t i = cluster_[k];
    const Eigen::Vector3d& w = world_[k];
    sum += w;
    shape.lo = shape.lo.cwiseMin(w);
    shape.hi = shape.hi.cwiseMax(w);
    range_sum += range[i];
    touches_top_or_bottom |= i < columns || i >= top_ring_start;
  }
  const double inv_n = 1.0 / static_cast<double>(end - begin);
  shape.mean = sum * inv_n;
  const double height = shape.hi.z() - shape.lo.z();
  shape.diagonal = std::hypot(shape.hi.x() - shape.lo.x(), shape.hi.y() - shape.lo.y());
  // Rings this far apart sample an object of height h as an extent down to h minus two ring
  // gaps, so the extent is credited with one gap at the cluster's mean range.
  const double height_allowance = range_sum * inv_n * static_cast<double>(min_height_gap_tan_);
  shape.too_high = shape.lo.z() - ground_z_m_ > config_.max_altitude_m;
  shape.too_tall = height > config_.max_height_m;
  shape.too_wide = shape.diagonal > config_.max_diagonal_m;
  shape.too_short = !touches_top_or_bottom && height + height_allowance < config_.min_height_m;
  return shape;
}

bool Detector::relaxable(const PartShape& shape, const Frame& frame) const {
  if (shape.too_high || shape.too_tall || shape.diagonal > config_.relaxed_max_diagonal_m) {
    return false;
  }
  const double r2 = config_.relaxed_radius_m * config_.relaxed_radius_m;
  for (const Eigen::Vector3f& p : *frame.predictions) {
    const double dx = static_cast<double>(p.x()) - shape.mean.x();
    const double dy = static_cast<double>(p.y()) - shape.mean.y();
    if (dx * dx + dy * dy <= r2) return true;
  }
  return false;
}

void Detector::count_rejected(const PartShape& shape) {
  ++stats_.clusters;
  if (shape.too_high) {
    ++stats_.too_high;
  } else if (shape.too_tall) {
    ++stats_.too_tall;
  } else if (shape.too_wide) {
    ++stats_.too_wide;
  } else {
    ++stats_.too_short;
  }
}

// A cluster of min_cluster_points or more: the strict model, else the relaxed one near a
// prediction. A smaller one: sparse when new to the scene and of the strict model's shape,
// relaxed when near a prediction (with relaxed_min_cluster_points, or new to the scene).
void Detector::evaluate_part(const core::OrganizedScan& scan, const Frame& frame, std::size_t begin,
                             std::size_t end) {
  const std::size_t n = end - begin;
  const bool small = n < static_cast<std::size_t>(config_.min_cluster_points);
  if (small && !may_be_small(n, frame)) {
    ++stats_.too_small;
    return;
  }
  const PartShape shape = measure_part(scan, frame, begin, end);
  if (!small) {
    if (shape.strict()) return add_detection(shape, begin, end, false, false, true);
    if (relaxable(shape, frame)) return add_detection(shape, begin, end, true, false, true);
    count_rejected(shape);
    return;
  }
  // The scene memory is the costly question (a moving sensor's recent views probe beams and
  // columns for every point), so it is asked only where its answer decides: a small cluster
  // that fails the strict model and lies near no prediction is dropped unasked.
  if (shape.strict()) {
    if (new_to_the_scene(scan, frame, begin, end)) {
      return add_detection(shape, begin, end, false, true, true);
    }
    if (may_confirm(n, frame) && relaxable(shape, frame)) {
      return add_detection(shape, begin, end, true, false, false);
    }
  } else if (relaxable(shape, frame)) {
    if (may_confirm(n, frame)) return add_detection(shape, begin, end, true, false, false);
    if (new_to_the_scene(scan, frame, begin, end)) {
      return add_detection(shape, begin, end, true, false, true);
    }
  }
  ++stats_.too_small;
}

void Detector::add_detection(const PartShape& shape, std::size_t begin, std::size_t end,
                             bool relaxed, bool sparse, bool counted) {
  if (counted) ++stats_.clusters;
  const double inv_n = 1.0 / static_cast<double>(end - begin);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t k = begin; k < end; ++k) {
    const Eigen::Vector3d d = world_[k] - shape.mean;
    cov.noalias() += d * d.transpose();
  }
  cov *= inv_n;
  const double floor = config_.min_position_stddev_m * config_.min_position_stddev_m;
  for (int a = 0; a < 3; ++a) cov(a, a) = std::max(cov(a, a), floor);

  core::Detection& d = next_detection();
  d.centroid = shape.mean.cast<float>();
  d.covariance = cov.cast<float>();
  d.box.min = shape.lo.cast<float>();
  d.box.max = shape.hi.cast<float>();
  d.indices.assign(cluster_.begin() + static_cast<std::ptrdiff_t>(begin),
                   cluster_.begin() + static_cast<std::ptrdiff_t>(end));
  std::sort(d.indices.begin(), d.indices.end());
  d.relaxed = relaxed;
  d.sparse = sparse;
  stats_.relaxed += relaxed ? 1 : 0;
  stats_.sparse += sparse ? 1 : 0;
  ++stats_.detections;
}

const std::vector<core::Detection>& Detector::detect(
    const core::OrganizedScan& scan, const std::vector<std::uint8_t>& segment_labels,
    const core::Pose& sensor_pose, const std::vector<Eigen::Vector3f>& predicted_positions_world,
    const core::SceneMemory* memory) {
  const std::size_t n = scan.size();
  if (segment_labels.size() != n) {
    throw core::InputError("detection: expected one segment label per cell (" + std::to_string(n) +
                           "), got " + std::to_string(segment_labels.size()));
  }
  if (n > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max())) {
    throw core::InputError("detection: a scan of " + std::to_string(n) +
                           " cells exceeds the 31-bit grid arithmetic");
  }
  stats_ = {};
  // Park last call's detections (with their buffers) for reuse.
  while (!detections_.empty()) {
    spare_.push_back(std::move(detections_.back()));
    detections_.pop_back();
  }
  if (n == 0) return detections_;

  if (state_.size() != n || state_dirty_) state_.assign(n, kNone);
  if (offsets_columns_ != scan.columns()) build_offsets(scan.columns());

  Frame frame;
  frame.rings = scan.rings();
  frame.columns = scan.columns();
  frame.rotation = sensor_pose.rotation.normalized().toRotationMatrix();
  frame.translation = sensor_pose.translation;
  frame.predictions = &predicted_positions_world;
  frame.memory = memory;
  frame.azimuth_step_rad = 2.0 * std::numbers::pi / static_cast<double>(scan.columns());

  state_dirty_ = true;
  collect_segment_points(scan, segment_labels);
  stats_.segment_points = seeds_.size();
  if (config_.join_rule == core::JoinRule::kEuclidean) {
    grow_clusters<core::JoinRule::kEuclidean>(scan, frame);
  } else {
    grow_clusters<core::JoinRule::kRangeDifference>(scan, frame);
  }
  for (const std::uint32_t i : seeds_) state_[i] = kNone;
  state_dirty_ = false;
  // Clusters come in order of their smallest cell; the parts of a split cluster may not.
  if (stats_.splits > 0) {
    std::sort(detections_.begin(), detections_.end(),
              [](const core::Detection& a, const core::Detection& b) {
                return a.indices.front() < b.indices.front();
              });
  }
  return detections_;
}

}  // namespace ringtrack::detection
