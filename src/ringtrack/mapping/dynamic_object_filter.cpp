#include "ringtrack/mapping/dynamic_object_filter.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "ringtrack/core/error.hpp"

namespace ringtrack::mapping {

namespace {

std::size_t block_count(std::size_t points) {
  return (points + LoggedScan::kBlockPoints - 1) / LoggedScan::kBlockPoints;
}

// Bounds per block of LoggedScan::kBlockPoints points. This runs on every scan, so the block's
// coordinates are read as one float array, four at a time, into three vector accumulators whose
// lanes hold x y z x / y z x y / z x y z. A block whose bounds come out non-finite (a NaN point)
// gets unbounded bounds, so that it is always tested point by point.
void compute_block_bounds(const std::vector<Eigen::Vector3f>& points,
                          std::vector<core::Box3>& bounds) {
  constexpr std::size_t kBlock = LoggedScan::kBlockPoints;
  static_assert(kBlock % 4 == 0);
  static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
  constexpr float kInf = std::numeric_limits<float>::infinity();
  bounds.resize(block_count(points.size()));
  if (points.empty()) return;
  const Eigen::Map<const Eigen::ArrayXf> flat(points.front().data(),
                                              static_cast<Eigen::Index>(3 * points.size()));
  for (std::size_t b = 0; b < bounds.size(); ++b) {
    const std::size_t begin = b * kBlock;
    const std::size_t count = std::min(kBlock, points.size() - begin);
    Eigen::Vector3f lo = Eigen::Vector3f::Constant(kInf), hi = Eigen::Vector3f::Constant(-kInf);
    std::size_t i = 0;
    if (count >= 4) {
      Eigen::Array4f lo0 = Eigen::Array4f::Constant(kInf), lo1 = lo0, lo2 = lo0;
      Eigen::Array4f hi0 = -lo0, hi1 = hi0, hi2 = hi0;
      for (; i + 4 <= count; i += 4) {
        const auto j = static_cast<Eigen::Index>(3 * (begin + i));
        lo0 = lo0.min(flat.segment<4>(j));
        hi0 = hi0.max(flat.segment<4>(j));
        lo1 = lo1.min(flat.segment<4>(j + 4));
        hi1 = hi1.max(flat.segment<4>(j + 4));
        lo2 = lo2.min(flat.segment<4>(j + 8));
        hi2 = hi2.max(flat.segment<4>(j + 8));
      }
      lo = {std::min({lo0[0], lo0[3], lo1[2], lo2[1]}), std::min({lo0[1], lo1[0], lo1[3], lo2[2]}),
            std::min({lo0[2], lo1[1], lo2[0], lo2[3]})};
      hi = {std::max({hi0[0], hi0[3], hi1[2], hi2[1]}), std::max({hi0[1], hi1[0], hi1[3], hi2[2]}),
            std::max({hi0[2], hi1[1], hi2[0], hi2[3]})};
    }
    for (; i < count; ++i) {
      lo = lo.cwiseMin(points[begin + i]);
      hi = hi.cwiseMax(points[begin + i]);
    }
    if (lo.allFinite() && hi.allFinite()) {
      bounds[b] = {lo, hi};
    } else {
      bounds[b] = {Eigen::Vector3f::Constant(-kInf), Eigen::Vector3f::Constant(kInf)};
    }
  }
}

// Both scans were taken from one viewpoint (a resting sensor): each cell's beam is the same, up
// to the pose noise of a resting sensor's pose source (the bounds of background.static_shift_m and
// static_turn_deg's defaults; a 0.1 degree turn moves a beam 9 cm at 50 m, well inside
// free_space_margin_m).
bool same_view(const LoggedScan& logged, const core::OrganizedScan& now, const core::Pose& pose) {
  constexpr double kShiftM = 0.02;
  constexpr double kTurnRad = 0.1 * std::numbers::pi / 180.0;
  return logged.rings == now.rings() && logged.columns == now.columns() &&
         logged.pose.near(pose, kShiftM, kTurnRad);
}

}  // namespace

void LoggedScan::update_bounds() {
  compute_block_bounds(points, block_bounds);
  bounded_points = points.size();
}

bool LoggedScan::bounds_current() const {
  return bounded_points == points.size() && block_bounds.size() == block_count(points.size());
}

std::size_t LoggedScan::remove_inside(const core::Box3& box,
                                      std::vector<std::uint32_t>* removed_cells,
                                      const std::function<bool(const Eigen::Vector3f&)>& keep) {
  // Retroactive removal tests the boxes of an object's whole static era (up to
  // log_delay_scans scans, each with tens of thousands of points); the block bounds cut that
  // to the few blocks the box meets.
  const bool bounded = bounds_current();
  std::size_t n = 0;
  for (std::size_t b = 0; b < block_count(points.size()); ++b) {
    if (bounded && !block_bounds[b].intersects(box)) continue;
    const std::size_t end = std::min(points.size(), (b + 1) * kBlockPoints);
    for (std::size_t i = b * kBlockPoints; i < end; ++i) {
      if (!removed[i] && box.contains(points[i]) && !(keep && keep(points[i]))) {
        removed[i] = 1;
        ++n;
        if (removed_cells != nullptr) removed_cells->push_back(cells[i]);
      }
    }
  }
  removed_count += n;
  return n;
}

float LoggedScan::lowest_in(const core::Box3& box) const {
  const bool bounded = bounds_current();
  float lowest = std::numeric_limits<float>::infinity();
  for (std::size_t b = 0; b < block_count(points.size()); ++b) {
    if (bounded && (!block_bounds[b].intersects(box) || block_bounds[b].min.z() >= lowest)) {
      continue;
    }
    const std::size_t end = std::min(points.size(), (b + 1) * kBlockPoints);
    for (std::size_t i = b * kBlockPoints; i < end; ++i) {
      if (points[i].z() < lowest && box.contains(points[i])) lowest = points[i].z();
    }
  }
  return lowest;
}

DynamicObjectFilter::DynamicObjectFilter(const core::MappingConfig& config)
    : config_(config),
      map_(config.voxel_size_m),
      transient_grid_(config.transient_cell_m, kTransientMemoryScans) {}

core::Box3 DynamicObjectFilter::inflate(const core::Box3& box) const {
  const auto m = static_cast<float>(config_.box_margin_m);
  return {box.min.array() - m, box.max.array() + m};
}

void DynamicObjectFilter::remove_box(std::uint64_t sequence, const core::Box3& box) {
  if (box.empty()) return;
  core::Box3 grown = inflate(box);
  if (!log_.empty() && sequence >= log_.front().sequence && sequence <= log_.back().sequence) {
    // A static era's and a gap's boxes miss the legs and the head as a measured box does.
    LoggedScan& logged = log_[sequence - log_.front().sequence];
    reach_ground(logged, grown);
    result_.retroactive_points += logged.remove_inside(grown);
  } else if (log_.empty() || sequence < log_.front().sequence) {
    // The scan already went into the map: remove the voxels instead.
    result_.map_voxels_removed += map_.remove_inside(grown);
  }
}

bool DynamicObjectFilter::removable(const tracking::Hypothesis& h) const {
  switch (config_.remove) {
    case core::RemovedObjects::kDynamic:
      return h.ever_dynamic;
    case core::RemovedObjects::kPerson:
      return h.ever_dynamic || h.person;
    case core::RemovedObjects::kConfirmed:
      return h.ever_dynamic || h.confirmed;
  }
  return h.ever_dynamic;
}

void DynamicObjectFilter::remove_object_box(LoggedScan& scan, const core::Box3& box) {
  // Points of the object outside its detection: 2-4 % of a walker's points lie above its
  // cluster's top (the head) or just beside it, and more below it (the legs the segmentation
  // left to the ground; docs/BENCHMARK.md, issue 12).
  if (box.empty()) return;
  const auto m = static_cast<float>(config_.object_margin_m);
  core::Box3 grown{{box.min.x() - m, box.min.y() - m, box.min.z()},
                   {box.max.x() + m, box.max.y() + m, box.max.z() + m}};
  reach_ground(scan, grown);
  result_.object_box_points += scan.remove_inside(grown, &result_.removed_cells);
  if (config_.object_outer_margin_m > config_.object_margin_m) remove_outer_ring(scan, grown);
}

void DynamicObjectFilter::remove_outer_ring(LoggedScan& scan, const core::Box3& grown) {
  // A walker's arm or coat 0.2-0.3 m beside its cluster (12 % of what a moving sensor's crowd
  // kept; docs/BENCHMARK.md, issue 12). A plain 0.3 m margin ate the hall's walls beside
  // people; here a point whose map voxel was seen free_space_protect_count times is structure and
  // stays. The points inside grown were removed just before: only the ring between is left.
  const auto extra = static_cast<float>(config_.object_outer_margin_m - config_.object_margin_m);
  const core::Box3 outer{{grown.min.x() - extra, grown.min.y() - extra, grown.min.z()},
                         {grown.max.x() + extra, grown.max.y() + extra, grown.max.z()}};
  const auto protect = static_cast<std::uint32_t>(config_.free_space_protect_count);
  const auto structure = [&](const Eigen::Vector3f& p) {
    const MapPoint* voxel = map_.voxel_at(p);
    return voxel != nullptr && voxel->count >= protect;
  };
  result_.object_box_points += scan.remove_inside(outer, &result_.removed_cells, structure);
}

void DynamicObjectFilter::reach_ground(const LoggedScan& scan, core::Box3& grown) const {
  // The ground beside the object: the lowest point of this scan under and around its box. The
  // footprint alone often holds no ground (the body hides it, the rings meet the ground metres
  // apart), and then its lowest point is a leg; a metre around it finds the ground beside the
  // feet on any floor flatter than ~10 % over that metre.
  if (config_.object_ground_clearance_m <= 0.0 && config_.object_min_height_m <= 0.0) return;
  constexpr float kGroundSearchM = 1.0f;
  const float inf = std::numeric_limits<float>::infinity();
  const core::Box3 around{
      {grown.min.x() - kGroundSearchM, grown.min.y() - kGroundSearchM, -inf},
      {grown.max.x() + kGroundSearchM, grown.max.y() + kGroundSearchM, grown.min.z()}};
  const float ground = scan.lowest_in(around);
  if (!(ground < grown.min.z())) return;  // nothing below it: the box shows all there is
  if (config_.object_ground_clearance_m > 0.0) {
    grown.min.z() =
        std::min(grown.min.z(), ground + static_cast<float>(config_.object_ground_clearance_m));
  }
  if (config_.object_min_height_m > 0.0) {
    grown.max.z() =
        std::max(grown.max.z(), ground + static_cast<float>(config_.object_min_height_m));
  }
}

void DynamicObjectFilter::release_front() {
  LoggedScan& scan = log_.front();
  remove_transient(scan);
  map_.insert(scan.points, scan.intensities, scan.removed, scan.cells, settled_);
  released_.push_back(std::move(scan));
  log_.pop_front();
  ++result_.scans_to_map;
  // Static boxes of scans now in the map shrink to one union box per object.
  const std::uint64_t oldest = log_.empty() ? next_sequence_ : log_.front().sequence;
  for (auto& [id, object] : objects_) {
    while (!object.static_boxes.empty() && object.static_boxes.front().sequence < oldest) {
      object.expired_static.extend(object.static_boxes.front().box);
      object.static_boxes.pop_front();
    }
  }
}

LoggedScan& DynamicObjectFilter::log_scan(const core::OrganizedScan& scan, const core::Pose& pose,
                                          std::uint64_t sequence) {
  // Reuse the buffers of a scan released by the previous call: no page faults per scan.
  LoggedScan logged;
  if (!released_.empty()) logged = std::move(released_.back());
  released_.clear();

  logged.sequence = sequence;
  logged.stamp_ns = scan.stamp_ns;
  logged.pose = pose;
  logged.rings = scan.rings();
  logged.columns = scan.columns();
  logged.removed_count = 0;
  logged.candidates.clear();
  logged.candidate_ranges.clear();
  logged.transient_candidates.clear();
  logged.transient_keys.clear();
  const Eigen::Isometry3d world_from_sensor = pose.isometry();
  const Eigen::Matrix3f rotation = world_from_sensor.linear().cast<float>();
  const Eigen::Vector3f translation = world_from_sensor.translation().cast<float>();
  const std::size_t valid = scan.valid_count();
  logged.cells.resize(valid);
  logged.points.resize(valid);
  logged.intensities.resize(valid);
  logged.removed.assign(valid, 0);
  point_of_cell_.assign(scan.size(), -1);
  const auto& xs = scan.xs();
  const auto& ys = scan.ys();
  const auto& zs = scan.zs();
  const auto& intensities = scan.intensities();
  std::size_t n = 0;
  for (std::size_t i = 0; i < scan.size(); ++i) {
    if (!scan.valid(i)) continue;
    point_of_cell_[i] = static_cast<std::int32_t>(n);
    logged.cells[n] = static_cast<std::uint32_t>(i);
    logged.points[n] = rotation * Eigen::Vector3f(xs[i], ys[i], zs[i]) + translation;
    logged.intensities[n] = intensities[i];
    ++n;
  }
  logged.update_bounds();
  log_.push_back(std::move(logged));
  return log_.back();
}

void DynamicObjectFilter::update_object(const tracking::Hypothesis& h,
                                        const std::vector<core::Detection>& detections,
                                        LoggedScan& current, std::uint64_t sequence) {
  ObjectHistory& object = objects_[h.id];
  object.touched = sequence;
  const bool detected = h.detection >= 0;
  if (!removable(h)) {
    // Remember where it stood: these points go if it turns out to be dynamic later.
    object.static_boxes.push_back({sequence, h.box});
    if (detected) {
      object.seen = true;
      object.last_seen = {sequence, h.box};
    }
    return;
  }
  if (!object.removing) {
    // Just turned dynamic (or removable): remove it from every scan of its static era.
    object.removing = true;
    for (const auto& b : object.static_boxes) remove_box(b.sequence, b.box);
    object.static_boxes.clear();
    if (!object.expired_static.empty()) {
      result_.map_voxels_removed += map_.remove_inside(inflate(object.expired_static));
      object.expired_static = core::Box3{};
    }
  }
  if (!detected) {
    object.gap.push_back({sequence, h.box});
    return;
  }
  // The object's cells: the detector's and those the completion added (its legs).
  for (const auto* cells :
       {&detections[h.detection].indices, &detections[h.detection].completion}) {
    for (const auto cell : *cells) {
      if (cell >= point_of_cell_.size() || point_of_cell_[cell] < 0) continue;
      const auto p = static_cast<std::size_t>(point_of_cell_[cell]);
      if (current.removed[p]) continue;
      current.removed[p] = 1;
      ++current.removed_count;
      result_.removed_cells.push_back(cell);
    }
  }
  if (config_.object_margin_m > 0.0) remove_object_box(current, h.box);
  if (!object.gap.empty()) remove_gap(object, h.box, sequence);
  object.seen = true;
  object.last_seen = {sequence, h.box};
}

void DynamicObjectFilter::remove_gap(ObjectHistory& object, const core::Box3& box,
                                     std::uint64_t sequence) {
  // Its points in the missed scans lie in the predicted boxes or, when it turned meanwhile,
  // along the straight way from where it was last seen to here.
  for (const auto& g : object.gap) {
    remove_box(g.sequence, g.box);
    if (object.seen && object.last_seen.sequence < g.sequence) {
      const double t = static_cast<double>(g.sequence - object.last_seen.sequence) /
                       static_cast<double>(sequence - object.last_seen.sequence);
      const auto tf = static_cast<float>(t);
      const core::Box3& a = object.last_seen.box;
      if (!a.empty() && !box.empty()) {
        remove_box(g.sequence,
                   {(1.0f - tf) * a.min + tf * box.min, (1.0f - tf) * a.max + tf * box.max});
      }
    }
  }
  object.gap.clear();
}

const FilterResult& DynamicObjectFilter::process(
    const core::OrganizedScan& scan, const core::Pose& pose,
    const std::vector<core::Detection>& detections,
    const std::vector<tracking::Hypothesis>& hypotheses, const ScanEvidence& evidence) {
  if (evidence.segments != nullptr && evidence.segments->size() != scan.size()) {
    throw core::InputError("mapping: " + std::to_string(evidence.segments->size()) +
                           " segment labels for a scan of " + std::to_string(scan.size()) +
                           " cells; the filter was left unchanged");
  }
  for (const auto& h : hypotheses) {
    if (h.detection >= static_cast<int>(detections.size())) {
      throw core::InputError("mapping: hypothesis " + std::to_string(h.id) + " names detection " +
                             std::to_string(h.detection) + " of " +
                             std::to_string(detections.size()) + "; the filter was left unchanged");
    }
  }
  const std::uint64_t sequence = next_sequence_++;
  result_ = FilterResult{};
  result_.sequence = sequence;
  evicted_.clear();
  LoggedScan& current = log_scan(scan, pose, sequence);
  for (const auto& h : hypotheses) update_object(h, detections, current, sequence);
  if (evidence.segments != nullptr) note_transient_candidates(current, *evidence.segments);
  // Forget deleted hypotheses.
  std::erase_if(objects_, [&](const auto& entry) { return entry.second.touched != sequence; });

  if (config_.free_space && evidence.visibility != nullptr) {
    mark_candidates(current, scan, evidence.segments, hypotheses);
    // Each logged scan is tested against the scan free_space_lag_scans later (a walker has left
    // its place within half a second) and against the newest scan before it leaves the log (a
    // person who stood for a while may leave later). A resting sensor's scans, one range
    // comparison per candidate, are also tested at twice, four times ... the lag.
    const auto lag = static_cast<std::size_t>(config_.free_space_lag_scans);
    const auto release = static_cast<std::size_t>(config_.log_delay_scans);
    for (std::size_t l = lag; l < log_.size() && l < release; l *= 2) {
      clear_seen_through(log_[log_.size() - 1 - l], *evidence.visibility, pose, l == lag);
    }
    if (log_.size() > release) clear_seen_through(log_.front(), *evidence.visibility, pose, true);
  }
  while (log_.size() > static_cast<std::size_t>(config_.log_delay_scans)) release_front();
  bound_map(pose);
  return result_;
}

void DynamicObjectFilter::bound_map(const core::Pose& pose) {
  if (config_.map_radius_m <= 0.0) return;
  // One pass over a map of millions of voxels costs tens of milliseconds (measured: 57 ms in
  // one scan of the town drive); a sweep in slices checks every voxel once per kSweepScans
  // scans at a tenth of that per scan.
  if (sweep_cursor_ == 0) sweep_cursor_ = map_.size();
  const std::size_t visits =
      std::max<std::size_t>(kMinSweepVisits, (map_.size() + kSweepScans - 1) / kSweepScans);
  result_.map_voxels_evicted += map_.remove_outside(pose.translation.head<2>().cast<float>(),
                                                    static_cast<float>(config_.map_radius_m),
                                                    evicted_, sweep_cursor_, visits);
}

void DynamicObjectFilter::mark_candidates(LoggedScan& logged, const core::OrganizedScan& scan,
                                          const std::vector<std::uint8_t>* segments,
                                          const std::vector<tracking::Hypothesis>& hypotheses) {
  logged.candidates.clear();
  logged.candidate_ranges.clear();
  // Segmented points are candidates while the sensor rests, where a later scan tests them with
  // one range comparison per cell. From a moving sensor every candidate costs a projection and
  // a segmented scene (a hall, a park) has thousands: there only the hypotheses' surroundings
  // are tested, and only with free_space_moving (docs/BENCHMARK.md, issue 12).
  const bool resting = log_.size() >= 2 && same_view(log_[log_.size() - 2], scan, logged.pose);
  if (!resting && !config_.free_space_moving) return;
  // Near every person or dynamic hypothesis: a head above its box, legs below it, an arm beside
  // it (the points the boxes miss, docs/BENCHMARK.md, issue 12), and people never found dynamic.
  // Not near other clutter: a moving sensor's park has hundreds of such hypotheses (trees,
  // bushes), whose surroundings would cost a projection per point and hold no walker.
  const auto reach = static_cast<float>(config_.free_space_reach_m);
  near_boxes_.clear();
  for (const auto& h : hypotheses) {
    if (h.box.empty() || !(h.person || h.ever_dynamic)) continue;
    near_boxes_.push_back({h.box.min.array() - reach, h.box.max.array() + reach});
  }
  const std::uint8_t* segmented = segments != nullptr && resting ? segments->data() : nullptr;
  // One pass over the points, block by block: the near boxes meet few blocks.
  const std::size_t n = logged.points.size();
  const bool bounded = logged.bounded_points == n;
  for (std::size_t b = 0; b * LoggedScan::kBlockPoints < n; ++b) {
    near_block_.clear();
    for (const auto& box : near_boxes_) {
      if (!bounded || logged.block_bounds[b].intersects(box)) near_block_.push_back(&box);
    }
    const std::size_t end = std::min(n, (b + 1) * LoggedScan::kBlockPoints);
    for (std::size_t i = b * LoggedScan::kBlockPoints; i < end; ++i) {
      bool candidate = segmented != nullptr && segmented[logged.cells[i]] != 0;
      for (std::size_t k = 0; !candidate && k < near_block_.size(); ++k) {
        candidate = near_block_[k]->contains(logged.points[i]);
      }
      if (!candidate) continue;
      logged.candidates.push_back(static_cast<std::uint32_t>(i));
      logged.candidate_ranges.push_back(scan.range_m(logged.cells[i]));
    }
  }
}

void DynamicObjectFilter::clear_seen_through(LoggedScan& logged,
                                             const core::VisibilityQuery& visibility,
                                             const core::Pose& pose, bool moved_too) {
  const core::OrganizedScan& now = visibility.scan();
  const bool resting = same_view(logged, now, pose);
  if (!resting && !(moved_too && config_.free_space_moving)) return;
  const auto margin = static_cast<float>(config_.free_space_margin_m);
  for (std::size_t k = 0; k < logged.candidates.size(); ++k) {
    const std::uint32_t i = logged.candidates[k];
    if (logged.removed[i] != 0) continue;
    if (resting) {
      // The same beam: one range comparison, no projection.
      const std::uint32_t cell = logged.cells[i];
      if (now.status(cell) != core::ReturnStatus::kValid ||
          !(now.range_m(cell) > logged.candidate_ranges[k] + margin)) {
        continue;
      }
    } else {
      if (!visibility.sees_through(logged.points[i].cast<double>(), config_.free_space_margin_m,
                                   config_.free_space_lateral_m, config_.free_space_clearance_m)) {
        continue;
      }
    }
    // Structure the map has seen occupied many times stays: range noise and mixed returns at
    // edges see through a few of its points now and then.
    const MapPoint* voxel = map_.voxel_at(logged.points[i]);
    if (voxel != nullptr &&
        voxel->count >= static_cast<std::uint32_t>(config_.free_space_protect_count)) {
      ++result_.free_space_protected;
      continue;
    }
    logged.removed[i] = 1;
    ++logged.removed_count;
    ++result_.free_space_points;
  }
}

void DynamicObjectFilter::note_transient_candidates(LoggedScan& logged,
                                                    const std::vector<std::uint8_t>& segments) {
  if (config_.transient_scans <= 0 || !ground_z_m_) return;
  const auto min_z = static_cast<float>(*ground_z_m_ + config_.transient_min_height_m);
  for (std::size_t i = 0; i < logged.points.size(); ++i) {
    // Points a track already removed are not noted: a walker's place confirms no later walker.
    if (segments[logged.cells[i]] == 0 || logged.removed[i] != 0) continue;
    if (!(logged.points[i].z() >= min_z)) continue;
    // The key now, while the point is in cache: the scan is judged 50 scans later. A point
    // without a cell (beyond the grid's +-2^30 cells) is never judged.
    const std::uint64_t key = transient_grid_.key(logged.points[i]);
    if (key == TransientGrid::kNoCell) continue;
    logged.transient_candidates.push_back(static_cast<std::uint32_t>(i));
    logged.transient_keys.push_back(key);
  }
  transient_grid_.note(logged.transient_keys, logged.sequence);
}

void DynamicObjectFilter::remove_transient(LoggedScan& scan) {
  const auto k = static_cast<std::uint64_t>(std::max(0, config_.transient_scans));
  // Judged only with k later scans logged: the end of a run (flush) leaves its last scans alone,
  // as does a log shorter than k.
  if (k == 0 || next_sequence_ < scan.sequence + k + 1) return;
  const auto protect = static_cast<std::uint32_t>(config_.free_space_protect_count);
  transient_out_.clear();
  transient_grid_.unconfirmed(scan.transient_keys, scan.sequence, k, transient_out_);
  for (const std::uint32_t j : transient_out_) {
    const std::uint32_t i = scan.transient_candidates[j];
    if (scan.removed[i] != 0) continue;
    // Structure the map holds many points of stays (a post seen long ago, then not segmented).
    const MapPoint* voxel = map_.voxel_at(scan.points[i]);
    if (voxel != nullptr && voxel->count >= protect) continue;
    scan.removed[i] = 1;
    ++scan.removed_count;
    ++result_.transient_points;
  }
}

const FilterResult& DynamicObjectFilter::flush() {
  result_ = FilterResult{};
  result_.sequence = next_sequence_ == 0 ? 0 : next_sequence_ - 1;
  released_.clear();
  evicted_.clear();
  while (!log_.empty()) release_front();
  return result_;
}

}  // namespace ringtrack::mapping
