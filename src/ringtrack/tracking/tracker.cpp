#include "ringtrack/tracking/tracker.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "ringtrack/core/error.hpp"
#include "ringtrack/tracking/assignment.hpp"
#include "ringtrack/tracking/association_cost.hpp"

namespace ringtrack::tracking {
namespace {

constexpr double kKmhToMps = 1.0 / 3.6;
// Floor on the eigenvalues of the measurement noise: a detection whose points lie on a line or
// plane (one ring, one column) would otherwise have a singular covariance.
constexpr double kMinMeasurementVariance = 0.01 * 0.01;
constexpr double kInf = std::numeric_limits<double>::infinity();
// Points a hypothesis remembers of a detection for the free-space tests: enough to outvote a
// few edge beams, few enough that probing costs microseconds.
constexpr std::size_t kRememberedPoints = 16;
// A passer-by hides a standing person for about a second; a partial view that lasts longer is
// what the scan shows of the object now (it stands behind something), and is followed.
constexpr int kMaxHeldScans = 10;
// Detections of at most this many points get the few-point association covariance.
constexpr std::size_t kFewPoints = 2;

// What one scan says about a set of remembered points (moved by shift): the verdict of each
// point whose deciding beam passes within free_space_lateral_m of it.
core::VisibilityCounts probe_points(const core::VisibilityQuery& query,
                                    const core::TrackingConfig& config,
                                    const std::vector<Eigen::Vector3f>& points,
                                    const Eigen::Vector3d& shift) {
  core::VisibilityCounts counts;
  for (const auto& p : points) {
    const auto probe = query.probe(p.cast<double>() + shift, config.free_space_margin_m);
    if (probe.lateral_m <= config.free_space_lateral_m) counts.add(probe.visibility);
  }
  return counts;
}

// A beam without a return passed the point and met nothing (sky): as good as seen free.
int seen_free(const core::VisibilityCounts& c) {
  return c.free + c.no_return;
}

double max_eigenvalue(const Eigen::Matrix3d& m) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(m, Eigen::EigenvaluesOnly);
  return solver.eigenvalues().maxCoeff();
}

// The eigenvalue the deletion test compares. With a random-walk height the vertical variance
// measures the rings' spread, not whether the object is still where the track thinks: only the
// horizontal block decides then.
double deletion_eigenvalue(const core::TrackingConfig& config, Eigen::Matrix3d p) {
  if (config.vertical_motion == core::VerticalMotion::kConstantPosition) {
    p.row(2).setZero();
    p.col(2).setZero();
  }
  return max_eigenvalue(p);
}

// One prediction as the tracker does it (the vertical model included).
void predict_filter(const core::TrackingConfig& config, ConstantVelocityKalman& filter,
                    double dt_s) {
  filter.predict(dt_s, config.process_noise);
  if (config.vertical_motion == core::VerticalMotion::kConstantPosition) {
    filter.hold_vertical_velocity();
    filter.add_vertical_variance(config.vertical_position_noise * dt_s);
  }
}

bool footprints_intersect(const core::Box3& a, const core::Box3& b) {
  if (a.empty() || b.empty()) return true;  // nothing to compare: no evidence of motion
  return a.min.x() <= b.max.x() && b.min.x() <= a.max.x() && a.min.y() <= b.max.y() &&
         b.min.y() <= a.max.y();
}

// Vertical distance between two boxes' height ranges (0 when they overlap or one is empty).
double vertical_gap(const core::Box3& a, const core::Box3& b) {
  if (a.empty() || b.empty()) return 0.0;
  return std::max(
      0.0, static_cast<double>(std::max(a.min.z(), b.min.z()) - std::min(a.max.z(), b.max.z())));
}

Eigen::Matrix3d floored_covariance(const Eigen::Matrix3f& c, double scale) {
  Eigen::Matrix3d r = c.cast<double>();
  r = 0.5 * scale * (r + r.transpose()).eval();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(r);
  const Eigen::Vector3d values = solver.eigenvalues().cwiseMax(kMinMeasurementVariance);
  return solver.eigenvectors() * values.asDiagonal() * solver.eigenvectors().transpose();
}

// Cost of one pair under the configured rule from precomputed terms; +inf when a cheap lower
// bound already exceeds the gate. Lower bounds: for Bhattacharyya the log term is >= 0 (log det
// is concave) and m^T S^-1 m >= |m|^2 / trace(S); likewise for Mahalanobis.
double pair_cost_terms(const core::TrackingConfig& config, double gate, const GaussianTerm& h,
                       const GaussianTerm& d) {
  const Eigen::Vector3d m = h.mean - d.mean;
  const double m2 = m.squaredNorm();
  switch (config.cost) {
    case core::AssociationCost::kBhattacharyya:
      if (m2 > 4.0 * gate * (h.max_eig_bound + d.max_eig_bound)) return kInf;
      return bhattacharyya_distance(h, d);
    case core::AssociationCost::kMahalanobis: {
      if (m2 > gate * gate * (h.max_eig_bound + d.max_eig_bound)) return kInf;
      return std::sqrt(m.dot((h.covariance + d.covariance).inverse() * m));
    }
    case core::AssociationCost::kEuclidean:
      return std::sqrt(m2);
  }
  return kInf;
}

// Whether a detection lies behind the hypothesis' prediction along its motion, more along it
// than across it: the object slowed down or stopped, rather than something beside its path.
bool falls_behind(const Hypothesis& h, const core::Detection& d) {
  const Eigen::Vector2d v = h.filter.velocity().head<2>();
  const double speed = v.norm();
  if (speed == 0.0) return false;
  const Eigen::Vector2d e = d.centroid.cast<double>().head<2>() - h.position().head<2>();
  const double along = e.dot(v) / speed;
  const double across = std::abs(e.x() * v.y() - e.y() * v.x()) / speed;
  return along < 0.0 && across < -along;
}

// Removes the hypotheses whose flag is set, keeping the others' order (creation order, which
// the merge relies on); returns how many went.
int remove_flagged(std::vector<Hypothesis>& hypotheses, const std::vector<char>& flagged) {
  std::size_t k = 0;
  for (std::size_t j = 0; j < hypotheses.size(); ++j) {
    if (flagged[j]) continue;
    if (k != j) hypotheses[k] = std::move(hypotheses[j]);
    ++k;
  }
  const auto removed = static_cast<int>(hypotheses.size() - k);
  hypotheses.resize(k);
  return removed;
}

// A deleted hypothesis that was confirmed and had moved is kept aside: its id may yet continue
// in a hypothesis born near where it was lost (Tracker::relink).
void keep_if_lost(Hypothesis& h, const core::TrackingConfig& config,
                  std::vector<Hypothesis>& lost) {
  if (h.confirmed && h.ever_dynamic && config.relink_distance_m > 0.0) lost.push_back(std::move(h));
}

}  // namespace

