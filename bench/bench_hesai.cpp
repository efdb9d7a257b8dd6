// Hesai decoding benchmarks: packets per second into OrganizedScans, one second of data per
// iteration (tests/support/hesai_encoder) through one long-running decoder. Real time at 600 rpm:
// PandarXT32 dual 5000 packets/s, Pandar64 dual 6000, PandarQT64 dual 3000, Pandar40P dual 3600.
// Goal >= 100x.

#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "ringtrack/sensors/hesai/hesai_calibration.hpp"
#include "ringtrack/sensors/hesai/hesai_decoder.hpp"
#include "support/hesai_encoder.hpp"

namespace {

using namespace ringtrack;

// recycle: hand each scan back to the decoder (as a consumer done with it may), so that the
// next is built in its memory instead of a freshly allocated (and page-faulted) one.
void decode(benchmark::State& state, const std::string& model, std::uint8_t mode,
            bool recycle = true) {
  test::HesaiEncoderOptions eo;
  eo.model = model;
  eo.return_mode = mode;
  const test::HesaiEncoder enc(eo);
  const int per_second = enc.firings_per_revolution() * 10 / enc.firings_per_packet();
  const auto packets = enc.encode(0, per_second, [](long long f, int ch) {
    const auto h = static_cast<std::uint32_t>((f * 2654435761LL + ch * 40503) & 0xFFFFFFFF);
    const auto d = static_cast<std::uint16_t>(h % 10 == 0 ? 0 : 200 + (h >> 8) % 15000);
    const auto r = static_cast<std::uint8_t>(h >> 24);
    const bool two = h % 7 == 0 && d != 0;
    return std::pair{test::HesaiEcho{static_cast<std::uint16_t>(two ? d + 300 : d), r},
                     test::HesaiEcho{d, static_cast<std::uint8_t>(two ? r / 2 : r)}};
  });
  sensors::hesai::HesaiDecoderOptions options;
  options.calibration =
      sensors::hesai::parse_hesai_calibration(test::hesai_calibration_csv(enc.channels()), "b");
  const double packet_ns = 1e9 / per_second;
  std::size_t scans = 0;
  // One decoder for the whole run (as for a live sensor): each iteration continues the stream by
  // another second.
  sensors::hesai::HesaiDecoder decoder(options);
  std::int64_t second = 0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < packets.size(); ++i) {
      decoder.add_packet(
          packets[i],
          second * 1'000'000'000 + static_cast<std::int64_t>(static_cast<double>(i) * packet_ns));
      while (auto scan = decoder.pop_scan()) {
        benchmark::DoNotOptimize(scan->ranges().data());
        ++scans;
        if (recycle) decoder.recycle(std::move(*scan));
      }
    }
    ++second;
  }
  state.counters["scans_per_s"] =
      static_cast<double>(scans) / static_cast<double>(state.iterations());
  const auto n = state.iterations() * static_cast<std::int64_t>(packets.size());
  state.SetItemsProcessed(n);
  state.counters["x_real_time"] =
      benchmark::Counter(static_cast<double>(n) / per_second, benchmark::Counter::kIsRate);
}

void BM_DecodeHesaiXT32Dual(benchmark::State& state) {
  decode(state, "PandarXT32", 0x39);
}
BENCHMARK(BM_DecodeHesaiXT32Dual)->Unit(benchmark::kMillisecond);

void BM_DecodeHesaiXT32DualFreshScans(benchmark::State& state) {
  decode(state, "PandarXT32", 0x39, false);
}
BENCHMARK(BM_DecodeHesaiXT32DualFreshScans)->Unit(benchmark::kMillisecond);

void BM_DecodeHesaiPandar64Dual(benchmark::State& state) {
  decode(state, "Pandar64", 0x39);
}
BENCHMARK(BM_DecodeHesaiPandar64Dual)->Unit(benchmark::kMillisecond);

void BM_DecodeHesaiQT64Dual(benchmark::State& state) {
  decode(state, "PandarQT64", 0x39);
}
BENCHMARK(BM_DecodeHesaiQT64Dual)->Unit(benchmark::kMillisecond);

void BM_DecodeHesaiPandar40PSingle(benchmark::State& state) {
  decode(state, "Pandar40P", 0x37);
}
BENCHMARK(BM_DecodeHesaiPandar40PSingle)->Unit(benchmark::kMillisecond);

}  // namespace
