// Organizer benchmarks: one simulated VLP-16 scan (demo scene: ground, a wall at 12 m all
// around, people; 1808 x 16 cells, nearly all returns), flattened and shuffled like a KITTI-style
// cloud, organized back into rings x columns with the VLP-16 model (beam offsets: up to four
// candidate rings per point) and with a generic model (one); and the sensor measured on the
// cloud. A VLP-16 turns at 10 Hz: real time is 100 ms per scan.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <random>

#include "ringtrack/core/cloud_organizer.hpp"
#include "ringtrack/io/kitti_bin.hpp"
#include "ringtrack/sim/simple_scene.hpp"

namespace {

using namespace ringtrack;

const core::UnorganizedCloud& vlp16_cloud() {
  static const core::UnorganizedCloud cloud = [] {
    auto scan = sim::render(core::SensorModel::vlp16(), sim::SimpleScene::demo()).scan;
    core::UnorganizedCloud c = core::flatten_scan(scan);
    c.time_ns.clear();  // as in a .bin file
    std::vector<std::size_t> order(c.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::shuffle(order.begin(), order.end(), std::mt19937(5));
    core::UnorganizedCloud s;
    for (std::size_t i : order) {
      s.xyz.push_back(c.xyz[i]);
      s.intensity.push_back(c.intensity[i]);
    }
    return s;
  }();
  return cloud;
}

void report(benchmark::State& state, std::size_t points) {
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * points));
  state.counters["points"] = static_cast<double>(points);
  // Scans per second over the 10 scans per second the sensor delivers.
  state.counters["x_realtime"] = benchmark::Counter(static_cast<double>(state.iterations()) / 10.0,
                                                    benchmark::Counter::kIsRate);
}

void BM_OrganizeVlp16(benchmark::State& state) {
  const auto& cloud = vlp16_cloud();
  const core::CloudOrganizer organizer(core::SensorModel::vlp16());
  for (auto _ : state) {
    auto o = organizer.organize(cloud);
    benchmark::DoNotOptimize(o.scan.ranges().data());
  }
  report(state, cloud.size());
}
BENCHMARK(BM_OrganizeVlp16)->Unit(benchmark::kMillisecond);

void BM_OrganizeGeneric16(benchmark::State& state) {
  const auto& cloud = vlp16_cloud();
  std::vector<double> elevations;
  for (int r = 0; r < 16; ++r) elevations.push_back(-15.0 + 2.0 * r);
  const core::CloudOrganizer organizer(core::SensorModel::generic(elevations, 1808));
  for (auto _ : state) {
    auto o = organizer.organize(cloud);
    benchmark::DoNotOptimize(o.scan.ranges().data());
  }
  report(state, cloud.size());
}
BENCHMARK(BM_OrganizeGeneric16)->Unit(benchmark::kMillisecond);

void BM_MeasureCloudSensor(benchmark::State& state) {
  const auto& cloud = vlp16_cloud();
  for (auto _ : state) {
    auto model = core::measure_cloud_sensor(cloud, "bench.bin");
    benchmark::DoNotOptimize(model.elevation_rad.data());
  }
  report(state, cloud.size());
}
BENCHMARK(BM_MeasureCloudSensor)->Unit(benchmark::kMillisecond);

void BM_KittiBinDecode(benchmark::State& state) {
  const std::string file = io::encode_kitti_bin(vlp16_cloud());
  const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(file.data()),
                                            file.size());
  for (auto _ : state) {
    auto cloud = io::decode_kitti_bin(bytes, "bench.bin");
    benchmark::DoNotOptimize(cloud.xyz.data());
  }
  report(state, vlp16_cloud().size());
}
BENCHMARK(BM_KittiBinDecode)->Unit(benchmark::kMillisecond);

}  // namespace