Tracker::Tracker(const core::TrackingConfig& config)
    : config_(config),
      min_speed_mps_(config.min_speed_kmh * kKmhToMps),
      max_speed_mps_(config.max_speed_kmh * kKmhToMps) {}

void Tracker::reset() {
  hypotheses_.clear();
  lost_.clear();
  started_ = false;
  stats_ = {};
}

double Tracker::gate() const {
  switch (config_.cost) {
    case core::AssociationCost::kBhattacharyya:
      return config_.gate_bhattacharyya;
    case core::AssociationCost::kMahalanobis:
      return config_.gate_mahalanobis;
    case core::AssociationCost::kEuclidean:
      return config_.gate_euclidean_m;
  }
  return config_.gate_bhattacharyya;
}

Eigen::Matrix3d Tracker::measurement_covariance(const core::Detection& detection) const {
  Eigen::Matrix3d r =
      floored_covariance(detection.covariance, config_.measurement_covariance_scale);
  // One or two points (a far person's sparse or relaxed cluster) may be any part of the body:
  // their spread says nothing about where the object's centre is, and a tight covariance made
  // the gate reject them beside their own track, which then lost them to a new one.
  if (detection.indices.size() <= kFewPoints) {
    const double floor = config_.few_point_stddev_m * config_.few_point_stddev_m;
    r(0, 0) = std::max(r(0, 0), floor);
    r(1, 1) = std::max(r(1, 1), floor);
  }
  return r;
}

Eigen::Matrix3d Tracker::update_covariance(const core::Detection& detection) const {
  if (config_.centroid_noise_m <= 0.0) return measurement_covariance(detection);
  // The centroid of n points is known far better than the spread of the points: its standard
  // error is the spread over sqrt(n). What moves it beyond that (limb swing, a partial view) is
  // the centroid noise. The ground truth of the evaluation is a centroid too, so a filter fed
  // the point spread lagged behind it (docs/tracking.md, "Measurement noise").
  const double n = static_cast<double>(std::max<std::size_t>(1, detection.indices.size()));
  Eigen::Matrix3d r = detection.covariance.cast<double>() / n;
  r = 0.5 * (r + r.transpose()).eval();
  r.diagonal().array() += config_.centroid_noise_m * config_.centroid_noise_m;
  return floored_covariance(r.cast<float>(), 1.0);
}

double Tracker::pair_cost(const Hypothesis& hypothesis, const core::Detection& detection) const {
  return pair_cost_terms(
      config_, gate(), make_gaussian_term(hypothesis.position(), hypothesis.position_covariance()),
      make_gaussian_term(detection.centroid.cast<double>(), measurement_covariance(detection)));
}

std::vector<Eigen::Vector3f> Tracker::predicted_positions(std::int64_t stamp_ns) const {
  const double dt =
      started_ && stamp_ns > stamp_ns_ ? static_cast<double>(stamp_ns - stamp_ns_) * 1e-9 : 0.0;
  std::vector<Eigen::Vector3f> out;
  out.reserve(hypotheses_.size());
  for (const auto& h : hypotheses_) {
    out.push_back((h.filter.position() + dt * h.filter.velocity()).cast<float>());
  }
  return out;
}

