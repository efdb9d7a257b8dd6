#include "ringtrack/core/visibility.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <string>
#include <utility>

#include "ringtrack/core/error.hpp"

namespace ringtrack::core {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
// Angular slack when choosing candidate beams for a box: the exact slab test decides, so this
// only has to exceed the rounding of the bounds (~1e-15 rad).
constexpr double kSlackRad = 1e-9;

double wrap_two_pi(double a) {
  double w = std::fmod(a, kTwoPi);
  if (w < 0.0) w += kTwoPi;
  if (w >= kTwoPi) w -= kTwoPi;  // -1e-20 + 2 pi rounds to 2 pi
  return w;
}

Visibility classify(ReturnStatus status, double range_m, double entry_m, double exit_m,
                    double margin_m) {
  switch (status) {
    case ReturnStatus::kValid:
      if (range_m > exit_m + margin_m) return Visibility::kFree;
      if (range_m < entry_m - margin_m) return Visibility::kOccluded;
      return Visibility::kOccupied;
    case ReturnStatus::kNoReturn:
    case ReturnStatus::kTooFar:
      return Visibility::kNoReturn;
    case ReturnStatus::kTooClose:
      break;
  }
  return Visibility::kUnknown;
}

void check_margin(double margin_m) {
  if (!(margin_m >= 0.0) || !std::isfinite(margin_m)) {
    throw Error("visibility query: margin must be a finite number >= 0 m, got " +
                std::to_string(margin_m));
  }
}

// Slab test of the half-line o + t d (t >= 0) against [lo, hi]; entry/exit distances on a hit.
bool ray_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& lo,
             const Eigen::Vector3d& hi, double& entry, double& exit) {
  double t0 = 0.0;
  double t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (o[k] < lo[k] || o[k] > hi[k]) return false;
      continue;
    }
    const double inv = 1.0 / d[k];
    double a = (lo[k] - o[k]) * inv;
    double b = (hi[k] - o[k]) * inv;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
    if (t0 > t1) return false;
  }
  entry = t0;
  exit = t1;
  return true;
}

double segment_distance_xy(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector2d pa = a.head<2>();
  const Eigen::Vector2d ab = b.head<2>() - pa;
  const double len2 = ab.squaredNorm();
  if (len2 == 0.0) return pa.norm();
  const double t = std::clamp(-pa.dot(ab) / len2, 0.0, 1.0);
  return (pa + t * ab).norm();
}

}  // namespace

const char* to_string(Visibility v) {
  switch (v) {
    case Visibility::kFree:
      return "free";
    case Visibility::kOccupied:
      return "occupied";
    case Visibility::kOccluded:
      return "occluded";
    case Visibility::kNoReturn:
      return "no_return";
    case Visibility::kUnknown:
      break;
  }
  return "unknown";
}

void VisibilityCounts::add(Visibility v) {
  switch (v) {
    case Visibility::kFree:
      ++free;
      break;
    case Visibility::kOccupied:
      ++occupied;
      break;
    case Visibility::kOccluded:
      ++occluded;
      break;
    case Visibility::kNoReturn:
      ++no_return;
      break;
    case Visibility::kUnknown:
      ++unknown;
      break;
  }
}

namespace {

// The scan must be one of the model's: its rings, one finite azimuth per column.
void check_scan_fits_model(const OrganizedScan& scan, const SensorModel& model) {
  model.validate();
  if (scan.rings() != model.rings() || scan.columns() <= 0) {
    throw InputError("visibility query: the scan has " + std::to_string(scan.rings()) + " x " +
                     std::to_string(scan.columns()) + " cells but sensor model '" + model.name +
                     "' has " + std::to_string(model.rings()) + " rings");
  }
  if (scan.column_azimuth_rad.size() != static_cast<std::size_t>(scan.columns())) {
    throw InputError("visibility query: the scan has " + std::to_string(scan.columns()) +
                     " columns but " + std::to_string(scan.column_azimuth_rad.size()) +
                     " column azimuths");
  }
  for (std::size_t c = 0; c < scan.column_azimuth_rad.size(); ++c) {
    if (!std::isfinite(scan.column_azimuth_rad[c])) {
      throw InputError("visibility query: column " + std::to_string(c) +
                       " has a non-finite azimuth");
    }
  }
}

}  // namespace

