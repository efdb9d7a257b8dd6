#include "ringtrack/sim/simulator.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "ringtrack/core/error.hpp"

namespace ringtrack::sim {
namespace {

constexpr int kBins = 1024;
constexpr double kPi = std::numbers::pi;
constexpr double kBinWidth = 2.0 * kPi / kBins;

int bin_of(double azimuth_rad) {
  const int b = static_cast<int>((azimuth_rad + kPi) / kBinWidth);
  return std::clamp(b, 0, kBins - 1);
}

}  // namespace

Simulator::Simulator(Scenario scenario, std::uint64_t seed, std::optional<core::SensorModel> model)
    : scenario_((validate(scenario), std::move(scenario))),
      model_(model ? *model : core::SensorModel::by_name(scenario_.sensor.model)),
      world_(scenario_, seed),
      noise_rng_(Rng::derive(seed, 7)) {
  model_.validate();
  scenario_.ground.radius_m = scenario_.world_radius_m;
  prims_ = static_primitives(scenario_);
  static_count_ = prims_.size();
  velocity_.assign(world_.actors().size(), Eigen::Vector3d::Zero());
  const int rings = model_.rings(), cols = model_.columns();
  const double step = model_.azimuth_step_rad();
  sensor_dir_.resize(static_cast<std::size_t>(rings) * static_cast<std::size_t>(cols));
  for (int r = 0; r < rings; ++r) {
    const double el = model_.elevation_rad[static_cast<std::size_t>(r)];
    const std::size_t row = static_cast<std::size_t>(r) * static_cast<std::size_t>(cols);
    for (int c = 0; c < cols; ++c) {
      // Same geometry as SensorModel::point(): the ray starts at (0, 0, vertical offset).
      const double az = c * step + model_.azimuth_offset_rad[static_cast<std::size_t>(r)];
      sensor_dir_[row + static_cast<std::size_t>(c)] = {std::cos(el) * std::cos(az),
                                                        std::cos(el) * std::sin(az), std::sin(el)};
    }
  }
  bin_start_.assign(kBins + 1, 0);
}

std::int64_t Simulator::scan_count() const {
  return static_cast<std::int64_t>(std::floor(scenario_.duration_s * model_.scan_rate_hz + 1e-9));
}

std::int64_t Simulator::scan_stamp_ns(std::int64_t k) const {
  return static_cast<std::int64_t>(
      std::llround(static_cast<double>(k) * 1e9 / model_.scan_rate_hz));
}

core::Pose Simulator::sensor_pose_at(std::int64_t t_ns) const {
  return sensor_pose(scenario_.sensor, t_ns);
}

void Simulator::build_bins(const Eigen::Vector3d& ref, double sensor_sweep_m, double scan_s) {
  std::fill(bin_start_.begin(), bin_start_.end(), 0u);
  spans_.clear();
  all_around_.clear();
  for (std::size_t i = 0; i < prims_.size(); ++i) {
    const Primitive& p = prims_[i];
    // Any ray of this scan starts within sensor_sweep_m of ref, and a moving primitive stays
    // within |v| * scan / 2 of its mid-scan place: a ray can only hit p if the parallel ray from
    // ref passes the grown bounding circle (see docs/simulator.md).
    double r = p.bound_radius_xy + sensor_sweep_m + 0.02;
    if (p.mover >= 0)
      r += velocity_[static_cast<std::size_t>(p.mover)].head<2>().norm() * 0.5 * scan_s;
    const double dx = p.center.x() - ref.x(), dy = p.center.y() - ref.y();
    const double dist = std::hypot(dx, dy);
    if (dist <= r) {
      all_around_.push_back(static_cast<std::uint32_t>(i));
      continue;
    }
    const double half = std::asin(r / dist);
    const double az = std::atan2(dy, dx);
    int first = static_cast<int>(std::floor((az - half + kPi) / kBinWidth)) - 1;
    int last = static_cast<int>(std::floor((az + half + kPi) / kBinWidth)) + 1;
    if (last - first + 1 >= kBins) {
      all_around_.push_back(static_cast<std::uint32_t>(i));
      continue;
    }
    first = (first % kBins + kBins) % kBins;
    last = (last % kBins + kBins) % kBins;
    spans_.push_back({static_cast<std::uint32_t>(i), first, last});
    for (int b = first;; b = (b + 1) % kBins) {
      ++bin_start_[static_cast<std::size_t>(b) + 1];
      if (b == last) break;
    }
  }
  for (int b = 0; b < kBins; ++b)
    bin_start_[static_cast<std::size_t>(b) + 1] += bin_start_[static_cast<std::size_t>(b)];
  bin_items_.resize(bin_start_[kBins]);
  std::vector<std::uint32_t>& fill = bin_fill_;
  fill.assign(bin_start_.begin(), bin_start_.end() - 1);
  for (const Span& s : spans_) {
    for (int b = s.first;; b = (b + 1) % kBins) {
      bin_items_[fill[static_cast<std::size_t>(b)]++] = s.prim;
      if (b == s.last) break;
    }
  }
}

SimulatedScan Simulator::next() {
  SimulatedScan out;
  next(out);
  return out;
}

void Simulator::next(SimulatedScan& out) {
  const std::int64_t k = next_index_++;
  const std::int64_t t0 = scan_stamp_ns(k);
  const double scan_s = 1.0 / model_.scan_rate_hz;
  const std::int64_t t_mid = t0 + static_cast<std::int64_t>(std::llround(0.5 * scan_s * 1e9));

  out.index = k;
  out.scan = core::OrganizedScan(model_.rings(), model_.columns());
  out.scan.set_uniform_columns(model_, t0);
  out.labels.assign(out.scan.size(), 0u);
  out.pose = sensor_pose_at(t0);

  // Actors at mid-scan; each ray sees them shifted by their velocity to its own time.
  place_actors(t_mid);
  const double sweep = place_columns(out.scan, t_mid);
  if (use_bins_) build_bins(sensor_pose_at(t_mid).translation, sweep, scan_s);

  std::vector<ActorHits> hits(world_.actors().size());
  const double t_max = model_.max_range_m + std::max(0.5, 6.0 * scenario_.sensor.range_noise_m);
  for (int c = 0; c < model_.columns(); ++c) cast_column(c, t_mid, t_max, out, hits);
  collect_truth(hits, out);
}

void Simulator::place_actors(std::int64_t t_mid) {
  world_.advance_to(t_mid);
  const auto& actors = world_.actors();
  prims_.resize(static_count_);
  mid_states_.resize(actors.size());
  present_.resize(actors.size());
  for (std::size_t i = 0; i < actors.size(); ++i) {
    // Scripted actors exist only between their first and last waypoint (decided at mid-scan).
    present_[i] = static_cast<std::uint8_t>(world_.present(i, t_mid) ? 1 : 0);
    mid_states_[i] = world_.state_at(i, t_mid);
    velocity_[i] = present_[i] ? mid_states_[i].velocity_mps : Eigen::Vector3d::Zero();
    if (present_[i]) {
      append_body(actors[i], mid_states_[i], static_cast<std::int32_t>(i), prims_);
    }
  }
}

double Simulator::place_columns(const core::OrganizedScan& scan, std::int64_t t_mid) {
  // Sensor pose at every column's firing time: a moving sensor's scan is skewed like a real one.
  const int cols = model_.columns();
  col_rot_.resize(static_cast<std::size_t>(cols));
  col_pos_.resize(static_cast<std::size_t>(cols));
  const bool moving_sensor = scenario_.sensor.motion != SensorMotion::kStatic;
  for (int c = 0; c < cols; ++c) {
    const auto cu = static_cast<std::size_t>(c);
    if (!moving_sensor && c > 0) {
      col_rot_[cu] = col_rot_[0];
      col_pos_[cu] = col_pos_[0];
      continue;
    }
    const core::Pose p = sensor_pose_at(scan.column_stamp_ns[cu]);
    col_rot_[cu] = p.rotation.normalized().toRotationMatrix();
    col_pos_[cu] = p.translation;
  }
  const Eigen::Vector3d ref = sensor_pose_at(t_mid).translation;
  double sweep = 0.0;
  for (int c = 0; c < cols; ++c)
    sweep = std::max(sweep, (col_pos_[static_cast<std::size_t>(c)] - ref).norm());
  return sweep + 0.05;  // the rings' vertical offsets, rotated by the tilt
}

std::int64_t Simulator::nearest_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double dt,
                                    double& best) const {
  std::int64_t hit = -1;
  const auto test = [&](std::uint32_t i) {
    const Primitive& p = prims_[i];
    const double t =
        p.mover < 0
            ? intersect(p, o, d, 0.0, best)
            : intersect(p, o - velocity_[static_cast<std::size_t>(p.mover)] * dt, d, 0.0, best);
    if (t < best) {
      best = t;
      hit = static_cast<std::int64_t>(i);
    }
  };
  if (use_bins_) {
    for (const std::uint32_t i : all_around_) test(i);
    const auto b = static_cast<std::size_t>(bin_of(fast_atan2(d.y(), d.x())));
    for (std::uint32_t j = bin_start_[b]; j < bin_start_[b + 1]; ++j) test(bin_items_[j]);
  } else {
    for (std::uint32_t i = 0; i < prims_.size(); ++i) test(i);
  }
  return hit;
}