const std::vector<Hypothesis>& Tracker::update(const std::vector<core::Detection>& detections,
                                               std::int64_t stamp_ns,
                                               const core::VisibilityQuery* visibility) {
  if (started_ && stamp_ns < stamp_ns_) {
    throw core::InputError("tracking: scan stamp " + std::to_string(stamp_ns) +
                           " ns precedes the previous scan's " + std::to_string(stamp_ns_) + " ns");
  }
  for (std::size_t i = 0; i < detections.size(); ++i) {
    if (!detections[i].centroid.allFinite() || !detections[i].covariance.allFinite()) {
      throw core::InputError("tracking: detection " + std::to_string(i) + " of the scan at " +
                             std::to_string(stamp_ns) +
                             " ns has a non-finite centroid or covariance");
    }
  }
  const double dt = started_ ? static_cast<double>(stamp_ns - stamp_ns_) * 1e-9 : 0.0;
  started_ = true;
  stamp_ns_ = stamp_ns;
  stats_ = {};
  visibility_ = visibility;

  measurement_r_.clear();
  update_r_.clear();
  for (const auto& d : detections) {
    measurement_r_.push_back(measurement_covariance(d));
    update_r_.push_back(update_covariance(d));
  }
  predict_all(dt);
  assign(detections);
  detection_used_.assign(detections.size(), 0);
  for (const int d : col_of_row_) {
    if (d != kUnassigned) detection_used_[static_cast<std::size_t>(d)] = 1;
  }
  reassociate(detections);
  for (std::size_t i = 0; i < hypotheses_.size(); ++i) {
    const int d = col_of_row_[i];
    if (d == kUnassigned) {
      coast(hypotheses_[i]);
      look_for_missed(hypotheses_[i]);
    } else {
      if (paired_at_rest_[i]) {
        hypotheses_[i].filter.stop_at(hypotheses_[i].last_detection.centroid.cast<double>());
        ++stats_.paired_at_rest;
      }
      if (shows_part_at_rest(hypotheses_[i], detections[d])) {
        hold_at_full_view(hypotheses_[i], detections[d], d);
      } else {
        correct(hypotheses_[i], detections[d], d);
      }
      ++stats_.assigned;
    }
  }
  delete_uncertain();
  for (std::size_t j = 0; j < detections.size(); ++j) {
    if (detection_used_[j]) continue;
    if (detections[j].relaxed) {
      ++stats_.relaxed_unassigned;  // relaxed detections only confirm existing tracks
      continue;
    }
    create(detections[j], static_cast<int>(j));
  }
  delete_merged();
  newly_confirmed_.clear();
  for (std::size_t i = 0; i < hypotheses_.size(); ++i) {
    Hypothesis& h = hypotheses_[i];
    const bool was_confirmed = h.confirmed;
    report_velocity(h);
    classify(h);
    decide_report(h);
    set_reported_position(h);
    update_person_flag(h);
    if (h.confirmed && !was_confirmed) newly_confirmed_.push_back(i);
  }
  relink(newly_confirmed_);
  forget_lost();
  visibility_ = nullptr;  // the scan may not outlive this call
  return hypotheses_;
}

void Tracker::predict_all(double dt_s) {
  for (auto& h : hypotheses_) {
    const Eigen::Vector3d before = h.filter.position();
    predict_filter(config_, h.filter, dt_s);
    // A missed object's box follows the prediction; a corrected one is replaced below.
    h.box = h.box.translated((h.filter.position() - before).cast<float>());
    ++h.age_scans;
    h.detection = -1;
    h.points = 0;
  }
}

void Tracker::assign(const std::vector<core::Detection>& detections) {
  const auto rows = static_cast<Eigen::Index>(hypotheses_.size());
  const auto cols = static_cast<Eigen::Index>(detections.size());
  col_of_row_.assign(hypotheses_.size(), kUnassigned);
  paired_at_rest_.assign(hypotheses_.size(), 0);
  if (rows == 0 || cols == 0) return;
  h_terms_.clear();
  d_terms_.clear();
  for (const auto& h : hypotheses_) {
    h_terms_.push_back(make_gaussian_term(h.position(), h.position_covariance()));
  }
  for (std::size_t j = 0; j < detections.size(); ++j) {
    d_terms_.push_back(
        make_gaussian_term(detections[j].centroid.cast<double>(), measurement_r_[j]));
  }
  const double g = gate();
  cost_.resize(rows, cols);
  for (Eigen::Index i = 0; i < rows; ++i) {
    for (Eigen::Index j = 0; j < cols; ++j) {
      cost_(i, j) = pair_cost_terms(config_, g, h_terms_[i], d_terms_[j]);
    }
  }
  add_rest_alternatives(detections);
  col_of_row_ = solve_gated_assignment(cost_, g);
  if (rest_cheaper_.empty()) return;
  for (std::size_t i = 0; i < hypotheses_.size(); ++i) {
    const int j = col_of_row_[i];
    if (j != kUnassigned) {
      paired_at_rest_[i] = rest_cheaper_[i * detections.size() + static_cast<std::size_t>(j)];
    }
  }
}

bool Tracker::may_have_stopped(const Hypothesis& h) const {
  return config_.rest_pairing && h.ever_dynamic && (h.missed_scans > 0 || h.fell_behind) &&
         h.hits > 0 && !h.filter.velocity().head<2>().isZero();
}

