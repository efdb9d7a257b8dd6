// Simulator speed: one VLP-16 revolution of scenario 2 (50 people on an empty field), static and
// moving sensor, and the park (many static primitives, height field).

#include <benchmark/benchmark.h>

#include "ringtrack/sim/simulator.hpp"

namespace {

using namespace ringtrack;

void run(benchmark::State& state, const char* scenario) {
  sim::Simulator simulator(sim::builtin_scenario(scenario), 1);
  sim::SimulatedScan scan;
  for (int i = 0; i < 5; ++i) simulator.next(scan);  // warm up, buffers sized
  std::size_t valid = 0;
  for (auto _ : state) {
    simulator.next(scan);
    valid += scan.scan.valid_count();
    benchmark::DoNotOptimize(scan.labels.data());
  }
  state.counters["valid_points"] =
      static_cast<double>(valid) / static_cast<double>(state.iterations());
  state.counters["scans_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void BM_SimulateScan50People(benchmark::State& state) {
  run(state, "crowd");
}
void BM_SimulateScan50PeopleMovingSensor(benchmark::State& state) {
  run(state, "crowd-moving");
}
void BM_SimulateScanPark(benchmark::State& state) {
  run(state, "park");
}
void BM_SimulateScanHall(benchmark::State& state) {
  run(state, "hall");
}

}  // namespace

BENCHMARK(BM_SimulateScan50People)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SimulateScan50PeopleMovingSensor)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SimulateScanPark)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_SimulateScanHall)->Unit(benchmark::kMillisecond);
