// Tracking and mapping benchmarks: one Tracker::update per iteration on a steady scripted stream
// (people walking on circles), and one DynamicObjectFilter::process per iteration on a VLP-16 scan.

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>

#include "ringtrack/mapping/dynamic_object_filter.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "ringtrack/tracking/tracker.hpp"
#include "support/scripted_detections.hpp"

namespace {

using namespace ringtrack;

constexpr int kPeriodScans = 128;  // the circles close after this many scans: a steady stream

// Detections of `people` walking on circles of radius 1.5 m (about 0.74 m/s) on a 5 m grid,
// with centroid and box noise; scan k + kPeriodScans repeats scan k.
std::vector<std::vector<core::Detection>> circle_stream(int people) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  std::vector<double> phase0(people);
  for (auto& p : phase0) p = phase(rng);
  testing::PersonShape shape;
  shape.centroid_noise_m = 0.03f;
  shape.box_noise_m = 0.02f;
  std::vector<std::vector<core::Detection>> stream(kPeriodScans);
  for (int k = 0; k < kPeriodScans; ++k) {
    for (int i = 0; i < people; ++i) {
      const double a =
          phase0[i] + (i % 2 == 0 ? 1.0 : -1.0) * 2.0 * std::numbers::pi * k / kPeriodScans;
      const Eigen::Vector3f foot(static_cast<float>(5.0 * (i % 10) + 1.5 * std::cos(a)),
                                 static_cast<float>(5.0 * (i / 10) + 1.5 * std::sin(a)), 0.0f);
      stream[k].push_back(testing::person_detection(foot, shape, &rng));
    }
  }
  return stream;
}

void run_tracker(benchmark::State& state, int people) {
  const auto stream = circle_stream(people);
  tracking::Tracker tracker{core::TrackingConfig{}};
  int k = 0;
  for (; k < 2 * kPeriodScans; ++k)
    tracker.update(stream[k % kPeriodScans], testing::scan_stamp_ns(k));
  for (auto _ : state) {
    const auto& hypotheses = tracker.update(stream[k % kPeriodScans], testing::scan_stamp_ns(k));
    benchmark::DoNotOptimize(hypotheses.data());
    ++k;
  }
  state.counters["hypotheses"] = static_cast<double>(tracker.hypotheses().size());
}

void BM_Track10Targets(benchmark::State& state) {
  run_tracker(state, 10);
}
void BM_Track50Targets(benchmark::State& state) {
  run_tracker(state, 50);
}

// Detections straight from the rendered labels, as a perfect detector would give them.
std::vector<core::Detection> label_detections(const sim::RenderedScan& r) {
  std::vector<core::Detection> out;
  for (std::uint32_t label = 1;; ++label) {
    core::Detection d;
    for (std::size_t i = 0; i < r.labels.size(); ++i) {
      if (r.labels[i] != label) continue;
      d.indices.push_back(static_cast<std::uint32_t>(i));
      d.box.extend(r.scan.point(i));
    }
    if (d.indices.empty()) break;
    d.centroid = d.box.center();
    d.covariance = Eigen::Vector3f(0.01f, 0.01f, 0.25f).asDiagonal();
    out.push_back(std::move(d));
  }
  return out;
}

void BM_DynamicObjectFilterScan(benchmark::State& state) {
  const auto model = core::SensorModel::vlp16();
  const auto rendered = sim::render(model, sim::SimpleScene::demo());
  const auto detections = label_detections(rendered);
  tracking::Tracker tracker{core::TrackingConfig{}};
  auto hypotheses = tracker.update(detections, 0);
  hypotheses.front().ever_dynamic = true;  // one dynamic person: its points are removed
  mapping::DynamicObjectFilter filter{core::MappingConfig{}};
  core::Pose pose;
  for (int k = 0; k < 100; ++k) filter.process(rendered.scan, pose, detections, hypotheses);
  for (auto _ : state) {
    const auto& result = filter.process(rendered.scan, pose, detections, hypotheses);
    benchmark::DoNotOptimize(result.removed_cells.data());
  }
  state.counters["points"] = static_cast<double>(rendered.scan.valid_count());
  state.counters["map_voxels"] = static_cast<double>(filter.map().size());
}

void BM_StaticMapInsertScan(benchmark::State& state) {
  const auto model = core::SensorModel::vlp16();
  const auto rendered = sim::render(model, sim::SimpleScene::demo());
  std::vector<Eigen::Vector3f> points;
  std::vector<float> intensities;
  for (std::size_t i = 0; i < rendered.scan.size(); ++i) {
    if (!rendered.scan.valid(i)) continue;
    points.push_back(rendered.scan.point(i));
    intensities.push_back(rendered.scan.intensity(i));
  }
  mapping::StaticMap map(core::MappingConfig{}.voxel_size_m);
  map.insert(points, intensities, {});
  for (auto _ : state) {
    map.insert(points, intensities, {});
    benchmark::ClobberMemory();
  }
  state.counters["points"] = static_cast<double>(points.size());
  state.counters["map_voxels"] = static_cast<double>(map.size());
}

}  // namespace

BENCHMARK(BM_StaticMapInsertScan)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_Track10Targets)
    ->Unit(benchmark::kMicrosecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_Track50Targets)
    ->Unit(benchmark::kMicrosecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_DynamicObjectFilterScan)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