BeamGeometry::BeamGeometry(const OrganizedScan& scan, const SensorModel& model)
    : rings(scan.rings()), columns(scan.columns()), column_azimuth_rad(scan.column_azimuth_rad) {
  check_scan_fits_model(scan, model);
  set_rings(model);
  set_columns(scan, model);
}

void BeamGeometry::set_rings(const SensorModel& model) {
  // Rings: acceptance band of half the gap to each neighbour; a nominal (mean) gap at the ends.
  const auto nr = static_cast<std::size_t>(rings);
  elevation_rad = model.elevation_rad;
  offset_m = model.vertical_offset_m;
  az_offset_rad = model.azimuth_offset_rad;
  const double nominal_gap = rings > 1
                                 ? (elevation_rad.back() - elevation_rad.front()) / (rings - 1)
                                 : model.azimuth_step_rad();
  cos_el.resize(nr);
  sin_el.resize(nr);
  cos_az_off.resize(nr);
  sin_az_off.resize(nr);
  accept_below_rad.resize(nr);
  accept_above_rad.resize(nr);
  for (std::size_t r = 0; r < nr; ++r) {
    cos_el[r] = std::cos(elevation_rad[r]);
    sin_el[r] = std::sin(elevation_rad[r]);
    cos_az_off[r] = std::cos(az_offset_rad[r]);
    sin_az_off[r] = std::sin(az_offset_rad[r]);
    accept_below_rad[r] = 0.5 * (r == 0 ? nominal_gap : elevation_rad[r] - elevation_rad[r - 1]);
    accept_above_rad[r] =
        0.5 * (r + 1 == nr ? nominal_gap : elevation_rad[r + 1] - elevation_rad[r]);
  }
  max_abs_elevation_rad = std::max(std::abs(elevation_rad.front()), std::abs(elevation_rad.back()));
  offset_min_m = *std::min_element(offset_m.begin(), offset_m.end());
  offset_max_m = *std::max_element(offset_m.begin(), offset_m.end());
}

void BeamGeometry::set_columns(const OrganizedScan& scan, const SensorModel& model) {
  // Columns: sorted wrapped azimuths (any order or wrap of the capture), nominal step, buckets.
  const auto nc = static_cast<std::size_t>(columns);
  cos_az.resize(nc);
  sin_az.resize(nc);
  std::vector<std::pair<double, int>> order(nc);
  std::size_t smallest = 0;
  for (std::size_t c = 0; c < nc; ++c) {
    const double az = scan.column_azimuth_rad[c];
    cos_az[c] = std::cos(az);
    sin_az[c] = std::sin(az);
    order[c] = {wrap_two_pi(az), static_cast<int>(c)};
    if (order[c] < order[smallest]) smallest = c;
  }
  // A capture's azimuths ascend modulo 2 pi: starting at the smallest they are usually sorted
  // already, which saves the sort.
  std::rotate(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(smallest), order.end());
  if (!std::is_sorted(order.begin(), order.end())) std::sort(order.begin(), order.end());
  sorted_az.resize(nc);
  sorted_column.resize(nc);
  for (std::size_t i = 0; i < nc; ++i) {
    sorted_az[i] = order[i].first;
    sorted_column[i] = order[i].second;
  }
  if (nc > 1) {
    std::vector<double> gaps;
    gaps.reserve(nc);
    for (std::size_t i = 0; i < nc; ++i) {
      const double next = i + 1 < nc ? sorted_az[i + 1] : sorted_az[0] + kTwoPi;
      if (next - sorted_az[i] > 0.0) gaps.push_back(next - sorted_az[i]);
    }
    auto mid = gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2);
    std::nth_element(gaps.begin(), mid, gaps.end());
    nominal_step_rad = *mid;
  } else {
    nominal_step_rad = model.azimuth_step_rad();
  }
  const std::size_t buckets = 4 * nc;
  bucket.resize(buckets);
  std::size_t first = 0;  // lower bound of each bucket's start, found by one merge-like pass
  for (std::size_t b = 0; b < buckets; ++b) {
    const double start = kTwoPi * static_cast<double>(b) / static_cast<double>(buckets);
    while (first < nc && sorted_az[first] < start) ++first;
    bucket[b] = static_cast<int>(first);
  }
}