void Tracker::add_rest_alternatives(const std::vector<core::Detection>& detections) {
  // A walker that stops while unmeasured (hidden, or merged with the structure it stopped
  // beside) is not where the constant-velocity prediction puts it: that coasted on at walking
  // speed, and a static hypothesis on the structure beside the walker took its detection (an
  // identity switch, and a track that never turned dynamic again; the hall, docs/BENCHMARK.md).
  // So a coasting hypothesis that has moved may also pair at rest where it was last measured,
  // whichever costs less; update() then restarts its filter there. So may one whose last
  // detection fell behind its prediction, outside the gate: a walker slowing to a stop in view.
  rest_cheaper_.clear();
  const std::size_t cols = detections.size();
  const double g = gate();
  for (std::size_t i = 0; i < hypotheses_.size(); ++i) {
    const Hypothesis& h = hypotheses_[i];
    if (!may_have_stopped(h)) continue;
    if (rest_cheaper_.empty()) rest_cheaper_.assign(hypotheses_.size() * cols, 0);
    const GaussianTerm rest =
        make_gaussian_term(h.last_detection.centroid.cast<double>(), h.position_covariance());
    for (std::size_t j = 0; j < cols; ++j) {
      // A body, not one or two points of clutter near where a track was last seen: far clutter
      // kept alive this way turned dynamic (the town's false positives, docs/BENCHMARK.md).
      if (detections[j].relaxed || detections[j].indices.size() <= kFewPoints) continue;
      const double c = pair_cost_terms(config_, g, rest, d_terms_[j]);
      const auto r = static_cast<Eigen::Index>(i);
      const auto k = static_cast<Eigen::Index>(j);
      if (c < cost_(r, k)) {
        cost_(r, k) = c;
        rest_cheaper_[i * cols + j] = 1;
      }
    }
  }
}

void Tracker::reassociate(const std::vector<core::Detection>& detections) {
  // The Bhattacharyya distance also compares the two spreads: a hypothesis that coasted a few
  // scans (wide covariance) and a one-point detection (tight) are far apart even when their
  // means coincide, and the detection started a new track beside the old one (an identity
  // switch). A second, greedy pass pairs what the gate left over by horizontal distance.
  // Extends col_of_row_ and detection_used_ (the gated assignment's pairs, marked by update()).
  for (Hypothesis& h : hypotheses_) h.fell_behind = false;  // assign() has read last scan's
  if (config_.reassociate_distance_m <= 0.0 || detections.empty()) return;
  leftover_pairs_.clear();
  for (std::size_t i = 0; i < hypotheses_.size(); ++i) {
    if (col_of_row_[i] != kUnassigned) continue;
    const Eigen::Vector2d at = hypotheses_[i].position().head<2>();
    for (std::size_t j = 0; j < detections.size(); ++j) {
      if (detection_used_[j]) continue;
      const double d = (detections[j].centroid.cast<double>().head<2>() - at).norm();
      if (d <= config_.reassociate_distance_m) leftover_pairs_.push_back({d, i, j});
    }
  }
  std::sort(leftover_pairs_.begin(), leftover_pairs_.end(),
            [](const LeftoverPair& a, const LeftoverPair& b) {
              return a.distance < b.distance || (a.distance == b.distance && a.row < b.row);
            });
  for (const LeftoverPair& p : leftover_pairs_) {
    if (col_of_row_[p.row] != kUnassigned || detection_used_[p.col]) continue;
    col_of_row_[p.row] = static_cast<int>(p.col);
    detection_used_[p.col] = 1;
    // A walker slowing to a stop: the constant-velocity prediction runs ahead of it, out of the
    // gate, scan after scan, and a nearby young hypothesis within the gate took its detection
    // (an identity switch; docs/tracking.md, "Stopping in view"). Next scan it may also pair at
    // rest.
    hypotheses_[p.row].fell_behind = falls_behind(hypotheses_[p.row], detections[p.col]);
  }
}

void Tracker::measure(Hypothesis& h, const Eigen::Vector3d& at, const core::Detection& d,
                      int index) {
  h.filter.update(at, update_r_[index]);
  if (config_.vertical_motion == core::VerticalMotion::kConstantPosition) {
    h.filter.hold_vertical_velocity();
  }
  h.filter.cap_speed(max_speed_mps_);
  h.missed_scans = 0;
  h.points = d.indices.size();
  h.detection = index;
  ++h.hits;
  h.occluded = false;
  h.unseen = false;
  h.seen_through_scans = 0;
}

void Tracker::correct(Hypothesis& h, const core::Detection& d, int index) {
  measure(h, d.centroid.cast<double>(), d, index);
  h.box = d.box;
  h.last_detection = {d.centroid,       d.object_centroid(), d.covariance, d.box,
                      d.indices.size(), d.relaxed,           stamp_ns_};
  h.held_scans = 0;
  remember_points(h, d);
}

