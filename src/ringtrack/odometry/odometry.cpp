#include "ringtrack/odometry/odometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "ringtrack/core/error.hpp"
#include "ringtrack/odometry/registration.hpp"

namespace ringtrack::odometry {
namespace {

// Fewer pairs than this cannot be told from a chance alignment: the pose stays predicted.
constexpr std::size_t kMinCorrespondences = 20;
// Horizontal tangents of the grid normals span at least this (m): noise of a few centimetres
// between neighbouring columns would otherwise tilt the normals of the ground.
constexpr float kTangentSpanM = 0.4F;
constexpr int kMaxTangentColumns = 30;
// A second registration after compensating again pays off when the compensation moved points
// at kLeverM range by more than this over the revolution (m): on turning MAVs, not on cars.
constexpr double kSecondPassShiftM = 0.02;
constexpr double kLeverM = 20.0;
// Iterations of the first registration when more follow the compensation, and passes at most.
constexpr int kFirstPassIterations = 6;
constexpr int kMaxPasses = 3;
// After the first scans, a pass that another follows stops after this many iterations: the next
// pass starts from a new compensation anyway (docs/odometry.md, "Speed"). The first scans run
// every pass to convergence: their poses set the map's tilt for the rest of the run.
constexpr int kIntermediatePassIterations = 2;
constexpr std::size_t kFullPassScans = 30;
// The first scans enter the map at once: it is too sparse yet to wait for the next pose.
constexpr std::size_t kEarlyScans = 5;

bool inside_any(const Eigen::Vector3f& p, std::span<const core::Box3> boxes) {
  return std::any_of(boxes.begin(), boxes.end(), [&](const auto& b) { return b.contains(p); });
}

// Unit surface normal at a cell from its neighbours on the grid (same ring some columns apart,
// the next ring in the same column), with the points as compensated; false at edges, gaps and
// depth jumps.
bool grid_normal(const core::OrganizedScan& scan, const ScanCompensation& points, std::size_t cell,
                 Eigen::Vector3f& normal) {
  const int ring = scan.ring_of(cell), column = scan.column_of(cell), columns = scan.columns();
  const float range = scan.range_m(cell);
  const float step = range * 2.0F * std::numbers::pi_v<float> / static_cast<float>(columns);
  const int k = std::clamp(static_cast<int>(std::ceil(kTangentSpanM / std::max(step, 1e-6F))), 1,
                           kMaxTangentColumns);
  const auto near_cell = [&](int r, int c, std::size_t& out) {
    if (r < 0 || r >= scan.rings()) return false;
    out = scan.index(r, ((c % columns) + columns) % columns);
    return points.usable(out) && std::abs(scan.range_m(out) - range) < 0.3F * range;
  };
  std::size_t a = 0, b = 0, up = 0;
  if (!near_cell(ring, column - k, a) || !near_cell(ring, column + k, b)) return false;
  if (!near_cell(ring + 1, column, up) && !near_cell(ring - 1, column, up)) return false;
  const Eigen::Vector3f along = points.point(b) - points.point(a);
  const Eigen::Vector3f across = points.point(up) - points.point(cell);
  normal = along.cross(across);
  const float norm = normal.norm();
  if (!(norm > 1e-9F)) return false;
  normal /= norm;
  return true;
}

// Fraction of the motion that compensates a column fired t_ns after the scan stamp.
double column_share(std::int64_t t_ns, std::int64_t stamp_ns, double motion_duration_s) {
  return 1e-9 * static_cast<double>(t_ns - stamp_ns) / motion_duration_s;
}

// The motion scaled by s as the float rotation and translation applied to a column's points.
void column_motion(const Eigen::AngleAxisd& aa, const Eigen::Vector3d& translation, double s,
                   Eigen::Matrix3f& rotation_out, Eigen::Vector3f& translation_out) {
  rotation_out = Eigen::AngleAxisd(aa.angle() * s, aa.axis()).toRotationMatrix().cast<float>();
  translation_out = (s * translation).cast<float>();
}

// Per-column rotations and translations of one compensation, as columns of a table (twelve
// arrays of `columns` floats: r00 r01 r02 r10 ... r22 t0 t1 t2), so that the per-cell loop runs
// along a ring with every coefficient contiguous and SSE2 moves four cells at a time. Columns
// that do not move get no entry (moves[c] == 0); the loop recomputes them and they are restored.
struct ColumnTable {
  std::vector<float> coefficients;  // 12 x columns
  std::vector<std::uint8_t> moves;
  [[nodiscard]] const float* row(int k, int columns) const {
    return coefficients.data() + static_cast<std::size_t>(k) * static_cast<std::size_t>(columns);
  }
};

// The table of deskew_constant_velocity(scan, motion, duration): false when it moves nothing.
bool column_table(const core::OrganizedScan& scan, const Eigen::Isometry3d& motion,
                  double motion_duration_s, ColumnTable& table) {
  const int columns = scan.columns();
  const auto n = static_cast<std::size_t>(columns);
  table.moves.assign(n, 0);
  if (!(motion_duration_s > 0) || scan.column_stamp_ns.size() != n) return false;
  table.coefficients.resize(12 * n);  // every entry is written below (no fill first)
  const Eigen::AngleAxisd aa(motion.linear());
  bool any = false;
  for (std::size_t c = 0; c < n; ++c) {
    const std::int64_t t = scan.column_stamp_ns[c];
    if (t == scan.stamp_ns) {
      // Not moved: zeros keep the loop's arithmetic defined; the caller restores these cells.
      for (std::size_t k = 0; k < 12; ++k) table.coefficients[k * n + c] = 0.0F;
      continue;
    }
    Eigen::Matrix3f rotation;
    Eigen::Vector3f translation;
    column_motion(aa, motion.translation(), column_share(t, scan.stamp_ns, motion_duration_s),
                  rotation, translation);
    for (int k = 0; k < 9; ++k)
      table.coefficients[static_cast<std::size_t>(k) * n + c] = rotation(k / 3, k % 3);
    for (int k = 0; k < 3; ++k)
      table.coefficients[static_cast<std::size_t>(9 + k) * n + c] = translation(k);
    table.moves[c] = 1;
    any = true;
  }
  return any;
}

// Applies the table to one ring's cells: out = R p + t with the sums as Eigen's 3 x 3 product
// forms them, m0 p0 + (m1 p1 + m2 p2), then + t (tests compare with deskew_constant_velocity
// bit for bit). Columns the table does not move are left to the caller.
void apply_table(const ColumnTable& table, int columns, const float* __restrict xs,
                 const float* __restrict ys, const float* __restrict zs, float* __restrict ox,
                 float* __restrict oy, float* __restrict oz) {
  const float* __restrict r00 = table.row(0, columns);
  const float* __restrict r01 = table.row(1, columns);
  const float* __restrict r02 = table.row(2, columns);
  const float* __restrict r10 = table.row(3, columns);
  const float* __restrict r11 = table.row(4, columns);
  const float* __restrict r12 = table.row(5, columns);
  const float* __restrict r20 = table.row(6, columns);
  const float* __restrict r21 = table.row(7, columns);
  const float* __restrict r22 = table.row(8, columns);
  const float* __restrict t0 = table.row(9, columns);
  const float* __restrict t1 = table.row(10, columns);
  const float* __restrict t2 = table.row(11, columns);
  for (int c = 0; c < columns; ++c) {
    const float x = xs[c], y = ys[c], z = zs[c];
    ox[c] = (r00[c] * x + (r01[c] * y + r02[c] * z)) + t0[c];
    oy[c] = (r10[c] * x + (r11[c] * y + r12[c] * z)) + t1[c];
    oz[c] = (r20[c] * x + (r21[c] * y + r22[c] * z)) + t2[c];
  }
}

}  // namespace

Eigen::Isometry3d scale_motion(const Eigen::Isometry3d& motion, double s) {
  const Eigen::AngleAxisd aa(motion.linear());
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::AngleAxisd(aa.angle() * s, aa.axis()).toRotationMatrix();
  out.translation() = s * motion.translation();
  return out;
}

void deskew_constant_velocity(core::OrganizedScan& scan, const Eigen::Isometry3d& motion,
                              double motion_duration_s) {
  const int columns = scan.columns();
  if (!(motion_duration_s > 0) || scan.column_stamp_ns.size() != static_cast<std::size_t>(columns))
    return;
  // The reference of ScanCompensation (tests compare them bit for bit): a setter call per cell.
  const Eigen::AngleAxisd aa(motion.linear());
  for (int c = 0; c < columns; ++c) {
    const std::int64_t t = scan.column_stamp_ns[static_cast<std::size_t>(c)];
    if (t == scan.stamp_ns) continue;
    Eigen::Matrix3f rotation;
    Eigen::Vector3f translation;
    column_motion(aa, motion.translation(), column_share(t, scan.stamp_ns, motion_duration_s),
                  rotation, translation);
    for (int r = 0; r < scan.rings(); ++r) {
      const std::size_t i = scan.index(r, c);
      if (!scan.valid(i)) continue;
      scan.set_return(r, c, scan.range_m(i), scan.intensity(i),
                      rotation * scan.point(i) + translation);
    }
  }
}

void ScanCompensation::compensate(const core::OrganizedScan& scan, const Eigen::Isometry3d& motion,
                                  double motion_duration_s) {
  const std::size_t n = scan.size();
  const auto& xs = scan.xs();
  const auto& ys = scan.ys();
  const auto& zs = scan.zs();
  x_.resize(n);
  y_.resize(n);
  z_.resize(n);
  usable_.resize(n);
  const int columns = scan.columns();
  const auto width = static_cast<std::size_t>(columns);
  ColumnTable table;
  if (column_table(scan, motion, motion_duration_s, table)) {
    // Ring by ring, every cell (invalid ones hold NaN and stay unread: no branch in the loop),
    // then the columns that do not move get their points back as measured.
    for (int r = 0; r < scan.rings(); ++r) {
      const std::size_t row = scan.index(r, 0);
      apply_table(table, columns, xs.data() + row, ys.data() + row, zs.data() + row,
                  x_.data() + row, y_.data() + row, z_.data() + row);
      for (std::size_t c = 0; c < width; ++c) {
        if (table.moves[c] != 0) continue;
        x_[row + c] = xs[row + c];
        y_[row + c] = ys[row + c];
        z_[row + c] = zs[row + c];
      }
    }
  } else {
    std::copy(xs.begin(), xs.end(), x_.begin());
    std::copy(ys.begin(), ys.end(), y_.begin());
    std::copy(zs.begin(), zs.end(), z_.begin());
  }
  moved_ = std::move(table.moves);
  // A setter would have made a non-finite compensated point invalid. v - v is 0 exactly for a
  // finite v (NaN otherwise): std::isfinite without a branch.
  const auto& status = scan.statuses();
  for (std::size_t i = 0; i < n; ++i) {
    const bool finite =
        (x_[i] - x_[i]) == 0.0F && (y_[i] - y_[i]) == 0.0F && (z_[i] - z_[i]) == 0.0F;
    usable_[i] = static_cast<std::uint8_t>(status[i] == core::ReturnStatus::kValid && finite);
  }
}

void ScanCompensation::write(core::OrganizedScan& scan, const Eigen::Isometry3d& motion,
                             double motion_duration_s) const {
  const int columns = scan.columns();
  const auto width = static_cast<std::size_t>(columns);
  ColumnTable table;
  const bool again = column_table(scan, motion, motion_duration_s, table);
  std::vector<float> row_x(width), row_y(width), row_z(width);
  for (int r = 0; r < scan.rings(); ++r) {
    const std::size_t row = scan.index(r, 0);
    if (again) {
      apply_table(table, columns, x_.data() + row, y_.data() + row, z_.data() + row, row_x.data(),
                  row_y.data(), row_z.data());
    }
    for (std::size_t c = 0; c < width; ++c) {
      const bool second = again && table.moves[c] != 0;
      if (!second && moved_[c] == 0) continue;  // as measured
      const std::size_t i = row + c;
      if (!scan.valid(i)) continue;
      const Eigen::Vector3f p = second ? Eigen::Vector3f(row_x[c], row_y[c], row_z[c]) : point(i);
      scan.set_return(r, static_cast<int>(c), scan.range_m(i), scan.intensity(i), p);
    }
  }
}

Odometry::Odometry(const core::OdometryConfig& config, const Eigen::Isometry3d& start)
    : config_(config), start_(start), map_(config.voxel_size_m, config.max_points_per_voxel) {
  if (!(config.min_range_m < config.max_range_m)) {
    throw core::ConfigError("odometry.min_range_m must be below odometry.max_range_m");
  }
}

Eigen::Isometry3d Odometry::predict(double dt_s) const {
  if (!(motion_dt_s_ > 0)) return last_pose_;
  return last_pose_ * scale_motion(motion_, dt_s / motion_dt_s_);
}

double Odometry::correspondence_threshold() const {
  // Until a velocity is known the prediction may be off by a whole scan's motion: search the
  // 27 voxels around each point. Afterwards three standard deviations of the past prediction
  // errors, within the 2x2x2 block (half a voxel) that keeps the search cheap.
  if (!(motion_dt_s_ > 0)) return config_.voxel_size_m;
  const double sigma = error_samples_ == 0
                           ? config_.initial_threshold_m
                           : std::sqrt(error_sse_ / static_cast<double>(error_samples_));
  return std::clamp(3.0 * sigma, std::min(config_.min_threshold_m, 0.5 * config_.voxel_size_m),
                    0.5 * config_.voxel_size_m);
}

void Odometry::update_threshold(const Eigen::Isometry3d& predicted,
                                const Eigen::Isometry3d& estimated) {
  // How far the prediction was off, as the largest displacement of a point at max range.
  const Eigen::Isometry3d deviation = predicted.inverse() * estimated;
  const double angle = Eigen::AngleAxisd(deviation.linear()).angle();
  const double error =
      2.0 * config_.max_range_m * std::sin(0.5 * angle) + deviation.translation().norm();
  if (error > config_.min_motion_m) {
    error_sse_ += error * error;
    ++error_samples_;
  }
}

void Odometry::select_points(const core::OrganizedScan& scan, const Eigen::Isometry3d& predicted,
                             std::span<const core::Box3> excluded, OdometryResult& result) {
  frame_.clear();
  frame_time_s_.clear();
  frame_cells_.clear();
  const int columns = scan.columns();
  column_time_s_.assign(static_cast<std::size_t>(columns), 0.0F);
  if (scan.column_stamp_ns.size() == static_cast<std::size_t>(columns)) {
    for (std::size_t c = 0; c < column_time_s_.size(); ++c) {
      column_time_s_[c] =
          static_cast<float>(1e-9 * static_cast<double>(scan.column_stamp_ns[c] - scan.stamp_ns));
    }
  }
  frame_keys_.clear(scan.size() / 4);
  const auto inv_frame = static_cast<float>(1.0 / config_.map_spacing_m);
  const Eigen::Isometry3f to_world = predicted.cast<float>();
  const auto& ranges = scan.ranges();
  for (int r = 0; r < scan.rings(); ++r) {
    // Neighbouring columns mostly fall into the same frame cube (3.5 cm apart at 10 m): the
    // key of the last point asked is in the set already, so the hash needs no asking.
    VoxelKey last_key = ~VoxelKey{0};
    for (int c = 0; c < columns; ++c) {
      const std::size_t i = scan.index(r, c);
      if (!compensation_.usable(i)) continue;
      const float range = ranges[i];
      if (range < config_.min_range_m || range > config_.max_range_m) continue;
      const Eigen::Vector3f p = compensation_.point(i);
      const VoxelKey key = voxel_key(p, inv_frame);
      if (key == last_key) continue;
      last_key = key;
      if (!frame_keys_.insert(key)) continue;
      if (!excluded.empty() && inside_any(to_world * p, excluded)) {
        ++result.excluded_points;
        continue;
      }
      frame_.push_back(p);
      frame_time_s_.push_back(column_time_s_[static_cast<std::size_t>(c)]);
      frame_cells_.push_back(static_cast<std::uint32_t>(i));
    }
  }
  // The source grid is coarser: a point new to it is new to the finer frame grid too when the
  // edges divide (the defaults), and nearly always otherwise, so it samples the frame points.
  // A hall or a small room leaves a few dozen points in a grid made for outdoor ranges, and
  // registration on them wobbled: on the moving hall 75 points a scan, 0.33 degrees of tilt and
  // 0.2 of yaw error on average, tracks of people lost (docs/odometry.md, "Small scenes"). Outdoors
  // the grid holds hundreds to thousands.
  double voxel = config_.source_voxel_m;
  sample_source(voxel);
  while (source_.size() < static_cast<std::size_t>(config_.min_source_points) &&
         voxel > config_.map_spacing_m) {
    voxel = std::max(0.5 * voxel, config_.map_spacing_m);
    sample_source(voxel);
  }
  result.source_points = source_.size();
}

void Odometry::sample_source(double voxel_m) {
  source_.clear();
  source_time_s_.clear();
  source_cells_.clear();
  source_keys_.clear(frame_.size() / 4);
  const auto inv_source = static_cast<float>(1.0 / voxel_m);
  for (std::size_t k = 0; k < frame_.size(); ++k) {
    if (!source_keys_.insert(voxel_key(frame_[k], inv_source))) continue;
    source_.push_back(frame_[k]);
    source_time_s_.push_back(frame_time_s_[k]);
    source_cells_.push_back(frame_cells_[k]);
  }
}

void Odometry::compute_normals(const core::OrganizedScan& scan) {
  source_normals_.assign(source_cells_.size(), Eigen::Vector3f::Zero());
  valid_normals_.clear();
  for (std::size_t k = 0; k < source_cells_.size(); ++k) {
    if (grid_normal(scan, compensation_, source_cells_[k], source_normals_[k])) {
      valid_normals_.push_back(source_normals_[k]);
    } else {
      source_normals_[k].setZero();
    }
  }
}

void Odometry::insert_pending(const Eigen::Isometry3d& actual, double actual_dt_s) {
  if (pending_.empty()) return;
  if (config_.deskew && actual_dt_s > 0) {
    // The pending scan was compensated with the motion known when it was registered; now that
    // the next pose is known, its true motion over its own revolution is: correct to first order
    // (the difference is a fraction of a degree and centimetres).
    const Eigen::Isometry3d used =
        pending_used_dt_s_ > 0 ? scale_motion(pending_used_, actual_dt_s / pending_used_dt_s_)
                               : Eigen::Isometry3d::Identity();
    const Eigen::Isometry3d correction = actual * used.inverse();
    const Eigen::AngleAxisd aa(correction.linear());
    const Eigen::Vector3f w = (aa.angle() * aa.axis() / actual_dt_s).cast<float>();
    const Eigen::Vector3f v = (correction.translation() / actual_dt_s).cast<float>();
    for (std::size_t k = 0; k < pending_.size(); ++k) {
      pending_[k] += pending_time_s_[k] * (w.cross(pending_[k]) + v);
    }
  }
  const Eigen::Isometry3f to_world = pending_pose_.cast<float>();
  for (auto& p : pending_) p = to_world * p;
  map_.insert(pending_);
  pending_.clear();
}

void Odometry::commit(const Eigen::Isometry3d& pose, std::int64_t stamp_ns, double dt_s) {
  if (scans_ > 0) {
    const Eigen::Isometry3d before = motion_;
    const double before_dt_s = motion_dt_s_;
    motion_ = last_pose_.inverse() * pose;
    motion_dt_s_ = 1e-9 * static_cast<double>(stamp_ns - last_stamp_ns_);
    // How the motion changed from one interval to the next (the acceleration): unknown after a
    // velocity reset (the motion before is the assumed stop, not a measurement).
    change_known_ = before_dt_s > 0 && !velocity_reset_;
    if (change_known_) {
      change_ = scale_motion(before, motion_dt_s_ / before_dt_s).inverse() * motion_;
    }
    velocity_reset_ = false;
  }
  insert_pending(motion_, motion_dt_s_);
  last_pose_ = pose;
  last_stamp_ns_ = stamp_ns;
  ++scans_;
  // This scan enters the map once the next one has been registered (see insert_pending), unless
  // the map is empty or young: the next scan needs enough to register against.
  if (scans_ == 1 && config_.deskew) {  // kept until the first velocity is known
    first_frame_ = frame_;
    first_time_s_ = frame_time_s_;
  }
  pending_.swap(frame_);
  pending_time_s_.swap(frame_time_s_);
  pending_pose_ = pose;
  pending_used_ = applied_;
  pending_used_dt_s_ = dt_s;
  if (map_.voxel_count() == 0 || scans_ <= kEarlyScans) {
    insert_pending(Eigen::Isometry3d::Identity(), 0.0);
  }
  const Eigen::Vector3f here = pose.translation().cast<float>();
  // Cropping walks every voxel: only after the sensor moved a twentieth of the radius.
  if ((here - last_crop_).norm() > 0.05 * config_.map_radius_m) {
    map_.crop(here, config_.map_radius_m);
    last_crop_ = here;
  }
}

bool Odometry::register_scan(const Eigen::Isometry3d& predicted, int max_iterations,
                             OdometryResult& result, Eigen::Isometry3d& estimate) {
  IcpSettings settings;
  settings.max_distance_m = correspondence_threshold();
  settings.kernel_scale_m = settings.max_distance_m / 3.0;
  settings.max_iterations = max_iterations;
  settings.convergence = config_.convergence_m;
  settings.point_to_plane = config_.residual == core::OdometryResidual::kPointToPlane;
  if (!neighbours_ready_ || neighbours_.max_distance_m() != settings.max_distance_m) {
    neighbours_.reset(map_, settings.max_distance_m, source_.size());
    neighbours_ready_ = true;
  }
  const IcpResult icp =
      register_points(source_, map_, predicted, settings, source_normals_, &neighbours_);
  result.iterations += icp.iterations;
  result.correspondences = icp.correspondences;
  result.threshold_m = settings.max_distance_m;
  result.registered = icp.correspondences >= kMinCorrespondences;
  if (result.registered) estimate = icp.world_T_sensor;
  return icp.converged;
}

Eigen::Isometry3d Odometry::forward_motion(const Eigen::Isometry3d& implied, double dt_s) const {
  // The columns fire after the stamp, during the interval to the *next* scan, but the motion
  // known is the one since the last scan: on a platform whose turn rate changes (a MAV banking
  // into a figure 8, 30 degrees/s within a second) it lags by a whole revolution, and the
  // compensation error (tenths of a degree) biases the roll and pitch of every estimate and of
  // the map (docs/odometry.md, "Tilt"). The change between the last two intervals, scaled by
  // the configured share (a full one amplifies the estimates' noise until they run away),
  // extrapolates the motion over the scan's own revolution. The change is one interval old and
  // fixed during a scan's passes, so the passes' fixed point stays as stable as before.
  const double share = config_.deskew_acceleration;
  if (!(share > 0) || !change_known_ || !(motion_dt_s_ > 0)) return implied;
  // Over an interval the change grows with the square of its length (acceleration x time^2).
  const double ratio = dt_s / motion_dt_s_;
  return implied * scale_motion(change_, share * ratio * ratio);
}

double Odometry::deskew_correction_m(const Eigen::Isometry3d& estimate, double dt_s) const {
  const Eigen::Isometry3d change =
      forward_motion(last_pose_.inverse() * estimate, dt_s) * applied_.inverse();
  return change.translation().norm() + kLeverM * Eigen::AngleAxisd(change.linear()).angle();
}

void Odometry::refine_deskew(const Eigen::Isometry3d& estimate, double dt_s) {
  // The motion the scan was compensated with (over this scan's interval) and the one its
  // estimate implies (extrapolated over the scan's own revolution: forward_motion); the
  // difference is applied on top.
  const Eigen::Isometry3d implied = last_pose_.inverse() * estimate;
  const Eigen::Isometry3d forward = forward_motion(implied, dt_s);
  const Eigen::Isometry3d correction = forward * applied_.inverse();
  applied_ = forward;
  // The selected points, to first order (the correction is small): cheaper than compensating
  // the whole scan again and selecting them anew (the scan itself is compensated once, after the
  // last pass).
  const Eigen::AngleAxisd aa(correction.linear());
  const Eigen::Vector3f w = (aa.angle() * aa.axis() / dt_s).cast<float>();
  const Eigen::Vector3f v = (correction.translation() / dt_s).cast<float>();
  for (std::size_t k = 0; k < frame_.size(); ++k) {
    frame_[k] += frame_time_s_[k] * (w.cross(frame_[k]) + v);
  }
  for (std::size_t k = 0; k < source_.size(); ++k) {
    source_[k] += source_time_s_[k] * (w.cross(source_[k]) + v);
  }
  if (scans_ == 1 && !first_frame_.empty()) restart_map(implied, dt_s);
}

void Odometry::refine_passes(core::OrganizedScan& scan, double dt_s, bool converged,
                             OdometryResult& result, Eigen::Isometry3d& estimate) {
  // Compensated with the motion its estimate implies, the scan is registered again from there
  // while that moves the points noticeably: the velocity of the scan before lags too much on a
  // turning MAV or a shaking hand.
  const Eigen::Isometry3d scan_applied = applied_;
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    const bool changed = deskew_correction_m(estimate, dt_s) > kSecondPassShiftM;
    refine_deskew(estimate, dt_s);
    if (!changed && converged) break;
    OdometryResult again = result;
    again.iterations = 0;
    Eigen::Isometry3d refined = estimate;
    const bool capped = pass + 1 < kMaxPasses && scans_ >= kFullPassScans;
    converged = register_scan(estimate,
                              capped ? std::min(kIntermediatePassIterations, config_.max_iterations)
                                     : config_.max_iterations,
                              again, refined);
    if (!again.registered) break;
    estimate = refined;
    result.iterations += again.iterations;
    result.correspondences = again.correspondences;
  }
  compensation_.write(scan, applied_ * scan_applied.inverse(), dt_s);
}