void Simulator::cast_column(int c, std::int64_t t_mid, double t_max, SimulatedScan& out,
                            std::vector<ActorHits>& hits) {
  const Ground& ground = scenario_.ground;
  const SensorSpec& spec = scenario_.sensor;
  const int cols = model_.columns();
  const auto cu = static_cast<std::size_t>(c);
  const double dt = static_cast<double>(out.scan.column_stamp_ns[cu] - t_mid) * 1e-9;
  const Eigen::Matrix3d& rot = col_rot_[cu];
  const Eigen::Vector3d& pos = col_pos_[cu];
  for (int r = 0; r < model_.rings(); ++r) {
    const Eigen::Vector3d d =
        rot * sensor_dir_[static_cast<std::size_t>(r) * static_cast<std::size_t>(cols) + cu];
    const Eigen::Vector3d o =
        pos + rot.col(2) * model_.vertical_offset_m[static_cast<std::size_t>(r)];
    double best = ground.intersect(o, d, 0.0, t_max);
    const std::int64_t hit = nearest_hit(o, d, dt, best);
    if (!std::isfinite(best)) continue;  // no echo: stays kNoReturn
    // One uniform and one normal draw per echo keep the random stream aligned across changes.
    const double u = noise_rng_.uniform();
    const double noise = noise_rng_.normal() * spec.range_noise_m;
    const double frac = best / model_.max_range_m;
    if (u < spec.dropout_probability + spec.far_dropout_probability * frac * frac) continue;
    const Eigen::Vector3d x = o + best * d;
    Eigen::Vector3d n;
    float refl;
    std::uint32_t label = 0;
    std::int32_t slot = -1;
    if (hit < 0) {
      n = ground.normal_at(x.x(), x.y());
      refl = ground.reflectivity;
    } else {
      const Primitive& p = prims_[static_cast<std::size_t>(hit)];
      const Eigen::Vector3d shift =
          p.mover < 0 ? Eigen::Vector3d::Zero()
                      : Eigen::Vector3d(velocity_[static_cast<std::size_t>(p.mover)] * dt);
      n = normal_at(p, x - shift);
      refl = p.reflectivity;
      label = p.label;
      slot = p.mover;
    }
    // Calibrated reflectivity (0-255) with a Lambertian factor and a mild fall-off with range.
    const double cos_inc = std::abs(n.dot(d));
    const double inten =
        255.0 * refl * (0.35 + 0.65 * cos_inc) / (1.0 + (best / 150.0) * (best / 150.0));
    const float intensity = static_cast<float>(std::round(std::clamp(inten, 0.0, 255.0)));
    out.scan.set_range(model_, r, c, static_cast<float>(best + noise), intensity);
    const std::size_t idx = out.scan.index(r, c);
    if (!out.scan.valid(idx)) continue;
    out.labels[idx] = label;
    if (slot >= 0) {
      ActorHits& a = hits[static_cast<std::size_t>(slot)];
      ++a.n;
      a.sum += x;
      a.sum_dt += dt;
      a.box.extend(x.cast<float>());
    }
  }
}

