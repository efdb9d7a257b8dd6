// BM_OdometryScan: the odometry on one simulated VLP-16 scan of a MAV flying its figure 8 over the
// industrial site (scenario 4), in time order after a warm-up (map built, velocity known).
// BM_PipelineScanWithOdometry: the whole pipeline with the odometry estimating the poses, on the
// same flight with the scenario's walkers.

#include <benchmark/benchmark.h>

#include <memory>

#include "ringtrack/odometry/odometry.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace {

using namespace ringtrack;

constexpr int kScans = 150;
constexpr int kWarmUp = 30;

const std::vector<sim::SimulatedScan>& flight() {
  static const auto data = [] {
    sim::Simulator simulator(sim::with_moving_sensor(sim::builtin_scenario("4")), 7);
    std::vector<sim::SimulatedScan> out(kScans);
    for (auto& s : out) simulator.next(s);
    return out;
  }();
  return data;
}

void BM_OdometryScan(benchmark::State& state) {
  const auto& data = flight();
  std::unique_ptr<odometry::Odometry> odometry;
  core::OrganizedScan scan;
  int next = kScans;
  double degenerate = 0;
  double iterations = 0;
  for (auto _ : state) {
    state.PauseTiming();
    if (next == kScans) {  // start over, warmed up outside the timing
      odometry = std::make_unique<odometry::Odometry>(core::OdometryConfig{});
      for (next = 0; next < kWarmUp; ++next) {
        scan = data[next].scan;
        odometry->process(scan);
      }
    }
    scan = data[next].scan;  // the odometry compensates the scan in place
    state.ResumeTiming();
    const odometry::OdometryResult result = odometry->process(scan);
    degenerate += result.degenerate ? 1 : 0;
    iterations += result.iterations;
    ++next;
  }
  state.counters["degenerate"] = benchmark::Counter(degenerate, benchmark::Counter::kAvgIterations);
  // ICP iterations per scan, all passes: what the convergence settings cost.
  state.counters["iterations"] = benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_OdometryScan)->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_PipelineScanWithOdometry(benchmark::State& state) {
  const auto& data = flight();
  std::unique_ptr<pipeline::Pipeline> pipeline;
  core::OrganizedScan scan;
  int next = kScans;
  double odometry_ms = 0;
  for (auto _ : state) {
    state.PauseTiming();
    if (next == kScans) {
      pipeline = std::make_unique<pipeline::Pipeline>(core::Config{}, core::SensorModel::vlp16());
      for (next = 0; next < kWarmUp; ++next) {
        scan = data[next].scan;
        pipeline->process_with_odometry(scan);
      }
    }
    scan = data[next].scan;
    state.ResumeTiming();
    odometry_ms += pipeline->process_with_odometry(scan).times.odometry_ms;
    ++next;
  }
  state.counters["odometry_ms"] =
      benchmark::Counter(odometry_ms, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_PipelineScanWithOdometry)->Unit(benchmark::kMillisecond)->MinTime(3.0);

}  // namespace