bool Tracker::shows_part_at_rest(const Hypothesis& h, const core::Detection& d) const {
  // A standing person behind a passer-by: the detection holds only the visible edge, and its
  // centroid, followed, dragged the track off the person scan by scan until it was deleted; a
  // second hypothesis on the other edge took the person over and, never having moved, never
  // turned dynamic (the static hall's walker who stops: 30,000 of its 44,000 dynamic points kept
  // in the map; docs/BENCHMARK.md, issue 12). Only at rest: a walker's view changes as it moves.
  if (!config_.hold_partly_hidden || visibility_ == nullptr || !h.confirmed ||
      !h.velocity_mps.isZero() || h.last_points.empty()) {
    return false;
  }
  // As many points as the full view, or more: not a partial view.
  if (d.indices.size() >= h.last_detection.points) return false;
  if (h.held_scans >= kMaxHeldScans) return false;
  const Eigen::Vector3d shift = h.position() - h.last_detection.centroid.cast<double>();
  const auto counts = probe_points(*visibility_, config_, h.last_points, shift);
  // Something nearer in front of a quarter or more of the full view's points that the scan
  // decides about, two at least (a stray beam does not decide): hidden in part, not gone in
  // part. Two points alone held too often with estimated poses (the moving runs with the
  // odometry: MOTA 0.629 against 0.669; docs/BENCHMARK.md, issue 12).
  const int seen = seen_free(counts) + counts.occupied + counts.occluded;
  return counts.occluded >= 2 && 4 * counts.occluded >= seen;
}

void Tracker::hold_at_full_view(Hypothesis& h, const core::Detection& d, int index) {
  // Measured where the full view put it; that view (its centroid, box, points, count) stays the
  // reference the next scan is compared with, so a longer occlusion is recognised scan by scan.
  measure(h, h.last_detection.centroid.cast<double>(), d, index);
  h.box = h.last_detection.box;
  h.last_detection.stamp_ns = stamp_ns_;
  ++h.held_scans;
  ++stats_.held_partly_hidden;
}

void Tracker::coast(Hypothesis& h) {
  ++h.missed_scans;
}

void Tracker::remember_points(Hypothesis& h, const core::Detection& d) const {
  h.last_points.clear();
  if (visibility_ == nullptr || d.indices.empty()) return;
  // An even sample over the detection's cells (ascending: ring by ring), so every ring that hit
  // the object is represented.
  const std::size_t n = d.indices.size();
  const std::size_t k = std::min(n, kRememberedPoints);
  for (std::size_t s = 0; s < k; ++s) {
    const std::size_t cell = d.indices[s * n / k];
    h.last_points.push_back(visibility_->world_point(cell).cast<float>());
  }
}

void Tracker::look_for_missed(Hypothesis& h) const {
  h.occluded = false;
  h.unseen = false;
  if (visibility_ == nullptr || h.last_points.empty()) {
    h.seen_through_scans = 0;
    return;
  }
  // Where the object's points would be now if it moved as predicted.
  const Eigen::Vector3d shift = h.position() - h.last_detection.centroid.cast<double>();
  const auto counts = probe_points(*visibility_, config_, h.last_points, shift);
  const int free = seen_free(counts);
  const int seen = free + counts.occupied + counts.occluded;
  // Something in front of most of its points: it is hidden, not gone.
  h.occluded = seen > 0 && 2 * counts.occluded > seen;
  // The scan looks through nearly all of them and nothing there was detected: it is gone (or
  // the prediction is wrong, which a fresh hypothesis repairs).
  const bool seen_through = free >= 2 && free >= seen - 1;
  h.seen_through_scans = seen_through ? h.seen_through_scans + 1 : 0;
  // Nothing in the scan where it is predicted: no beam ended at its points (seen through,
  // passing beside them, or none there at all: a far object between two beams, an object below
  // a tilted sensor's lowest ring) and nothing hides them. It is kept (one stray beam does not
  // delete it) but not reported in a scan that shows nothing of it. (Beams ending inside the
  // predicted box instead of at the points: static 0.812 instead of 0.820, moving equal.)
  h.unseen = counts.occupied == 0 && !h.occluded;
}

void Tracker::create(const core::Detection& d, int index) {
  Hypothesis h;
  h.id = next_id_++;
  h.created_ns = stamp_ns_;
  h.first_position = d.centroid.cast<double>();
  h.filter = ConstantVelocityKalman(d.centroid.cast<double>(), measurement_r_[index],
                                    config_.initial_velocity_stddev_mps);
  if (config_.vertical_motion == core::VerticalMotion::kConstantPosition) {
    h.filter.hold_vertical_velocity();
  }
  h.box = h.initial_box = h.anchor_box = d.box;
  h.anchor_position = h.filter.position();
  h.age_scans = 1;
  h.points = d.indices.size();
  h.detection = index;
  h.last_detection = {d.centroid,       d.object_centroid(), d.covariance, d.box,
                      d.indices.size(), d.relaxed,           stamp_ns_};
  h.hits = 1;
  remember_points(h, d);
  h.anchor_points = h.last_points;
  if (visibility_ != nullptr) h.anchor_viewpoint = visibility_->sensor_position();
  hypotheses_.push_back(std::move(h));
  ++stats_.created;
}