void Odometry::restart_map(const Eigen::Isometry3d& first_motion, double dt_s) {
  // The first scan entered the map uncompensated (no velocity was known then): rebuild the map
  // from it compensated with the motion now known, so that the second pass, and every scan after,
  // registers against a consistent start (else its skew stays in the map as a tilt).
  map_.clear();
  neighbours_ready_ = false;
  const Eigen::AngleAxisd aa(first_motion.linear());
  const Eigen::Vector3f w = (aa.angle() * aa.axis() / dt_s).cast<float>();
  const Eigen::Vector3f v = (first_motion.translation() / dt_s).cast<float>();
  const Eigen::Isometry3f to_world = last_pose_.cast<float>();
  for (std::size_t k = 0; k < first_frame_.size(); ++k) {
    const Eigen::Vector3f& p = first_frame_[k];
    first_frame_[k] = to_world * (p + first_time_s_[k] * (w.cross(p) + v));
  }
  map_.insert(first_frame_);
  first_frame_.clear();
  first_frame_.shrink_to_fit();
}

OdometryResult Odometry::process(core::OrganizedScan& scan, std::span<const core::Box3> excluded) {
  if (scans_ > 0 && scan.stamp_ns <= last_stamp_ns_) {
    throw core::InputError("odometry: scan stamp " + std::to_string(scan.stamp_ns) +
                           " ns is not later than the previous scan's " +
                           std::to_string(last_stamp_ns_) + " ns");
  }
  OdometryResult result;
  const double dt_s =
      scans_ == 0 ? 0.0 : 1e-9 * static_cast<double>(scan.stamp_ns - last_stamp_ns_);
  const Eigen::Isometry3d predicted = scans_ == 0 ? start_ : predict(dt_s);
  applied_ = Eigen::Isometry3d::Identity();
  neighbours_ready_ = false;  // new points, and the map changed since
  // The scan is compensated with the prediction into compensation_, and written once at the end
  // with what the passes add on top.
  const bool compensated = config_.deskew && motion_dt_s_ > 0;
  if (compensated) {
    compensation_.compensate(scan, motion_, motion_dt_s_);
    applied_ = scale_motion(motion_, dt_s / motion_dt_s_);
  } else {
    compensation_.compensate(scan, Eigen::Isometry3d::Identity(), 0.0);
  }
  select_points(scan, predicted, excluded, result);
  compute_normals(scan);
  Eigen::Isometry3d estimate = predicted;
  bool converged = true;
  result.first = scans_ == 0;
  if (map_.voxel_count() == 0) {
    // The first scan (or the first with points) starts the map where the sensor is predicted.
    result.registered = !source_.empty();
  } else if (!source_.empty()) {
    // With compensation the first pass only needs to get near: a second one follows.
    converged =
        register_scan(predicted, config_.deskew ? kFirstPassIterations : config_.max_iterations,
                      result, estimate);
  }
  result.weakest_share = weakest_translation_share(valid_normals_);
  result.degenerate = !result.registered || result.weakest_share < config_.degeneracy_threshold;
  // Between the two thresholds the scan registers and its estimate stays as it is (a velocity
  // reset there broke a car park that registered well: ATE 0.06 -> 17 m), but the geometry that
  // holds one direction is thin, and where it was, unseen scenes slid by tens of metres along
  // it unflagged (docs/odometry.md, "Weak geometry").
  result.weak = !result.degenerate && result.weakest_share < config_.weak_share_threshold;
  const bool refine = result.registered && config_.deskew && scans_ > 0;
  if (refine) {
    refine_passes(scan, dt_s, converged, result, estimate);
  } else if (compensated) {
    compensation_.write(scan, Eigen::Isometry3d::Identity(), 0.0);
  }
  if (result.registered && scans_ > 0) update_threshold(predicted, estimate);
  // A scan that did not register keeps its prediction but adds nothing to the map.
  if (!result.registered) frame_.clear();
  commit(estimate, scan.stamp_ns, dt_s);
  // Where the scene does not fix the motion (a plain), the velocity learned from it would be
  // extrapolated scan after scan and run away: assume the sensor stops until geometry returns.
  if (result.degenerate) {
    motion_ = Eigen::Isometry3d::Identity();
    change_known_ = false;
    velocity_reset_ = true;
  }
  result.pose.stamp_ns = scan.stamp_ns;
  result.pose.translation = estimate.translation();
  result.pose.rotation = Eigen::Quaterniond(estimate.linear()).normalized();
  return result;
}

}  // namespace ringtrack::odometry
