// Segmentation benchmarks: one VLP-16 scan per iteration, fast and naive on the same scan.

#include <benchmark/benchmark.h>

#include "ringtrack/segmentation/segmenter.hpp"
#include "ringtrack/sim/simple_scene.hpp"
#include "support/naive_segmentation.hpp"

namespace {

using namespace ringtrack;

const sim::RenderedScan& scene(bool hard) {
  static const auto model = core::SensorModel::vlp16();
  static const auto hard_scan = sim::render(model, sim::SimpleScene::hard_wall());
  static const auto open_scan = sim::render(model, sim::SimpleScene::open_field());
  return hard ? hard_scan : open_scan;
}

void run_fast(benchmark::State& state, bool hard) {
  const auto& scan = scene(hard).scan;
  segmentation::Segmenter segmenter{core::SegmentationConfig{}};
  std::vector<std::uint8_t> labels;
  segmenter.segment(scan, labels);  // builds the radius tables once, outside the timing
  for (auto _ : state) {
    segmenter.segment(scan, labels);
    benchmark::DoNotOptimize(labels.data());
  }
  const auto& stats = segmenter.stats();
  // Share of points the reference brackets left open, and of those needing exact median values.
  state.counters["open_share"] =
      static_cast<double>(stats.bucket_decisions) / static_cast<double>(stats.points);
  state.counters["exact_share"] =
      static_cast<double>(stats.exact_decisions) / static_cast<double>(stats.points);
  state.counters["updates_per_point"] =
      static_cast<double>(stats.window_updates) / static_cast<double>(scan.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(scan.size()));
}

void run_naive(benchmark::State& state, bool hard) {
  const auto& scan = scene(hard).scan;
  for (auto _ : state)
    benchmark::DoNotOptimize(testing::naive_segment(scan, core::SegmentationConfig{}));
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(scan.size()));
}

void BM_SegmentHardWall(benchmark::State& state) {
  run_fast(state, true);
}
void BM_SegmentOpenField(benchmark::State& state) {
  run_fast(state, false);
}
void BM_SegmentHardWallNaive(benchmark::State& state) {
  run_naive(state, true);
}
void BM_SegmentOpenFieldNaive(benchmark::State& state) {
  run_naive(state, false);
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
BENCHMARK(BM_SegmentHardWallNaive)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SegmentOpenFieldNaive)->Unit(benchmark::kMillisecond);
