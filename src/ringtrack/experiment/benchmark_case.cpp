#include "ringtrack/experiment/benchmark_case.hpp"

#include <algorithm>
#include <chrono>
#include <deque>
#include <functional>
#include <map>
#include <set>
#include <stdexcept>

#include "ringtrack/eval/statistics.hpp"
#include "ringtrack/pipeline/deskew.hpp"

namespace ringtrack::experiment {
namespace {

using Clock = std::chrono::steady_clock;

double seconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

// Point counts of released scans, by object id (0 = background), until the run ends and the
// objects that ever moved are known.
struct PointTally {
  std::int64_t points = 0;
  std::int64_t removed = 0;
};

// Fills scan k and the pose to give the pipeline.
using ScanFeed = std::function<void(std::int64_t k, sim::SimulatedScan&, core::Pose&)>;

// The points the filter kept, counted by the map voxel they went into (background points and
// each object's apart), so that the map at the end of the run can be asked which of them it
// still holds (BenchmarkCase::final_map).
class KeptByVoxel {
 public:
  // One kept point of grid cell `cell` with its ground-truth label (0 = background).
  void add(const mapping::StaticMap& map, std::uint32_t cell, const Eigen::Vector3f& point,
           std::uint32_t label) {
    const auto key = map.key_of(point);
    if (!key) return;  // the map dropped it too
    // The voxel the cell's point fell in last time is tried first, before the hash table.
    if (cell >= cell_key_.size()) {
      cell_key_.resize(cell + 1, kNoKey);
      cell_voxel_.resize(cell + 1, 0);
    }
    if (cell_key_[cell] != *key) {
      cell_key_[cell] = *key;
      cell_voxel_[cell] = voxel_of(*key, point);
    }
    const std::size_t v = cell_voxel_[cell];
    if (label == 0) {
      ++background_[v];
    } else {
      ++objects_[{v, label}];
    }
  }

  // `counts` (the per-scan decisions) with every kept point whose voxel the final map no
  // longer holds (a later decision removed it: an object's static era older than the log,
  // docs/evaluation.md) counted as removed.
  [[nodiscard]] eval::MapCounts final_counts(
      const mapping::StaticMap& map, eval::MapCounts counts,
      const std::function<bool(std::int64_t)>& is_dynamic) const {
    std::vector<char> gone(point_.size(), 0);
    for (std::size_t v = 0; v < point_.size(); ++v) {
      if (map.voxel_at(point_[v]) != nullptr) continue;
      gone[v] = 1;
      counts.static_kept -= background_[v];
    }
    for (const auto& [voxel_and_id, n] : objects_) {
      if (!gone[voxel_and_id.first]) continue;
      if (is_dynamic(voxel_and_id.second)) {
        counts.dynamic_removed += n;
      } else {
        counts.static_kept -= n;
      }
    }
    return counts;
  }

 private:
  static constexpr std::uint64_t kNoKey = ~std::uint64_t{0};  // no voxel key is all ones

  // The index of the voxel with this key, added (with point as its representative) if new. A
  // flat table with linear probing: with std::unordered_map's chained buckets this tally took
  // 23 % of a benchmark run's samples (perf, crowd, static, 30 s), 13 % with this table.
  std::size_t voxel_of(std::uint64_t key, const Eigen::Vector3f& point) {
    if (2 * (point_.size() + 1) > table_keys_.size()) grow_table();
    const std::size_t mask = table_keys_.size() - 1;
    for (std::size_t s = slot_of(key, mask);; s = (s + 1) & mask) {
      if (table_keys_[s] == key) return table_voxels_[s];
      if (table_keys_[s] == kNoKey) {
        table_keys_[s] = key;
        table_voxels_[s] = point_.size();
        point_.push_back(point);
        background_.push_back(0);
        return table_voxels_[s];
      }
    }
  }

  static std::size_t slot_of(std::uint64_t key, std::size_t mask) {
    return static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ULL) >> 20) & mask;
  }