void Tracker::delete_uncertain() {
  const auto doomed = [&](const Hypothesis& h) {
    if (config_.free_delete_scans > 0 && h.seen_through_scans >= config_.free_delete_scans) {
      ++stats_.deleted_seen_through;
      return true;
    }
    // A hidden object is still there: keep it while the occlusion lasts (bounded).
    if (h.occluded && h.missed_scans <= config_.occluded_coast_scans) return false;
    if (deletion_eigenvalue(config_, h.position_covariance()) <= config_.delete_eigenvalue_m2) {
      return false;
    }
    ++stats_.deleted_uncertain;
    return true;
  };
  std::size_t k = 0;
  for (std::size_t j = 0; j < hypotheses_.size(); ++j) {
    Hypothesis& h = hypotheses_[j];
    if (doomed(h)) {
      keep_if_lost(h, config_, lost_);
    } else {
      if (k != j) hypotheses_[k] = std::move(h);
      ++k;
    }
  }
  hypotheses_.resize(k);
}

void Tracker::delete_merged() {
  // hypotheses_ is in creation order, so a later entry is the younger one.
  const double r = config_.merge_distance_m;
  // Two hypotheses last measured by one or two points each may sit on one far person: its hits
  // fall anywhere on the body, a hit the gate rejected started the second one, and then the two
  // took the person's hits in turns (an identity switch each time; docs/tracking.md, "Merging").
  const double few_point_reach = std::max(r, config_.few_point_merge_distance_m);
  if (few_point_reach <= 0.0) return;
  constexpr char kMerged = 1;          // within merge_distance_m
  constexpr char kFewPointMerged = 2;  // within few_point_merge_distance_m only
  std::vector<char> doomed(hypotheses_.size(), 0);
  for (std::size_t j = 1; j < hypotheses_.size(); ++j) {
    const auto& young = hypotheses_[j];
    for (std::size_t i = 0; i < j; ++i) {
      if (doomed[i]) continue;
      const auto& old = hypotheses_[i];
      const double horizontal = (young.position() - old.position()).head<2>().norm();
      const bool few_points =
          young.last_detection.points <= kFewPoints && old.last_detection.points <= kFewPoints;
      const double reach = few_points ? few_point_reach : r;
      if (horizontal < reach && vertical_gap(young.box, old.box) < reach) {
        doomed[j] = few_points ? kFewPointMerged : kMerged;
        break;
      }
    }
  }
  // Two people crossing are one cluster for a scan or two: the older track takes it, the other
  // coasts into it and is merged away. When they part, the other person would come back as a
  // new identity; kept as lost, it continues the old one (relink()). Not so for two few-point
  // tracks on one far person: kept, the duplicate's id came back on the person's next stray hit
  // and the two ids alternated (validation far field, moving sensor: 27 -> 46 switches).
  for (std::size_t j = 0; j < hypotheses_.size(); ++j) {
    if (doomed[j] == kMerged) keep_if_lost(hypotheses_[j], config_, lost_);
  }
  stats_.deleted_merged += remove_flagged(hypotheses_, doomed);
}

double Tracker::relink_distance(const Hypothesis& lost, const Hypothesis& young) const {
  // Only what has moved: static clutter lost from a moving sensor and a new cluster beside it
  // are two objects as often as one, and a clutter id handed on lived longer and turned dynamic
  // (industrial, moving sensor: 39 -> 128 false positives when any confirmed one was relinked).
  if (!lost.ever_dynamic) return kInf;
  // Only an object that was not measured after the young one was born can have become it (one
  // measured since is another object beside it), and only within the gap. Measured in the very
  // scan of the birth is allowed: a far body cut into two fragments, the old track took one, the
  // young one the other and then every later detection (ID switches, all built-ins: 382 -> 352).
  const std::int64_t gap_ns = young.created_ns - lost.last_detection.stamp_ns;
  if (gap_ns < 0 || static_cast<double>(gap_ns) * 1e-9 > config_.relink_max_gap_s) return kInf;
  if (vertical_gap(lost.last_detection.box, young.initial_box) > config_.relink_distance_m) {
    return kInf;
  }
  // Where it would have been at that birth had it gone on as it went (the filter's velocity,
  // already capped at max_speed_kmh).
  const Eigen::Vector3d expected = lost.last_detection.centroid.cast<double>() +
                                   static_cast<double>(gap_ns) * 1e-9 * lost.filter.velocity();
  const double d = (young.first_position - expected).head<2>().norm();
  return d <= config_.relink_distance_m ? d : kInf;
}

Tracker::RelinkCandidate Tracker::nearest_lost(const Hypothesis& young,
                                               const std::vector<char>& taken) const {
  RelinkCandidate best;
  for (std::size_t i = 0; i < hypotheses_.size(); ++i) {
    const Hypothesis& h = hypotheses_[i];
    // Measured in this scan (the young one itself among them) is not lost.
    if (taken[i] || !h.confirmed || h.detection >= 0) continue;
    const double d = relink_distance(h, young);
    if (d < best.distance) best = {d, static_cast<int>(i), -1};
  }
  for (std::size_t i = 0; i < lost_.size(); ++i) {
    const double d = relink_distance(lost_[i], young);
    if (d < best.distance) best = {d, -1, static_cast<int>(i)};
  }
  return best;
}