bool BeamGeometry::fits(const OrganizedScan& scan) const {
  return scan.rings() == rings && scan.column_azimuth_rad == column_azimuth_rad;
}

VisibilityQuery::VisibilityQuery(const OrganizedScan& scan, const SensorModel& model,
                                 const Pose& pose, const Motion& motion)
    : VisibilityQuery(scan, std::make_shared<const BeamGeometry>(scan, model), pose, motion) {}

VisibilityQuery::VisibilityQuery(const OrganizedScan& scan,
                                 std::shared_ptr<const BeamGeometry> geometry, const Pose& pose,
                                 const Motion& motion)
    : scan_(&scan), rings_(scan.rings()), columns_(scan.columns()), geo_(std::move(geometry)) {
  if (geo_ == nullptr || geo_->rings != rings_ || geo_->columns != columns_) {
    throw InputError("visibility query: the scan has " + std::to_string(rings_) + " x " +
                     std::to_string(columns_) + " cells, its beam geometry " +
                     (geo_ == nullptr
                          ? std::string("is missing")
                          : std::to_string(geo_->rings) + " x " + std::to_string(geo_->columns)));
  }
  if (!pose.translation.allFinite() || !pose.rotation.coeffs().allFinite() ||
      !(pose.rotation.norm() > 0.0)) {
    throw InputError("visibility query: the sensor pose at stamp " + std::to_string(pose.stamp_ns) +
                     " ns is not finite (translation or rotation holds NaN/inf, or a zero "
                     "quaternion)");
  }
  const Eigen::Isometry3d world_T_sensor = pose.isometry();
  world_R_sensor_ = world_T_sensor.linear();
  world_t_sensor_ = world_T_sensor.translation();
  sensor_R_world_ = world_R_sensor_.transpose();
  sensor_t_world_ = -(sensor_R_world_ * world_t_sensor_);
  set_motion(motion);
}

void VisibilityQuery::set_motion(const Motion& motion) {
  if (!motion.velocity_mps.allFinite() || !motion.angular_velocity_radps.allFinite()) {
    throw InputError("visibility query: the sensor motion of the scan at " +
                     std::to_string(scan_->stamp_ns) +
                     " ns is not finite (velocity or angular velocity holds NaN/inf)");
  }
  const auto& stamps = scan_->column_stamp_ns;
  if (motion.still() || stamps.size() != static_cast<std::size_t>(columns_)) return;
  double sweep_s = 0.0;
  for (const std::int64_t t : stamps) {
    sweep_s = std::max(sweep_s, std::abs(1e-9 * static_cast<double>(t - scan_->stamp_ns)));
  }
  // Every column at the scan's stamp; or stamps that are no revolution's (a scan built without
  // times keeps zeros): without times the columns cannot be placed on the path.
  constexpr double kLongestSweepS = 1.0;
  if (!(sweep_s > 0.0) || sweep_s > kLongestSweepS) return;
  moving_ = true;
  sweep_s_ = sweep_s;
  velocity_ = motion.velocity_mps;
  spin_rate_ = motion.angular_velocity_radps.norm();
  if (spin_rate_ > 0.0) {
    const Eigen::Vector3d axis = motion.angular_velocity_radps / spin_rate_;
    Eigen::Matrix3d k;
    k << 0.0, -axis.z(), axis.y(), axis.z(), 0.0, -axis.x(), -axis.y(), axis.x(), 0.0;
    spin_a_ = k * world_R_sensor_;
    spin_b_ = k * spin_a_;
  }
}

VisibilityQuery::Frame VisibilityQuery::column_frame(int column) const {
  if (!moving_) return {world_R_sensor_, world_t_sensor_};
  const double dt =
      1e-9 * static_cast<double>(scan_->column_stamp_ns[static_cast<std::size_t>(column)] -
                                 scan_->stamp_ns);
  const double a = spin_rate_ * dt;
  double sin_a = 0.0;
  double one_minus_cos_a = 0.0;
  if (std::abs(a) < 0.25) {
    // Series to the a^7 / a^8 terms (error below 1e-11 here): a turn within one revolution is
    // small, and this is cheaper than sin and cos for every beam of a box.
    const double a2 = a * a;
    sin_a = a * (1.0 - a2 / 6.0 * (1.0 - a2 / 20.0 * (1.0 - a2 / 42.0)));
    one_minus_cos_a = 0.5 * a2 * (1.0 - a2 / 12.0 * (1.0 - a2 / 30.0 * (1.0 - a2 / 56.0)));
  } else {
    sin_a = std::sin(a);
    one_minus_cos_a = 1.0 - std::cos(a);
  }
  return {world_R_sensor_ + sin_a * spin_a_ + one_minus_cos_a * spin_b_,
          world_t_sensor_ + dt * velocity_};
}