  void grow_table() {
    std::vector<std::uint64_t> keys(std::max<std::size_t>(1024, 2 * table_keys_.size()), kNoKey);
    std::vector<std::size_t> voxels(keys.size(), 0);
    const std::size_t mask = keys.size() - 1;
    for (std::size_t i = 0; i < table_keys_.size(); ++i) {
      if (table_keys_[i] == kNoKey) continue;
      std::size_t s = slot_of(table_keys_[i], mask);
      while (keys[s] != kNoKey) s = (s + 1) & mask;
      keys[s] = table_keys_[i];
      voxels[s] = table_voxels_[i];
    }
    table_keys_ = std::move(keys);
    table_voxels_ = std::move(voxels);
  }

  std::vector<std::uint64_t> table_keys_;  // open addressing, a power of two; kNoKey = empty
  std::vector<std::size_t> table_voxels_;  // index of the voxel in the slot
  std::vector<Eigen::Vector3f> point_;     // per voxel: a kept point in it
  std::vector<std::int64_t> background_;   // per voxel: kept background points
  std::map<std::pair<std::size_t, std::int64_t>, std::int64_t> objects_;  // (voxel, id): points
  std::vector<std::uint64_t> cell_key_;  // per grid cell: the key of its last kept point's voxel
  std::vector<std::size_t> cell_voxel_;  // ... and that voxel's index
};

// Ground truth, tracks and map tallies gathered over one run.
class CaseRecorder {
 public:
  void add_truth(std::int64_t k, const sim::SimulatedScan& scan) {
    for (const sim::ObjectTruth& o : scan.objects) {
      if (o.moving) ever_moving_.insert(o.id);
      ground_truth_.push_back({k, static_cast<std::int64_t>(o.id),
                               std::string(sim::class_name(o.object_class)), o.hit_points,
                               o.centroid_m.cast<double>(), o.body_center_m.cast<double>()});
    }
    pending_labels_.push_back(scan.labels);
  }

  void add_result(std::int64_t k, const pipeline::FrameResult& result, StageSeries& times) {
    for (const tracking::Hypothesis& h : result.hypotheses) {
      if (!h.reported) continue;
      // Back in the frame of the poses and the ground truth (the pipeline's is local).
      tracks_.push_back({k, static_cast<std::int64_t>(h.id), h.reported_position + result.origin,
                         h.dynamic, h.ever_dynamic, h.person});
    }
    times.segmentation.push_back(result.times.segmentation_ms);
    times.detection.push_back(result.times.detection_ms);
    times.tracking.push_back(result.times.tracking_ms);
    times.mapping.push_back(result.times.mapping_ms);
    times.total.push_back(result.times.total_ms);
  }

  // Ground truth from a table (recorded sequences): no labels, so no map figures.
  void set_truth(std::vector<eval::GroundTruthObject> rows) {
    ground_truth_ = std::move(rows);
    with_map_ = false;
  }

  // Without a map radius every voxel stays in memory, so the final map can be asked which
  // voxels of the kept points it still holds (final_map_counts).
  void follow_final_map(bool on) { with_final_map_ = on; }

  // Tallies the points of the scans the filter released (its decisions are final), and the
  // kept ones by map voxel.
  void count_released(const pipeline::Pipeline& pipeline) {
    if (!with_map_) return;
    const mapping::StaticMap& map = pipeline.static_map();
    for (const mapping::LoggedScan& logged : pipeline.dynamic_filter().released()) {
      const std::vector<std::uint32_t>& labels = pending_labels_.front();
      for (std::size_t p = 0; p < logged.cells.size(); ++p) {
        const std::uint32_t label = labels[logged.cells[p]];
        PointTally& t = tally_[label];
        ++t.points;
        t.removed += logged.removed[p] ? 1 : 0;
        if (with_final_map_ && !logged.removed[p]) {
          kept_by_voxel_.add(map, logged.cells[p], logged.points[p], label);
        }
      }
      pending_labels_.pop_front();
    }
  }

