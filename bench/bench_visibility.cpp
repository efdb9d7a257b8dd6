// Visibility-query and background-range benchmarks on a simulated VLP-16 park scan (scan 20,
// seed 1).

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "ringtrack/core/background_range.hpp"
#include "ringtrack/core/visibility.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/simulator.hpp"

namespace {

using namespace ringtrack;

const core::SensorModel& model() {
  static const auto m = core::SensorModel::vlp16();
  return m;
}

const core::OrganizedScan& park_scan() {
  static const auto scan = [] {
    sim::Simulator simulator(sim::builtin_scenario("park"), 1);
    sim::SimulatedScan s;
    for (int i = 0; i < 20; ++i) simulator.next(s);
    return s.scan;
  }();
  return scan;
}

// The sensor a little off the origin and turned, so the world->sensor transform is not trivial.
core::Pose bench_pose() {
  core::Pose p;
  p.translation = Eigen::Vector3d(2.0, -1.0, 0.5);
  p.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  return p;
}

void BM_VisibilityConstruct(benchmark::State& state) {
  const auto& scan = park_scan();
  const auto pose = bench_pose();
  for (auto _ : state) {
    core::VisibilityQuery q(scan, model(), pose);
    benchmark::DoNotOptimize(&q);
  }
}

// The same query over a beam geometry shared from an earlier scan with the same column azimuths
// (what the pipeline does: BeamGeometryCache), which leaves the pose and the motion to set up.
void BM_VisibilityConstructShared(benchmark::State& state) {
  const auto& scan = park_scan();
  const auto pose = bench_pose();
  core::BeamGeometryCache cache;
  for (auto _ : state) {
    core::VisibilityQuery q(scan, cache.get(scan, model()), pose);
    benchmark::DoNotOptimize(&q);
  }
}

// 1000 world points spread over 0.5..30 m around the sensor and +-3 m in height.
void BM_VisibilityPoint(benchmark::State& state) {
  const auto& scan = park_scan();
  const auto pose = bench_pose();
  const core::VisibilityQuery q(scan, model(), pose);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> points(1000);
  for (auto& p : points) {
    const double d = 0.5 + 29.5 * u(rng);
    const double az = 2.0 * std::numbers::pi * u(rng);
    p = pose.isometry() * Eigen::Vector3d(d * std::cos(az), d * std::sin(az), 6.0 * (u(rng) - 0.5));
  }
  int known = 0;
  for (auto _ : state) {
    known = 0;
    for (const auto& p : points) known += q.at(p, 0.2) != core::Visibility::kUnknown ? 1 : 0;
    benchmark::DoNotOptimize(known);
  }
  state.counters["known_share"] = known / 1000.0;
  state.SetItemsProcessed(state.iterations() * 1000);
}

// A person-sized box (0.6 x 0.6 x 1.8 m) at state.range(0) metres in front of the sensor.
void BM_VisibilityBox(benchmark::State& state) {
  const auto& scan = park_scan();
  const auto pose = bench_pose();
  const core::VisibilityQuery q(scan, model(), pose);
  const auto d = static_cast<double>(state.range(0));
  const Eigen::Vector3d c = pose.isometry() * Eigen::Vector3d(d * 0.8, d * 0.6, -0.1);
  const core::Box3 box{(c - Eigen::Vector3d(0.3, 0.3, 0.9)).cast<float>(),
                       (c + Eigen::Vector3d(0.3, 0.3, 0.9)).cast<float>()};
  core::VisibilityCounts counts;
  for (auto _ : state) {
    counts = q.in_box(box, 0.2);
    benchmark::DoNotOptimize(counts);
  }
  state.counters["beams"] = counts.total();
}

// One VLP-16 scan into a background model that has already learned it (the steady state).
void BM_BackgroundUpdate(benchmark::State& state) {
  const auto& scan = park_scan();
  core::BackgroundRangeModel bg(model());
  for (int i = 0; i < 30; ++i) bg.update(scan);
  for (auto _ : state) {
    bg.update(scan);
    benchmark::ClobberMemory();
  }
  state.counters["learned_share"] =
      static_cast<double>(bg.learned_count()) / static_cast<double>(bg.size());
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(scan.size()));
}

}  // namespace

BENCHMARK(BM_BackgroundUpdate)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_VisibilityConstruct)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_VisibilityConstructShared)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_VisibilityPoint)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_VisibilityBox)->Arg(5)->Arg(20)->Unit(benchmark::kMicrosecond);
