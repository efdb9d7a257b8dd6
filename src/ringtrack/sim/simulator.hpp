#pragma once
/// The spinning-LiDAR simulator: casts every firing of a core::SensorModel through a Scenario's
/// world, from the sensor pose at that firing's column time, against actors moved to that time,
/// and returns organized scans with per-cell object labels and per-object ground truth.

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "ringtrack/core/box3.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/sim/actors.hpp"
#include "ringtrack/sim/geometry.hpp"
#include "ringtrack/sim/scenario.hpp"

namespace ringtrack::sim {

/// Ground truth of one object in one scan (world frame).
struct ObjectTruth {
  std::uint32_t id{0};
  ObjectClass object_class{ObjectClass::kPerson};
  int hit_points{0};  ///< valid returns labelled with this id
  Eigen::Vector3f centroid_m{Eigen::Vector3f::Constant(
      std::numeric_limits<float>::quiet_NaN())};  ///< of the true (noise-free) hit points; NaN
                                                  ///< without hits
  core::Box3 box;                                 ///< of the true hit points; empty without hits
  Eigen::Vector3f body_center_m{
      Eigen::Vector3f::Zero()};  ///< at the mean time of its hits (else mid-scan)
  Eigen::Vector3f velocity_mps{Eigen::Vector3f::Zero()};
  bool moving{false};  ///< speed above 0.1 m/s
};

/// One simulated revolution.
struct SimulatedScan {
  std::int64_t index{0};              ///< 0-based scan number
  core::OrganizedScan scan;           ///< sensor frame, per-column stamps
  std::vector<std::uint32_t> labels;  ///< per cell: object id, 0 = background / no return
  core::Pose pose;                    ///< sensor in world at scan.stamp_ns (the first column)
  std::vector<ObjectTruth> objects;   ///< every actor present in this scan, sorted by id
};

/// Scenario + seed -> deterministic sequence of scans (no disk access).
class Simulator {
 public:
  /// Validates the scenario; model defaults to the scenario's sensor model.
  Simulator(Scenario scenario, std::uint64_t seed, std::optional<core::SensorModel> model = {});

  /// The sensor model in use.
  [[nodiscard]] const core::SensorModel& model() const { return model_; }
  /// The scenario.
  [[nodiscard]] const Scenario& scenario() const { return scenario_; }
  /// Scans in the scenario's duration.
  [[nodiscard]] std::int64_t scan_count() const;
  /// Index of the next scan.
  [[nodiscard]] std::int64_t next_index() const { return next_index_; }
  /// Simulates the next revolution.
  SimulatedScan next();
  /// Same as next() but reuses out's buffers (no allocation after the first call).
  void next(SimulatedScan& out);
  /// Sensor-to-world pose at time t_ns.
  [[nodiscard]] core::Pose sensor_pose_at(std::int64_t t_ns) const;
  /// Start time of scan k.
  [[nodiscard]] std::int64_t scan_stamp_ns(std::int64_t k) const;
  /// Tests every primitive for every ray instead of the angular bins (the naive reference).
  void set_use_bins(bool on) { use_bins_ = on; }
  /// The actors (ids and classes).
  [[nodiscard]] const std::vector<Actor>& actors() const { return world_.actors(); }

 private:
  // What the rays of one scan found on one actor: the ground truth's hit count, centroid, box
  // and the mean time offset of its hits from mid-scan.
  struct ActorHits {
    int n{0};
    Eigen::Vector3d sum{Eigen::Vector3d::Zero()};
    double sum_dt{0.0};
    core::Box3 box;
  };
  void build_bins(const Eigen::Vector3d& ref, double sensor_sweep_m, double scan_s);
  // The actors present at t_mid (state, velocity, body primitives after the static ones).
  void place_actors(std::int64_t t_mid);
  // The sensor's rotation and position at each column's firing time (col_rot_, col_pos_);
  // returns how far the beam origins sweep from the mid-scan position (for the bins).
  double place_columns(const core::OrganizedScan& scan, std::int64_t t_mid);
  // Nearest primitive the ray o + t d meets before `best` (updated), a moving one shifted back
  // by its velocity times dt; -1 when none is nearer.
  std::int64_t nearest_hit(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double dt,
                           double& best) const;
  // Casts every ring of column c into out (range, intensity, label) and accumulates hits.
  void cast_column(int c, std::int64_t t_mid, double t_max, SimulatedScan& out,
                   std::vector<ActorHits>& hits);
  // The ground truth of the present actors from their hits, sorted by id.
  void collect_truth(const std::vector<ActorHits>& hits, SimulatedScan& out) const;

  Scenario scenario_;
  core::SensorModel model_;
  ActorWorld world_;
  Rng noise_rng_;
  std::int64_t next_index_{0};
  bool use_bins_{true};
  std::size_t static_count_{0};
  std::vector<Primitive> prims_;             // static first, then this scan's actor parts
  std::vector<Eigen::Vector3d> velocity_;    // per actor slot
  std::vector<Eigen::Vector3d> sensor_dir_;  // per ring x column, sensor frame
  // Angular bins of primitive indices over world azimuth (CSR), plus primitives seen all around.
  std::vector<std::uint32_t> bin_start_, bin_items_, all_around_;
  struct Span {
    std::uint32_t prim;
    int first, last;  // bin range, may wrap (first > last)
  };
  std::vector<Span> spans_;
  std::vector<Eigen::Matrix3d> col_rot_;
  std::vector<Eigen::Vector3d> col_pos_;
  std::vector<std::uint32_t> bin_fill_;
  std::vector<ActorState> mid_states_;
  std::vector<std::uint8_t> present_;  // per actor slot, this scan
};

/// Reference ray caster: tests every primitive for one ray (no bins); for tests.
double cast_naive(const std::vector<Primitive>& prims, const Ground& ground,
                  const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_max,
                  std::int64_t* hit_index);

}  // namespace ringtrack::sim
