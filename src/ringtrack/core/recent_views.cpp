#include "ringtrack/core/recent_views.hpp"

#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "ringtrack/core/error.hpp"

namespace ringtrack::core {

RecentViews::RecentViews(const SensorModel& model, const BackgroundRangeConfig& config)
    : model_(model),
      lateral_m_(config.moving_lateral_m),
      clearance_m_(config.moving_clearance_m),
      column_m_(config.moving_column_m),
      column_ground_m_(config.moving_column_ground_m) {
  if (config.moving_lag_scans < 1 || config.moving_lag_scans > 250) {
    throw ConfigError("background.moving_lag_scans must lie in [1, 250], got " +
                      std::to_string(config.moving_lag_scans));
  }
  if (!(lateral_m_ >= 0.0) || !std::isfinite(lateral_m_)) {
    throw ConfigError("background.moving_lateral_m must be finite and >= 0");
  }
  if (!(clearance_m_ >= 0.0) || !std::isfinite(clearance_m_)) {
    throw ConfigError("background.moving_clearance_m must be finite and >= 0");
  }
  if (!(column_m_ >= 0.0) || !std::isfinite(column_m_)) {
    throw ConfigError("background.moving_column_m must be finite and >= 0");
  }
  if (!(column_ground_m_ >= 0.0) || !std::isfinite(column_ground_m_)) {
    throw ConfigError("background.moving_column_ground_m must be finite and >= 0");
  }
  // Doubling lags: a walker has left its place by the first, a slow one by the last.
  lags_ = {config.moving_lag_scans, 2 * config.moving_lag_scans, 4 * config.moving_lag_scans};
  views_.resize(static_cast<std::size_t>(lags_.back()));
}

void RecentViews::add(const OrganizedScan& scan, const Pose& pose, const Motion& motion) {
  add(scan, pose, motion, std::make_shared<const BeamGeometry>(scan, model_));
}

void RecentViews::add(const OrganizedScan& scan, const Pose& pose, const Motion& motion,
                      std::shared_ptr<const BeamGeometry> geometry) {
  View& view = views_[next_];
  view.query.reset();  // it points at the scan about to be overwritten
  view.scan = scan;    // same size as before: the buffers are reused, nothing is allocated
  view.query.emplace(view.scan, std::move(geometry), pose, motion);
  next_ = (next_ + 1) % views_.size();
  count_ = std::min(count_ + 1, views_.size());
}

void RecentViews::reset() {
  for (auto& view : views_) view.query.reset();
  next_ = 0;
  count_ = 0;
}

const RecentViews::View* RecentViews::view_back(int lag) const {
  // The newest view is the previous scan (lag 1).
  const auto back = static_cast<std::size_t>(lag);
  if (back > count_) return nullptr;
  return &views_[(next_ + views_.size() - back) % views_.size()];
}

bool RecentViews::seen_free_before(const OrganizedScan& scan, std::size_t cell,
                                   const Eigen::Vector3d& world_point, double margin_m) const {
  static_cast<void>(scan);
  static_cast<void>(cell);
  for (const int lag : lags_) {
    const View* view = view_back(lag);
    if (view == nullptr) break;
    const PointProbe probe = view->query->probe(world_point, margin_m);
    if (view->query->sees_through(world_point, probe, margin_m, lateral_m_, clearance_m_)) {
      return true;
    }
    // A beam that passed the point itself and ended at it says something stood there: the
    // column, a fallback for points no earlier beam passed closely, is not asked.
    const bool hit_there =
        probe.visibility == Visibility::kOccupied && probe.lateral_m <= lateral_m_;
    if (column_m_ > 0.0 && !hit_there && column_seen_free(*view->query, world_point, margin_m)) {
      return true;
    }
  }
  return false;
}

// Why a column: at 70 m a VLP-16's rings lie 2.4 m apart, and a moving sensor's earlier scan
// rarely has a beam within moving_lateral_m of a point one ring hit now. But a person (or a post,
// a car, a wall) stands on the ground and fills the space under its hits; an earlier beam that
// passed through that column below the point and ended beyond it saw the place empty. A beam
// ending inside or before the column (the post, an occluder) vetoes. Floating structure (an
// overhang, a sign on a thin pole, a tree crown above the trunk's side) passes the test: the
// detector's altitude and height tests and the tracker's dynamic test stand behind it.
bool RecentViews::column_seen_free(const VisibilityQuery& query, const Eigen::Vector3d& point,
                                   double margin_m) const {
  const double top = point.z() - clearance_m_;
  const double bottom = ground_z_m_ + column_ground_m_;
  if (top - bottom < 0.1) return false;
  const Box3 column{
      Eigen::Vector3f(static_cast<float>(point.x() - column_m_),
                      static_cast<float>(point.y() - column_m_), static_cast<float>(bottom)),
      Eigen::Vector3f(static_cast<float>(point.x() + column_m_),
                      static_cast<float>(point.y() + column_m_), static_cast<float>(top))};
  return query.seen_through_box(column, margin_m);
}

}  // namespace ringtrack::core