std::optional<int> VisibilityQuery::column_of_azimuth(double azimuth_rad) const {
  if (!std::isfinite(azimuth_rad)) return std::nullopt;
  const double a = wrap_two_pi(azimuth_rad);
  const int n = columns_;
  const auto nb = geo_->bucket.size();
  const auto b = std::min(nb - 1, static_cast<std::size_t>(a / kTwoPi * static_cast<double>(nb)));
  // j becomes the first sorted index whose azimuth exceeds a; the walks make the bucket's
  // rounding irrelevant, so this equals upper_bound.
  int j = geo_->bucket[b];
  while (j > 0 && geo_->sorted_az[static_cast<std::size_t>(j - 1)] > a) --j;
  while (j < n && geo_->sorted_az[static_cast<std::size_t>(j)] <= a) ++j;
  const int lo = j == 0 ? n - 1 : j - 1;
  const int hi = j == n ? 0 : j;
  const double az_lo = geo_->sorted_az[static_cast<std::size_t>(lo)] - (j == 0 ? kTwoPi : 0.0);
  const double az_hi = geo_->sorted_az[static_cast<std::size_t>(hi)] + (j == n ? kTwoPi : 0.0);
  const double below = a - az_lo;
  const double above = az_hi - a;
  int pick = -1;
  if (az_hi - az_lo <= 2.0 * geo_->nominal_step_rad) {
    pick = below <= above ? lo : hi;
  } else if (below <= 0.5 * geo_->nominal_step_rad) {
    pick = lo;  // a gap (dropped packets, partial revolution): half a step from its ends
  } else if (above <= 0.5 * geo_->nominal_step_rad) {
    pick = hi;
  }
  if (pick < 0) return std::nullopt;
  return geo_->sorted_column[static_cast<std::size_t>(pick)];
}

std::optional<int> VisibilityQuery::ring_of_sensor_point(const Eigen::Vector3d& p) const {
  if (!p.allFinite()) return std::nullopt;
  const double rho = std::hypot(p.x(), p.y());
  // Elevation seen from the middle beam origin bounds the elevation seen from every ring's
  // origin (at most half_spread away): only rings whose band meets that bound are evaluated.
  const double mid = 0.5 * (geo_->offset_min_m + geo_->offset_max_m);
  const double half_spread = 0.5 * (geo_->offset_max_m - geo_->offset_min_m);
  const double dist = std::hypot(rho, p.z() - mid);
  double lo_e = -std::numbers::pi;
  double hi_e = std::numbers::pi;
  if (dist > 2.0 * half_spread && dist > 0.0) {
    const double e = std::atan2(p.z() - mid, rho);
    const double delta = std::asin(half_spread / (dist - half_spread)) + kSlackRad;
    lo_e = e - delta;
    hi_e = e + delta;
  }
  int best = -1;
  double best_dev = std::numeric_limits<double>::infinity();
  for (int r = 0; r < rings_; ++r) {
    const auto i = static_cast<std::size_t>(r);
    if (geo_->elevation_rad[i] + geo_->accept_above_rad[i] < lo_e) continue;
    if (geo_->elevation_rad[i] - geo_->accept_below_rad[i] > hi_e) break;
    const double dz = p.z() - geo_->offset_m[i];
    if (rho == 0.0 && dz == 0.0) continue;  // the point is the beam origin
    const double dev = std::atan2(dz, rho) - geo_->elevation_rad[i];
    if (dev < -geo_->accept_below_rad[i] || dev > geo_->accept_above_rad[i]) continue;
    if (std::abs(dev) < best_dev) {
      best_dev = std::abs(dev);
      best = r;
    }
  }
  if (best < 0) return std::nullopt;
  return best;
}

