#pragma once
/// Scene memory of a moving sensor: what its recent scans saw through, from their own viewpoints.

#include <cstdint>
#include <optional>
#include <vector>

#include "ringtrack/core/config.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/scene_memory.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/core/visibility.hpp"

namespace ringtrack::core {

/// Keeps the last scans of a moving sensor (copies, with their poses and motions) and answers,
/// for a point of the current scan, whether one of the scans moving_lag_scans, twice and four
/// times that many scans back (BackgroundRangeConfig) saw through that space from where it stood
/// (VisibilityQuery::sees_through): something is there now that was not then, as a walker hit
/// by one or two beams far away. The resting sensor's counterpart is BackgroundRangeModel,
/// which compares ranges cell by cell instead.
class RecentViews : public SceneMemory {
 public:
  /// Throws ConfigError naming the parameter when one of the moving_* keys is out of range.
  explicit RecentViews(const SensorModel& model, const BackgroundRangeConfig& config = {});

  /// Adds a motion-compensated scan with its pose (at scan.stamp_ns) and its sweep's motion.
  void add(const OrganizedScan& scan, const Pose& pose, const Motion& motion);
  /// The same with the scan's beam geometry (BeamGeometry::fits the scan), shared, not rebuilt.
  void add(const OrganizedScan& scan, const Pose& pose, const Motion& motion,
           std::shared_ptr<const BeamGeometry> geometry);
  /// Forgets every scan.
  void reset();
  /// The ground's z in the frame of the poses (the column test stops above it).
  void set_ground_z(double z_m) { ground_z_m_ = z_m; }
  /// Scans kept (at most four times moving_lag_scans).
  [[nodiscard]] std::size_t scans() const { return count_; }

  /// SceneMemory: whether one of those scans saw through world_point by more than
  /// margin_m (false while no such scan is kept).
  [[nodiscard]] bool seen_free_before(const OrganizedScan& scan, std::size_t cell,
                                      const Eigen::Vector3d& world_point,
                                      double margin_m) const override;

 private:
  struct View {
    OrganizedScan scan;
    std::optional<VisibilityQuery> query;  // over `scan`, which stays in place
  };
  [[nodiscard]] const View* view_back(int lag) const;
  [[nodiscard]] bool column_seen_free(const VisibilityQuery& query, const Eigen::Vector3d& point,
                                      double margin_m) const;

  SensorModel model_;
  std::vector<int> lags_;  // scans back, ascending
  double lateral_m_;
  double clearance_m_;
  double column_m_;
  double column_ground_m_;
  double ground_z_m_{0.0};
  std::vector<View> views_;  // ring buffer of the largest lag's size
  std::size_t next_{0};
  std::size_t count_{0};
};

}  // namespace ringtrack::core