  // final_map: the pipeline's map after the run (nullptr: no final-map figures).
  void evaluate(const BenchmarkCaseOptions& options, BenchmarkCase& out,
                const mapping::StaticMap* final_map = nullptr) const {
    for (const auto& [id, t] : tally_) {
      if (is_dynamic(id)) {
        out.map.dynamic_points += t.points;
        out.map.dynamic_removed += t.removed;
      } else {
        out.map.static_points += t.points;
        out.map.static_kept += t.points - t.removed;
      }
    }
    if (with_map_ && with_final_map_ && final_map != nullptr) {
      out.final_map = kept_by_voxel_.final_counts(
          *final_map, out.map, [this](std::int64_t id) { return is_dynamic(id); });
    }
    out.tracking = eval::evaluate_tracks(ground_truth_, tracks_, options.evaluation);
    if (options.person_figures) {
      eval::TrackingEvalOptions person = options.evaluation;
      person.hypotheses = eval::HypothesisSelection::kPerson;
      out.person = eval::evaluate_tracks(ground_truth_, tracks_, person);
    }
  }

 private:
  [[nodiscard]] bool is_dynamic(std::int64_t id) const {
    return id != 0 && ever_moving_.count(id) != 0;
  }

  std::vector<eval::GroundTruthObject> ground_truth_;
  std::vector<eval::TrackObservation> tracks_;
  std::set<std::int64_t> ever_moving_;
  std::map<std::int64_t, PointTally> tally_;
  std::deque<std::vector<std::uint32_t>> pending_labels_;  // of the scans in the filter's log
  bool with_map_ = true;
  bool with_final_map_ = false;
  KeptByVoxel kept_by_voxel_;
};

BenchmarkCase run_case(const sim::Scenario& scenario, const core::SensorModel& model,
                       std::int64_t scans, const ScanFeed& feed, const core::Config& config,
                       const BenchmarkCaseOptions& options) {
  BenchmarkCase out;
  out.scenario = scenario.number;
  out.name = scenario.name;
  out.moving = scenario.sensor.motion != sim::SensorMotion::kStatic;
  out.scans = scans;
  // The simulator knows how high its sensor stands above the ground, and the pipeline is told, as
  // users tell it of theirs: the altitude test then counts from the scenario's ground.
  core::Config effective = config;
  effective.detection.sensor_height_m =
      sim::sensor_pose(scenario.sensor, 0).translation.z() - scenario.ground.height_m;
  pipeline::Pipeline pipeline(effective, model);
  CaseRecorder recorder;
  recorder.follow_final_map(options.final_map && effective.mapping.map_radius_m <= 0.0);
  sim::SimulatedScan scan;
  core::Pose pose;
  for (std::int64_t k = 0; k < scans; ++k) {
    if (options.interrupt != nullptr && options.interrupt->load()) {
      out.interrupted = true;
      return out;
    }
    const auto t0 = Clock::now();
    feed(k, scan, pose);
    const auto t1 = Clock::now();
    recorder.add_truth(k, scan);
    const auto t2 = Clock::now();
    if (options.odometry && k == 0) pipeline.set_odometry_start(pose);
    const auto& result = options.odometry ? pipeline.process_with_odometry(scan.scan)
                                          : pipeline.process(scan.scan, pose);
    const auto t3 = Clock::now();
    if (options.on_scan) options.on_scan(scan, result);
    recorder.add_result(k, result, out.times);
    recorder.count_released(pipeline);
    out.simulate_s += seconds(t0, t1);
    out.pipeline_s += seconds(t2, t3);
  }
  const auto t4 = Clock::now();
  pipeline.finish();
  out.pipeline_s += seconds(t4, Clock::now());
  recorder.count_released(pipeline);
  recorder.evaluate(options, out, &pipeline.static_map());
  return out;
}