std::optional<VisibilityQuery::Located> VisibilityQuery::locate(
    const Eigen::Vector3d& world_point) const {
  if (!moving_) return locate_sensor_point(sensor_R_world_ * world_point + sensor_t_world_);
  // The column the point falls in seen from the scan's pose, then from that column's pose, until
  // the column's own pose confirms it (within a column or so: the pose barely moves from one
  // column to the next). At the seam of a turning sensor no column may confirm it: a turn
  // against the spin leaves a wedge no beam swept, which is unknown.
  std::optional<Located> loc = locate_sensor_point(sensor_R_world_ * world_point + sensor_t_world_);
  const auto& stamps = scan_->column_stamp_ns;
  const double column_s = sweep_s_ / static_cast<double>(std::max(1, columns_ - 1));
  for (int step = 0; step < 4 && loc; ++step) {
    const Frame f = column_frame(loc->column);
    const auto next =
        locate_sensor_point(f.world_R_sensor.transpose() * (world_point - f.world_t_sensor));
    if (!next) return next;
    const double apart_s =
        1e-9 * std::abs(static_cast<double>(stamps[static_cast<std::size_t>(next->column)] -
                                            stamps[static_cast<std::size_t>(loc->column)]));
    if (apart_s <= 2.0 * column_s) return next;
    loc = next;
  }
  return std::nullopt;
}

std::optional<VisibilityQuery::Located> VisibilityQuery::locate_sensor_point(
    const Eigen::Vector3d& p) const {
  const auto ring = ring_of_sensor_point(p);
  if (!ring) return std::nullopt;
  const auto r = static_cast<std::size_t>(*ring);
  const auto column = column_of_azimuth(std::atan2(p.y(), p.x()) - geo_->az_offset_rad[r]);
  if (!column) return std::nullopt;
  return Located{*ring, *column, std::hypot(p.x(), p.y(), p.z() - geo_->offset_m[r])};
}

std::optional<std::size_t> VisibilityQuery::cell_of(const Eigen::Vector3d& world_point) const {
  const auto loc = locate(world_point);
  if (!loc) return std::nullopt;
  return scan_->index(loc->ring, loc->column);
}

std::optional<double> VisibilityQuery::beam_distance(const Eigen::Vector3d& world_point) const {
  const auto loc = locate(world_point);
  if (!loc) return std::nullopt;
  return loc->distance_m;
}

Visibility VisibilityQuery::at(const Eigen::Vector3d& world_point, double margin_m) const {
  check_margin(margin_m);
  const auto loc = locate(world_point);
  if (!loc) return Visibility::kUnknown;
  const auto i = scan_->index(loc->ring, loc->column);
  return classify(scan_->status(i), scan_->range_m(i), loc->distance_m, loc->distance_m, margin_m);
}

PointProbe VisibilityQuery::probe(const Eigen::Vector3d& world_point, double margin_m) const {
  check_margin(margin_m);
  const auto loc = locate(world_point);
  if (!loc) return {};
  const auto i = scan_->index(loc->ring, loc->column);
  const BeamRay ray = cell_ray(loc->ring, loc->column);
  const Eigen::Vector3d v = world_point - ray.origin;
  const Eigen::Vector3d to_beam = v.dot(ray.direction) * ray.direction - v;
  const bool returned = scan_->status(i) == ReturnStatus::kValid;
  return {classify(scan_->status(i), scan_->range_m(i), loc->distance_m, loc->distance_m, margin_m),
          to_beam.norm(), to_beam.z(), ray.direction.z(),
          returned ? scan_->range_m(i) - loc->distance_m : 0.0};
}

bool VisibilityQuery::sees_through(const Eigen::Vector3d& point, double margin_m, double lateral_m,
                                   double clearance_m) const {
  return sees_through(point, probe(point, margin_m), margin_m, lateral_m, clearance_m);
}

bool VisibilityQuery::sees_through(const Eigen::Vector3d& point, const PointProbe& p,
                                   double margin_m, double lateral_m, double clearance_m) const {
  if (p.visibility != Visibility::kFree || p.lateral_m > lateral_m) return false;
  // A descending beam that passes h above a point on the ground lands on the ground h / tan(its
  // depression) beyond it: at grazing angles that is metres, and the ground would be seen
  // "free" though nothing moved. Such a beam proves free space only when it ends farther.
  if (p.beam_direction_z < 0.0 && p.beam_above_m > 0.0) {
    const double sine = -p.beam_direction_z;
    const double run_per_drop = std::sqrt(std::max(0.0, 1.0 - sine * sine)) / sine;
    if (p.beyond_m <= margin_m + p.beam_above_m * run_per_drop) return false;
  }
  const Box3 around{(point.array() - clearance_m).cast<float>(),
                    (point.array() + clearance_m).cast<float>()};
  bool blocked = false;  // one beam ending inside or before the cube decides
  visit_box(around, margin_m, [&](std::size_t, Visibility v, double, double) {
    blocked = v == Visibility::kOccupied || v == Visibility::kOccluded;
    return !blocked;
  });
  return !blocked;
}

