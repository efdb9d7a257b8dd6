// BM_PipelineScan: the whole pipeline on one simulated VLP-16 scan with 10 people walking in an
// open field, in time order with the tracker warmed up (the steady state of a long run).

#include <benchmark/benchmark.h>

#include <memory>

#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace {

using namespace ringtrack;

constexpr int kScans = 120;
constexpr int kWarmUp = 20;  // scans before timing: tracks exist, the map log is filling

const std::vector<sim::SimulatedScan>& scans() {
  static const auto data = [] {
    auto scenario = sim::builtin_scenario("1");
    scenario.people = 10;
    sim::Simulator simulator(scenario, 7);
    std::vector<sim::SimulatedScan> out(kScans);
    for (auto& s : out) simulator.next(s);
    return out;
  }();
  return data;
}

void BM_PipelineScan(benchmark::State& state) {
  const auto& data = scans();
  std::unique_ptr<pipeline::Pipeline> pipeline;
  int next = kScans;
  std::size_t hypotheses = 0;
  pipeline::StageTimes sum;  // per-stage breakdown, reported as means per scan
  for (auto _ : state) {
    if (next == kScans) {  // start over with a fresh pipeline, warmed up outside the timing
      state.PauseTiming();
      pipeline = std::make_unique<pipeline::Pipeline>(core::Config{}, core::SensorModel::vlp16());
      for (next = 0; next < kWarmUp; ++next) pipeline->process(data[next].scan, data[next].pose);
      state.ResumeTiming();
    }
    const auto& result = pipeline->process(data[next].scan, data[next].pose);
    hypotheses = result.hypotheses.size();
    sum.segmentation_ms += result.times.segmentation_ms;
    sum.detection_ms += result.times.detection_ms;
    sum.tracking_ms += result.times.tracking_ms;
    sum.mapping_ms += result.times.mapping_ms;
    ++next;
  }
  state.counters["hypotheses"] = static_cast<double>(hypotheses);
  const auto mean = [&](double total) {
    return benchmark::Counter(total, benchmark::Counter::kAvgIterations);
  };
  state.counters["segmentation_ms"] = mean(sum.segmentation_ms);
  state.counters["detection_ms"] = mean(sum.detection_ms);
  state.counters["tracking_ms"] = mean(sum.tracking_ms);
  state.counters["mapping_ms"] = mean(sum.mapping_ms);
}

}  // namespace

BENCHMARK(BM_PipelineScan)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
