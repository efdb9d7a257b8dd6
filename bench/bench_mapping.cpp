// Worst-case mapping benchmarks (moving sensor). The median scan says little about real time:
// what matters is the slowest scan. Each benchmark runs a whole sequence per iteration, times
// every scan and reports the per-scan median, p99 and max as counters; the iteration time is
// the sum of the per-scan times.
//
// BM_MappingMovingSequence: the pipeline's stages on built-in scenario 3 (large field, 100 m
//   of open ground) with the sensor on its figure 8, seed 1, as `ringtrack benchmark` runs it;
//   only the dynamic-object filter (the mapping stage) is timed. The map grows to ~1.3 M voxels
//   in 400 scans; each scan adds thousands of new voxels (the ground the rings sweep), and the
//   voxel table has to grow several times (from 1 k to 4 M slots).
// BM_StaticMapGrowthScans: the static map alone, pre-filled with 1 M voxels of ground, then 112
//   synthetic scans of 12.8 k ground points from a sensor driving into unmapped ground (~9.5 k
//   new voxels per scan, 1.0 M -> 2.1 M voxels): the scans during which the table must grow.
// BM_LoggedScanRemoveBox/bounds:{0,1}: one retroactive removal, a person's box (0.8 x 0.8 x
//   2 m, grown by the margin) from a logged VLP-16 scan of 28.9 k points, tested point by point
//   (0) or block by block (1). An object that stood for the whole log before it moved costs
//   log_delay_scans (50) of these in one scan.
// BM_LoggedScanBounds: computing the block bounds of that scan, which every scan pays.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <numbers>
#include <vector>

#include "ringtrack/detection/detector.hpp"
#include "ringtrack/mapping/dynamic_object_filter.hpp"
#include "ringtrack/mapping/static_map.hpp"
#include "ringtrack/pipeline/deskew.hpp"
#include "ringtrack/segmentation/segmenter.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace {

using namespace ringtrack;
using Clock = std::chrono::steady_clock;

struct Quantiles {
  double sum = 0.0, median = 0.0, p99 = 0.0, max = 0.0;
};

Quantiles quantiles(std::vector<double> ms) {
  Quantiles q;
  for (const double t : ms) q.sum += t;
  std::sort(ms.begin(), ms.end());
  const auto at = [&](double f) {
    return ms[static_cast<std::size_t>(f * static_cast<double>(ms.size() - 1))];
  };
  q.median = at(0.5);
  q.p99 = at(0.99);
  q.max = ms.back();
  return q;
}

// Wall time per scan (what real time is about) sets the iteration time and the median, p99 and
// max counters; the process CPU time per scan (cpu_*) is less disturbed by other jobs on a
// shared machine.
void report(benchmark::State& state, const std::vector<double>& wall_ms,
            const std::vector<double>& cpu_ms) {
  const Quantiles wall = quantiles(wall_ms);
  state.SetIterationTime(wall.sum / 1000.0);
  state.counters["median_ms"] = wall.median;
  state.counters["p99_ms"] = wall.p99;
  state.counters["max_ms"] = wall.max;
  const Quantiles cpu = quantiles(cpu_ms);
  state.counters["cpu_sum_ms"] = cpu.sum;
  state.counters["cpu_median_ms"] = cpu.median;
  state.counters["cpu_max_ms"] = cpu.max;
}

