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
  for (auto _ : state) {
    if (next == kScans) {  // start over with a fresh pipeline, warmed up outside the timing
      state.PauseTiming();
      pipeline = std::make_unique<pipeline::Pipeline>(core::Config{}, core::SensorModel::vlp16());
      for (next = 0; next < kWarmUp; ++next) pipeline->process(data[next].scan, data[next].pose);
      state.ResumeTiming();
    }
    const auto& result = pipeline->process(data[next].scan, data[next].pose);
    hypotheses = result.hypotheses.size();
    ++next;
  }
  state.counters["hypotheses"] = static_cast<double>(hypotheses);
}

}  // namespace

BENCHMARK(BM_PipelineScan)
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);