void Simulator::collect_truth(const std::vector<ActorHits>& hits, SimulatedScan& out) const {
  const auto& actors = world_.actors();
  const std::vector<ActorState>& mid = mid_states_;
  out.objects.clear();
  for (std::size_t i = 0; i < actors.size(); ++i) {
    if (!present_[i]) continue;  // absent actors have no ground truth
    ObjectTruth t;
    t.id = actors[i].id;
    t.object_class = actors[i].object_class;
    t.hit_points = hits[i].n;
    const double mean_dt = hits[i].n > 0 ? hits[i].sum_dt / hits[i].n : 0.0;
    if (hits[i].n > 0) {
      t.centroid_m = (hits[i].sum / hits[i].n).cast<float>();
      t.box = hits[i].box;
    }
    t.body_center_m =
        (body_center(actors[i], mid[i]) + mid[i].velocity_mps * mean_dt).cast<float>();
    t.velocity_mps = mid[i].velocity_mps.cast<float>();
    t.moving = mid[i].velocity_mps.norm() > 0.1;
    out.objects.push_back(t);
  }
  std::sort(out.objects.begin(), out.objects.end(),
            [](const ObjectTruth& a, const ObjectTruth& b) { return a.id < b.id; });
}

double cast_naive(const std::vector<Primitive>& prims, const Ground& ground,
                  const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max,
                  std::int64_t* hit_index) {
  double best = ground.intersect(o, d, 0.0, t_max);
  std::int64_t hit = -1;
  for (std::size_t i = 0; i < prims.size(); ++i) {
    const double t = intersect(prims[i], o, d, 0.0, best);
    if (t < best) {
      best = t;
      hit = static_cast<std::int64_t>(i);
    }
  }
  if (hit_index) *hit_index = hit;
  return best;
}

}  // namespace ringtrack::sim