void Tracker::take_over(Hypothesis& young, const Hypothesis& old) {
  young.id = old.id;
  young.ever_dynamic = young.ever_dynamic || old.ever_dynamic;
  if (old.dynamic && !young.dynamic) {  // a walker that moved goes on moving
    young.dynamic = true;
    young.rest_scans = 0;
    young.moved_scans = 0;
  }
  young.person_scans += old.person_scans;
  young.person = young.person || old.person;
  ++stats_.relinked;
}

void Tracker::relink(const std::vector<std::size_t>& newly_confirmed) {
  // A person lost for a few scans (a turn the filter lagged, a body cut into fragments, a
  // detection the gate rejected) comes back as a new hypothesis; confirmed, it would be a new
  // identity (an identity switch in the evaluation: docs/BENCHMARK.md, issue 10 part 6). Before
  // it is ever reported, it takes over the lost one's id and flags instead. Candidates are the
  // confirmed hypotheses deleted lately and the live ones coasting since its birth; the nearest
  // wins and is then gone.
  if (config_.relink_distance_m <= 0.0 || newly_confirmed.empty()) return;
  std::vector<char> taken(hypotheses_.size(), 0);
  for (const std::size_t y : newly_confirmed) {
    Hypothesis& young = hypotheses_[y];
    const RelinkCandidate best = nearest_lost(young, taken);
    if (best.live >= 0) {
      take_over(young, hypotheses_[static_cast<std::size_t>(best.live)]);
      taken[static_cast<std::size_t>(best.live)] = 1;  // it would only have coasted out
    } else if (best.lost >= 0) {
      take_over(young, lost_[static_cast<std::size_t>(best.lost)]);
      lost_.erase(lost_.begin() + best.lost);
    }
  }
  remove_flagged(hypotheses_, taken);
}

void Tracker::forget_lost() {
  // A hypothesis born later than relink_max_gap_s after a lost one's last measurement can no
  // longer take it over; one born earlier and confirmed late may, so keep twice that.
  const auto horizon_ns = static_cast<std::int64_t>(2.0 * config_.relink_max_gap_s * 1e9);
  std::erase_if(lost_, [&](const Hypothesis& h) {
    return stamp_ns_ - h.last_detection.stamp_ns > horizon_ns;
  });
}

void Tracker::decide_report(Hypothesis& h) const {
  // Confirmation (M detections) keeps one-scan blips out of the output, at the cost of
  // confirm_hits - 1 scans of latency for a new object. A hypothesis that has gone unmeasured
  // for long is kept (its id survives a short gap, longer when the scan shows it hidden) but
  // not listed: its prediction drifts off the object, and a hidden object has no hit points, so
  // listing it only counts as a false positive (docs/tracking.md, "What is reported").
  h.confirmed = h.confirmed || h.hits >= config_.confirm_hits;
  h.reported = h.confirmed && (h.missed_scans == 0 ||
                               (h.missed_scans <= config_.report_missed_scans && !h.unseen));
}

void Tracker::set_reported_position(Hypothesis& h) const {
  // The filter smooths the centroid over scans, so it lags a walker that turns or changes pace
  // and its height follows the rings only slowly; the detection's centroid is where this scan
  // shows the object, with the cells the completion added (the evaluation's ground truth is
  // the centroid of all the object's hit points: docs/tracking.md, "Reported position"). The filter
  // still drives association and prediction, and a missed hypothesis has nothing better than its
  // prediction.
  const bool measured = h.detection >= 0;
  h.reported_position = measured && config_.reported_position == core::ReportedPosition::kMeasured
                            ? h.last_detection.object_centroid.cast<double>()
                            : h.filter.position();
}

void Tracker::update_person_flag(Hypothesis& h) const {
  // The strict object model is a person's size (height, footprint); a relaxed detection may be
  // any clutter near the prediction and says nothing about the shape. Counted, not required in a
  // row: a partial occlusion (relaxed, missed) pauses the count without resetting it. Sticky, so
  // a user filtering on the flag keeps a person who later walks behind something.
  if (h.detection >= 0 && !h.last_detection.relaxed) ++h.person_scans;
  h.person = h.person || (h.confirmed && h.person_scans >= config_.person_min_scans);
}

void Tracker::report_velocity(Hypothesis& h) const {
  const Eigen::Vector3d v = h.filter.velocity();
  const double speed = v.norm();
  if (speed <= min_speed_mps_) {
    h.velocity_mps.setZero();
  } else if (speed > max_speed_mps_) {
    h.velocity_mps = v * (max_speed_mps_ / speed);
  } else {
    h.velocity_mps = v;
  }
}