// Processes every scan of a recorded sequence and records the results.
void run_scans(const RecordedSequence& recorded, const core::Config& config, CaseRecorder& recorder,
               BenchmarkCase& out) {
  pipeline::Pipeline pipeline(config, recorded.model());
  for (std::size_t k = 0; k < recorded.size(); ++k) {
    const auto t0 = Clock::now();
    const auto& result = pipeline.process(recorded.scan(k), recorded.pose(k));
    out.pipeline_s += seconds(t0, Clock::now());
    recorder.add_result(static_cast<std::int64_t>(k), result, out.times);
  }
  const auto t1 = Clock::now();
  pipeline.finish();
  out.pipeline_s += seconds(t1, Clock::now());
}

}  // namespace

StageStats stats_of(const std::vector<double>& series) {
  if (series.empty()) return {};
  return {eval::quantile(series, 0.5), eval::quantile(series, 0.95),
          *std::max_element(series.begin(), series.end())};
}

const std::vector<std::pair<const char*, std::vector<double> StageSeries::*>>& stage_members() {
  static const std::vector<std::pair<const char*, std::vector<double> StageSeries::*>> kStages = {
      {"segmentation", &StageSeries::segmentation},
      {"detection", &StageSeries::detection},
      {"tracking", &StageSeries::tracking},
      {"mapping", &StageSeries::mapping},
      {"total", &StageSeries::total}};
  return kStages;
}

core::Pose next_simulated_scan(sim::Simulator& simulator, sim::SimulatedScan& scan, bool deskew) {
  const std::int64_t k = simulator.next_index();
  simulator.next(scan);
  if (!deskew) return scan.pose;
  const std::int64_t next = simulator.scan_stamp_ns(k + 1);
  return pipeline::deskew_scan(scan.scan, scan.pose, simulator.sensor_pose_at(next));
}

BenchmarkCase run_benchmark_case(const sim::Scenario& scenario, const core::Config& config,
                                 const BenchmarkCaseOptions& options) {
  sim::Simulator simulator(scenario, options.seed);
  const bool deskew =
      scenario.sensor.motion != sim::SensorMotion::kStatic && options.deskew && !options.odometry;
  const ScanFeed feed = [&](std::int64_t, sim::SimulatedScan& scan, core::Pose& pose) {
    pose = next_simulated_scan(simulator, scan, deskew);
  };
  return run_case(scenario, simulator.model(), simulator.scan_count(), feed, config, options);
}

BenchmarkCase run_benchmark_case(const RecordedScenario& recorded, const core::Config& config,
                                 const BenchmarkCaseOptions& options) {
  if (options.odometry && recorded.deskew() && recorded.moving()) {
    throw std::invalid_argument(
        "benchmark case: the odometry needs the scans as measured, and this recording of '" +
        recorded.scenario().name + "' was deskewed with the true poses");
  }
  const ScanFeed feed = [&](std::int64_t k, sim::SimulatedScan& scan, core::Pose& pose) {
    recorded.expand(static_cast<std::size_t>(k), scan, pose);
  };
  return run_case(recorded.scenario(), recorded.model(), static_cast<std::int64_t>(recorded.size()),
                  feed, config, options);
}

BenchmarkCase run_benchmark_case(const RecordedSequence& recorded, const core::Config& config,
                                 const BenchmarkCaseOptions& options) {
  if (options.odometry) {
    throw std::invalid_argument("benchmark case: the odometry is not supported on sequence '" +
                                recorded.name() + "' (its scans are read deskewed)");
  }
  BenchmarkCase out;
  out.name = recorded.name();
  out.moving = recorded.moving();
  out.scans = static_cast<std::int64_t>(recorded.size());
  CaseRecorder recorder;
  recorder.set_truth(recorded.ground_truth());
  run_scans(recorded, config, recorder, out);
  recorder.evaluate(options, out);
  return out;
}

}  // namespace ringtrack::experiment
