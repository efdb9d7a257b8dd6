// PCD benchmarks: encode and decode one labeled VLP-16 scan (1808 x 16 cells, open field with
// ten people) in memory, per encoding; `ringtrack run` decodes one such file per scan.

#include <benchmark/benchmark.h>

#include "ringtrack/io/lzf.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/sim/simple_scene.hpp"

namespace {

using namespace ringtrack;

const sim::RenderedScan& vlp16_scan() {
  static const auto scan =
      sim::render(core::SensorModel::vlp16(), sim::SimpleScene::open_field(10));
  return scan;
}

void BM_PcdEncode(benchmark::State& state) {
  const auto encoding = static_cast<io::PcdEncoding>(state.range(0));
  const auto& s = vlp16_scan();
  std::size_t bytes = 0;
  for (auto _ : state) {
    const std::string out = io::encode_pcd(s.scan, s.labels, encoding);
    bytes = out.size();
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["file_bytes"] = static_cast<double>(bytes);
  state.SetLabel(std::string(io::to_string(encoding)));
}
BENCHMARK(BM_PcdEncode)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

void BM_PcdDecode(benchmark::State& state) {
  const auto encoding = static_cast<io::PcdEncoding>(state.range(0));
  const auto& s = vlp16_scan();
  const std::string file = io::encode_pcd(s.scan, s.labels, encoding);
  const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(file.data()),
                                            file.size());
  for (auto _ : state) {
    auto scan = io::decode_pcd(bytes, "bench.pcd");
    benchmark::DoNotOptimize(scan.scan.ranges().data());
  }
  state.SetLabel(std::string(io::to_string(encoding)));
}
BENCHMARK(BM_PcdDecode)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

}  // namespace