void Tracker::classify(Hypothesis& h) const {
  if (h.detection < 0) return;  // only a measured box is evidence either way
  if (!h.dynamic) {
    // Free space is exact evidence only from the viewpoint the anchor was seen from: then every
    // remembered point is probed by the very beam that measured it. From elsewhere, beams pass
    // beside the points, and those grazing an edge of static clutter see past it (measured:
    // more clutter turned dynamic with a moving sensor, docs/tracking.md).
    if (config_.dynamic_test == core::DynamicTest::kFreeSpace && visibility_ != nullptr &&
        !h.anchor_points.empty() &&
        (visibility_->sensor_position() - h.anchor_viewpoint).norm() <=
            config_.free_space_max_viewpoint_shift_m) {
      classify_by_free_space(h);
    } else {
      classify_by_box(h);
    }
    return;
  }
  h.rest_scans = h.velocity_mps.isZero() ? h.rest_scans + 1 : 0;
  if (config_.rest_scans_to_static > 0 && h.rest_scans >= config_.rest_scans_to_static) {
    h.dynamic = false;
    h.anchor_box = h.box;
    h.anchor_position = h.last_detection.centroid.cast<double>();
    h.anchor_points = h.last_points;
    if (visibility_ != nullptr) h.anchor_viewpoint = visibility_->sensor_position();
    h.rest_scans = 0;
  }
}

void Tracker::classify_by_free_space(Hypothesis& h) const {
  // The object stood at its anchor; if the scan now sees through most of the points it occupied
  // there while the object is measured elsewhere, it has left. Occlusion hides those points
  // (occluded), a moving viewpoint sees them from another side (occupied or occluded): neither
  // makes them free, so static clutter stays static however its cluster changes shape.
  const double moved =
      (h.last_detection.centroid.cast<double>() - h.anchor_position).head<2>().norm();
  const auto counts = probe_points(*visibility_, config_, h.anchor_points, Eigen::Vector3d::Zero());
  const int free = seen_free(counts);
  // Two points seen free outvote a stray beam; an anchor of one point (a far person's sparse
  // detection) has only the one.
  const int min_free = std::min<int>(2, static_cast<int>(h.anchor_points.size()));
  const bool left = moved > config_.free_space_min_distance_m && free >= min_free &&
                    free >= config_.free_space_min_share * (free + counts.occupied);
  extend_streak(h, left);
  if (h.moved_scans >= config_.free_space_confirm_scans) {
    h.dynamic = h.ever_dynamic = true;
    h.rest_scans = 0;
    h.moved_scans = 0;
  }
}

void Tracker::classify_by_box(Hypothesis& h) const {
  // Measured evidence only: the filter's position drifts while coasting on a spurious
  // velocity, and a relaxed detection may be any clutter near the prediction, so neither can
  // make a static object (fence post, wall edge) dynamic.
  // Clutter's clusters jump back and forth, a walker keeps going: the displacement must hold
  // in dynamic_confirm_scans consecutive measured scans.
  if (h.last_detection.relaxed) return;
  const double moved =
      (h.last_detection.centroid.cast<double>() - h.anchor_position).head<2>().norm();
  extend_streak(
      h, !footprints_intersect(h.box, h.anchor_box) && moved > config_.dynamic_min_distance_m);
  if (h.moved_scans < config_.dynamic_confirm_scans) return;
  // Far from its anchor is not yet moving: a moving sensor's tracker loses static clutter and
  // re-acquires it on a neighbouring post or bush 1-4 m away, where it then stands still (the
  // moving park's false positives, docs/BENCHMARK.md). A walker also covers ground during the
  // streak; clutter stays put. A streak that covered too little within kStreakSpan times the
  // confirmation length starts over, so slow drift of a cluster's centre never adds up.
  constexpr int kStreakSpan = 3;
  const double covered =
      (h.last_detection.centroid.cast<double>() - h.streak_start).head<2>().norm();
  if (covered >= config_.dynamic_streak_min_m) {
    h.dynamic = h.ever_dynamic = true;
    h.rest_scans = 0;
    h.moved_scans = 0;
  } else if (h.moved_scans >= kStreakSpan * config_.dynamic_confirm_scans) {
    h.moved_scans = 0;
  }
}

void Tracker::extend_streak(Hypothesis& h, bool held) {
  if (!held) {
    h.moved_scans = 0;
    return;
  }
  if (h.moved_scans == 0) h.streak_start = h.last_detection.centroid.cast<double>();
  ++h.moved_scans;
}

int missed_scans_until_deletion(const core::TrackingConfig& config, const Eigen::Matrix3d& r_create,
                                const Eigen::Matrix3d& r_update, double dt_s, int updates) {
  const bool flat = config.vertical_motion == core::VerticalMotion::kConstantPosition;
  ConstantVelocityKalman filter(Eigen::Vector3d::Zero(), r_create,
                                config.initial_velocity_stddev_mps);
  if (flat) filter.hold_vertical_velocity();
  for (int u = 0; u < updates; ++u) {
    predict_filter(config, filter, dt_s);
    filter.update(Eigen::Vector3d::Zero(), r_update);
    if (flat) filter.hold_vertical_velocity();
  }
  constexpr int kLimit = 1000000;
  for (int missed = 1; missed <= kLimit; ++missed) {
    predict_filter(config, filter, dt_s);
    if (deletion_eigenvalue(config, filter.position_covariance()) > config.delete_eigenvalue_m2) {
      return missed;
    }
  }
  return kLimit;
}

}  // namespace ringtrack::tracking