BeamRay VisibilityQuery::cell_ray(int ring, int column) const {
  const auto r = static_cast<std::size_t>(ring);
  const auto c = static_cast<std::size_t>(column);
  // cos/sin of (column azimuth + ring azimuth offset) by the angle-sum identities.
  const double ca = geo_->cos_az[c] * geo_->cos_az_off[r] - geo_->sin_az[c] * geo_->sin_az_off[r];
  const double sa = geo_->sin_az[c] * geo_->cos_az_off[r] + geo_->cos_az[c] * geo_->sin_az_off[r];
  const Eigen::Vector3d d(geo_->cos_el[r] * ca, geo_->cos_el[r] * sa, geo_->sin_el[r]);
  if (!moving_) {
    return {world_R_sensor_.col(2) * geo_->offset_m[r] + world_t_sensor_, world_R_sensor_ * d};
  }
  const Frame f = column_frame(column);
  return {f.world_R_sensor.col(2) * geo_->offset_m[r] + f.world_t_sensor, f.world_R_sensor * d};
}

VisibilityQuery::BeamBand VisibilityQuery::beam_band(const Box3& world_box) const {
  const Eigen::Vector3d lo = world_box.min.cast<double>();
  const Eigen::Vector3d hi = world_box.max.cast<double>();
  // A moving sensor's beams start up to `reach` from the scan pose's origin and point up to
  // `turn` away from its directions: candidates come from the box grown by the reach, in an
  // azimuth and elevation band widened by the turn; the exact slab test of visit_box decides.
  const double reach = moving_ ? velocity_.norm() * sweep_s_ : 0.0;
  const double turn = moving_ ? spin_rate_ * sweep_s_ : 0.0;
  const Eigen::Vector3d grown_lo = lo.array() - reach;
  const Eigen::Vector3d grown_hi = hi.array() + reach;

  // The box's corners in the sensor frame bound the beams that can reach it.
  std::array<Eigen::Vector3d, 8> corner;
  std::array<double, 8> corner_az{};
  double z_min = std::numeric_limits<double>::infinity();
  double z_max = -z_min;
  double rho_max = 0.0;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3d w((k & 1) ? grown_hi.x() : grown_lo.x(),
                            (k & 2) ? grown_hi.y() : grown_lo.y(),
                            (k & 4) ? grown_hi.z() : grown_lo.z());
    const auto ku = static_cast<std::size_t>(k);
    corner[ku] = sensor_R_world_ * w + sensor_t_world_;
    corner_az[ku] = wrap_two_pi(std::atan2(corner[ku].y(), corner[ku].x()));
    z_min = std::min(z_min, corner[ku].z());
    z_max = std::max(z_max, corner[ku].z());
    rho_max = std::max(rho_max, corner[ku].head<2>().norm());
  }
  // Azimuth span: the complement of the widest gap between corner azimuths. A widest gap of at
  // most pi means the sensor's z axis meets the box's footprint: every azimuth.
  std::array<double, 8> sorted = corner_az;
  std::sort(sorted.begin(), sorted.end());
  double widest = sorted[0] + kTwoPi - sorted[7];
  BeamBand band;
  band.az_start = sorted[0];
  for (std::size_t k = 0; k + 1 < 8; ++k) {
    if (sorted[k + 1] - sorted[k] > widest) {
      widest = sorted[k + 1] - sorted[k];
      band.az_start = sorted[k + 1];
    }
  }
  // A turn of `turn` moves a direction's azimuth by at most turn / cos(elevation) (small turns).
  const double steepest = geo_->max_abs_elevation_rad + turn;
  const double turn_az = turn == 0.0 ? 0.0 : 1.01 * turn / std::cos(std::min(steepest, 1.4));
  band.all_azimuths =
      widest <= std::numbers::pi || (turn > 0.0 && (steepest >= 1.4 || widest <= 2.0 * turn_az));
  band.az_start -= turn_az;
  band.az_span = kTwoPi - widest + 2.0 * turn_az;
  // Nearest horizontal distance of the box to the z axis: its footprint's boundary lies on the
  // projected edges.
  double rho_min = 0.0;
  if (!band.all_azimuths) {
    rho_min = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 8; ++k) {
      for (int bit : {1, 2, 4}) {
        if (k & bit) continue;
        rho_min = std::min(rho_min, segment_distance_xy(corner[static_cast<std::size_t>(k)],
                                                        corner[static_cast<std::size_t>(k | bit)]));
      }
    }
  }
  // Elevation band over every beam origin (the lowest origin sees the box highest).
  const double dz_hi = z_max - geo_->offset_min_m;
  const double dz_lo = z_min - geo_->offset_max_m;
  band.el_max = std::atan2(dz_hi, dz_hi > 0.0 ? rho_min : rho_max) + turn + kSlackRad;
  band.el_min = std::atan2(dz_lo, dz_lo < 0.0 ? rho_min : rho_max) - turn - kSlackRad;
  return band;
}

