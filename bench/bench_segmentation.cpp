// Segmentation benchmarks: one VLP-16 scan per iteration, fast and naive on the same scan.

#include <benchmark/benchmark.h>

#include "ringtrack/segmentation/segmenter.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "ringtrack/sim/simulator.hpp"
#include "support/naive_segmentation.hpp"

namespace {

using namespace ringtrack;

enum class Scene { kHardWall, kOpenField, kPark };

const core::OrganizedScan& scene(Scene which) {
  static const auto model = core::SensorModel::vlp16();
  static const auto hard_scan = sim::render(model, sim::SimpleScene::hard_wall()).scan;
  static const auto open_scan = sim::render(model, sim::SimpleScene::open_field()).scan;
  // A structured outdoor scan: trees, bushes, height-field ground, people (scan 20, seed 1).
  static const auto park_scan = [] {
    sim::Simulator simulator(sim::builtin_scenario("park"), 1);
    sim::SimulatedScan scan;
    for (int i = 0; i < 20; ++i) simulator.next(scan);
    return scan.scan;
  }();
  switch (which) {
    case Scene::kHardWall:
      return hard_scan;
    case Scene::kOpenField:
      return open_scan;
    case Scene::kPark:
      break;
  }
  return park_scan;
}

void run_fast(benchmark::State& state, Scene which) {
  const auto& scan = scene(which);
  segmentation::Segmenter segmenter{core::SegmentationConfig{}};
  std::vector<std::uint8_t> labels;
  segmenter.segment(scan, labels);  // builds the radius tables once, outside the timing
  for (auto _ : state) {
    segmenter.segment(scan, labels);
    benchmark::DoNotOptimize(labels.data());
  }
  const auto& stats = segmenter.stats();
  // Shares of points the references' lazy bounds left open, the tight bounds left open (exact
  // median buckets needed) and that needed exact median values.
  state.counters["tight_share"] =
      static_cast<double>(stats.tight_decisions) / static_cast<double>(stats.points);
  state.counters["open_share"] =
      static_cast<double>(stats.bucket_decisions) / static_cast<double>(stats.points);
  state.counters["exact_share"] =
      static_cast<double>(stats.exact_decisions) / static_cast<double>(stats.points);
  state.counters["updates_per_point"] =
      static_cast<double>(stats.window_updates) / static_cast<double>(scan.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(scan.size()));
}

void run_naive(benchmark::State& state, Scene which) {
  const auto& scan = scene(which);
  for (auto _ : state)
    benchmark::DoNotOptimize(testing::naive_segment(scan, core::SegmentationConfig{}));
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(scan.size()));
}

void BM_SegmentHardWall(benchmark::State& state) {
  run_fast(state, Scene::kHardWall);
}
void BM_SegmentOpenField(benchmark::State& state) {
  run_fast(state, Scene::kOpenField);
}
void BM_SegmentPark(benchmark::State& state) {
  run_fast(state, Scene::kPark);
}
void BM_SegmentHardWallNaive(benchmark::State& state) {
  run_naive(state, Scene::kHardWall);
}
void BM_SegmentOpenFieldNaive(benchmark::State& state) {
  run_naive(state, Scene::kOpenField);
}
void BM_SegmentParkNaive(benchmark::State& state) {
  run_naive(state, Scene::kPark);
}

}  // namespace

BENCHMARK(BM_SegmentHardWall)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_SegmentOpenField)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_SegmentPark)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
BENCHMARK(BM_SegmentHardWallNaive)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SegmentOpenFieldNaive)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SegmentParkNaive)->Unit(benchmark::kMillisecond);