// Times one call: wall and process CPU milliseconds.
template <class F>
void timed(F&& f, std::vector<double>& wall_ms, std::vector<double>& cpu_ms) {
  const std::clock_t c0 = std::clock();
  const auto t0 = Clock::now();
  f();
  wall_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  cpu_ms.push_back(1000.0 * static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
}

// The stages of pipeline::Pipeline::process, with the dynamic-object filter timed alone.
void BM_MappingMovingSequence(benchmark::State& state) {
  const auto scans = static_cast<std::int64_t>(state.range(0));
  const sim::Scenario scenario = sim::with_moving_sensor(sim::builtin_scenario("3"));
  const core::Config config;
  std::size_t voxels = 0;
  for (auto _ : state) {
    sim::Simulator simulator(scenario, 1);
    segmentation::Segmenter segmenter(config.segmentation);
    detection::Detector detector(config.detection);
    tracking::Tracker tracker(config.tracking);
    mapping::DynamicObjectFilter filter(config.mapping);
    std::vector<std::uint8_t> labels;
    std::vector<double> wall_ms, cpu_ms;
    sim::SimulatedScan scan;
    for (std::int64_t k = 0; k < scans; ++k) {
      simulator.next(scan);
      const core::Pose pose = pipeline::deskew_scan(
          scan.scan, scan.pose, simulator.sensor_pose_at(simulator.scan_stamp_ns(k + 1)));
      segmenter.segment(scan.scan, labels);
      const auto& detections =
          detector.detect(scan.scan, labels, pose, tracker.predicted_positions(scan.scan.stamp_ns));
      const auto& hypotheses = tracker.update(detections, scan.scan.stamp_ns);
      timed([&] { filter.process(scan.scan, pose, detections, hypotheses); }, wall_ms, cpu_ms);
    }
    voxels = filter.map().size();
    report(state, wall_ms, cpu_ms);
  }
  state.counters["map_voxels"] = static_cast<double>(voxels);
}

constexpr float kVoxelM = 0.1f;

// Ground points on 16 circles (5 m to 80 m) around a sensor at (x, 50 m), 800 per circle.
void ground_scan(float x, std::vector<Eigen::Vector3f>& points) {
  points.clear();
  for (int ring = 0; ring < 16; ++ring) {
    const float radius = 5.0f + 5.0f * static_cast<float>(ring);
    for (int c = 0; c < 800; ++c) {
      const float a = 2.0f * std::numbers::pi_v<float> * static_cast<float>(c) / 800.0f;
      points.emplace_back(x + radius * std::cos(a), 50.0f + radius * std::sin(a), 0.05f);
    }
  }
}

void BM_StaticMapGrowthScans(benchmark::State& state) {
  constexpr int kSide = 1000;  // 1000 x 1000 voxels of ground: 1 M voxels
  constexpr int kScans = 112;
  std::vector<Eigen::Vector3f> base;
  base.reserve(std::size_t{kSide} * kSide);
  for (int i = 0; i < kSide; ++i) {
    for (int j = 0; j < kSide; ++j) {
      base.emplace_back((static_cast<float>(i) + 0.5f) * kVoxelM,
                        (static_cast<float>(j) + 0.5f) * kVoxelM, 0.05f);
    }
  }
  const std::vector<float> base_intensity(base.size(), 10.0f);
  std::vector<Eigen::Vector3f> points;
  const std::vector<float> intensities(16 * 800, 20.0f);
  std::size_t voxels = 0;
  for (auto _ : state) {
    mapping::StaticMap map(kVoxelM);
    map.insert(base, base_intensity, {});
    std::vector<double> wall_ms, cpu_ms;
    for (int k = 0; k < kScans; ++k) {
      // The sensor drives east from the mapped square at 2.5 m per scan.
      ground_scan(100.0f + 2.5f * static_cast<float>(k), points);
      timed([&] { map.insert(points, intensities, {}); }, wall_ms, cpu_ms);
    }
    voxels = map.size();
    report(state, wall_ms, cpu_ms);
  }
  state.counters["map_voxels"] = static_cast<double>(voxels);
}

void BM_LoggedScanRemoveBox(benchmark::State& state) {
  const auto rendered = sim::render(core::SensorModel::vlp16(), sim::SimpleScene::demo());
  mapping::LoggedScan logged;
  for (std::size_t i = 0; i < rendered.scan.size(); ++i) {
    if (rendered.scan.valid(i)) logged.points.push_back(rendered.scan.point(i));
  }
  if (state.range(0) != 0) logged.update_bounds();
  // Around the first labelled object (a person), as the filter grows it.
  core::Box3 box;
  for (std::size_t i = 0; i < rendered.labels.size(); ++i) {
    if (rendered.labels[i] == 1) box.extend(rendered.scan.point(i));
  }
  box = {box.min.array() - 0.1f, box.max.array() + 0.1f};
  std::size_t removed = 0;
  for (auto _ : state) {
    logged.removed.assign(logged.points.size(), 0);
    removed = logged.remove_inside(box);
    benchmark::DoNotOptimize(removed);
  }
  state.counters["points"] = static_cast<double>(logged.points.size());
  state.counters["removed"] = static_cast<double>(removed);
}

// What the block bounds cost: every logged scan computes them once.
void BM_LoggedScanBounds(benchmark::State& state) {
  const auto rendered = sim::render(core::SensorModel::vlp16(), sim::SimpleScene::demo());
  mapping::LoggedScan logged;
  for (std::size_t i = 0; i < rendered.scan.size(); ++i) {
    if (rendered.scan.valid(i)) logged.points.push_back(rendered.scan.point(i));
  }
  for (auto _ : state) {
    logged.update_bounds();
    benchmark::DoNotOptimize(logged.block_bounds.data());
  }
  state.counters["points"] = static_cast<double>(logged.points.size());
}

}  // namespace

BENCHMARK(BM_MappingMovingSequence)
    ->Arg(400)
    ->ArgName("scans")
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime()
    ->Iterations(1)
    ->Repetitions(3);
BENCHMARK(BM_StaticMapGrowthScans)
    ->Unit(benchmark::kMillisecond)
    ->UseManualTime()
    ->Iterations(1)
    ->Repetitions(5);
BENCHMARK(BM_LoggedScanRemoveBox)
    ->Arg(0)
    ->Arg(1)
    ->ArgName("bounds")
    ->Unit(benchmark::kMicrosecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_LoggedScanBounds)
    ->Unit(benchmark::kMicrosecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