template <typename Visit>
void VisibilityQuery::visit_box(const Box3& world_box, double margin_m, Visit&& visit) const {
  check_margin(margin_m);
  if (world_box.empty() || !world_box.min.allFinite() || !world_box.max.allFinite()) return;
  const Eigen::Vector3d lo = world_box.min.cast<double>();
  const Eigen::Vector3d hi = world_box.max.cast<double>();
  const BeamBand band = beam_band(world_box);
  const bool all_azimuths = band.all_azimuths;
  const auto n = geo_->sorted_az.size();
  for (int r = 0; r < rings_; ++r) {
    const auto ri = static_cast<std::size_t>(r);
    if (geo_->elevation_rad[ri] < band.el_min) continue;
    if (geo_->elevation_rad[ri] > band.el_max) break;
    std::size_t first = 0;
    std::size_t count = n;
    double start = 0.0;
    double span = kTwoPi;
    if (!all_azimuths) {
      start = wrap_two_pi(band.az_start - geo_->az_offset_rad[ri] - kSlackRad);
      span = band.az_span + 2.0 * kSlackRad;
      first = static_cast<std::size_t>(
          std::lower_bound(geo_->sorted_az.begin(), geo_->sorted_az.end(), start) -
          geo_->sorted_az.begin());
    }
    for (std::size_t k = 0; k < count; ++k) {
      const std::size_t s = (first + k) % n;
      if (!all_azimuths) {
        double off = geo_->sorted_az[s] - start;
        if (off < 0.0) off += kTwoPi;
        if (off > span) break;
      }
      const int column = geo_->sorted_column[s];
      const BeamRay ray = cell_ray(r, column);
      double entry = 0.0;
      double exit = 0.0;
      if (!ray_box(ray.origin, ray.direction, lo, hi, entry, exit)) continue;
      const auto i = scan_->index(r, column);
      if (!visit(i, classify(scan_->status(i), scan_->range_m(i), entry, exit, margin_m), entry,
                 exit)) {
        return;
      }
    }
  }
}

VisibilityCounts VisibilityQuery::in_box(const Box3& world_box, double margin_m) const {
  VisibilityCounts counts;
  visit_box(world_box, margin_m, [&](std::size_t, Visibility v, double, double) {
    counts.add(v);
    return true;
  });
  return counts;
}

bool VisibilityQuery::seen_through_box(const Box3& world_box, double margin_m) const {
  bool free = false;
  bool blocked = false;
  visit_box(world_box, margin_m, [&](std::size_t, Visibility v, double, double) {
    blocked = v == Visibility::kOccupied || v == Visibility::kOccluded;
    free = free || v == Visibility::kFree;
    return !blocked;  // one beam ending inside or before the box decides
  });
  return free && !blocked;
}

void VisibilityQuery::cells_in_box(const Box3& world_box, double margin_m,
                                   std::vector<BoxBeam>& out) const {
  out.clear();
  visit_box(world_box, margin_m, [&](std::size_t i, Visibility v, double entry, double exit) {
    out.push_back({i, v, entry, exit});
    return true;
  });
}

}  // namespace ringtrack::core
