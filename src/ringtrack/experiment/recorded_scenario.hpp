#pragma once
/// A simulated scenario kept in memory in compact form, so that the pipeline can be run on the
/// same scans many times (parameter tuning) without simulating them again.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace ringtrack::experiment {

/// Every scan of one scenario run, simulated once. Only cells with a return are stored (about
/// 12 bytes each instead of 25 per cell); expand() rebuilds a scan that is bit-identical to the
/// simulator's, so a replayed run gives the same results as a simulated one.
class RecordedScenario {
 public:
  /// Simulates every scan of the scenario (its duration as given) with this seed. With deskew,
  /// moving-sensor scans are motion-compensated on expansion, as `ringtrack benchmark` does.
  RecordedScenario(const sim::Scenario& scenario, std::uint64_t seed, bool deskew = true);

  /// The scenario as simulated.
  [[nodiscard]] const sim::Scenario& scenario() const { return scenario_; }
  /// The simulator's sensor model.
  [[nodiscard]] const core::SensorModel& model() const { return model_; }
  /// Simulator seed.
  [[nodiscard]] std::uint64_t seed() const { return seed_; }
  /// Whether the sensor moves (any motion other than static).
  [[nodiscard]] bool moving() const;
  /// Whether moving-sensor scans are deskewed on expansion.
  [[nodiscard]] bool deskew() const { return deskew_; }
  /// Number of scans.
  [[nodiscard]] std::size_t size() const { return scans_.size(); }
  /// Bytes held by the recorded scans (approximate: vector payloads).
  [[nodiscard]] std::size_t memory_bytes() const;
  /// Rebuilds scan k into out (reusing its buffers) and the pose to give the pipeline: the
  /// simulator's pose, or the deskewed scan's pose for a moving sensor with deskew.
  void expand(std::size_t k, sim::SimulatedScan& out, core::Pose& pipeline_pose) const;

 private:
  struct CompactScan {
    std::int64_t stamp_ns{0};
    core::Pose pose;                   // sensor in world at the first column
    core::Pose next_pose;              // at the next scan's start, for deskew
    std::vector<std::uint32_t> cells;  // cells that are not kNoReturn
    std::vector<float> range_m;        // per stored cell; out-of-range stand-ins for invalid ones
    std::vector<float> intensity;
    std::vector<std::uint32_t> labels;  // per stored cell
    std::vector<sim::ObjectTruth> objects;
  };
  CompactScan compact(const sim::SimulatedScan& scan) const;
  /// Per-ring elevation and per-cell azimuth terms of SensorModel::point, so that expand() needs
  /// no trigonometry; the arithmetic is point()'s own, so the points are bit-identical.
  void precompute_directions();
  /// Cell i's point at range_m, as SensorModel::point computes it.
  [[nodiscard]] Eigen::Vector3f point(std::size_t i, double range_m) const;

  sim::Scenario scenario_;
  core::SensorModel model_;
  std::uint64_t seed_{1};
  bool deskew_{true};
  std::vector<CompactScan> scans_;
  std::vector<double> cos_el_, sin_el_;  // per ring
  std::vector<double> cos_az_, sin_az_;  // per cell (uniform columns plus the ring's offset)
};

}  // namespace ringtrack::experiment
