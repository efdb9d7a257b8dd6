// Ouster decoding benchmark: an OS1-128 at 1024x10 (640 lidar packets per second, RNG19 single
// return) encoded by tests/support/ouster_encoder, one second per iteration through one
// long-running decoder. Goal >= 100x real time.

#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "ringtrack/sensors/ouster/ouster_decoder.hpp"
#include "ringtrack/sensors/ouster/ouster_metadata.hpp"
#include "support/ouster_encoder.hpp"

namespace {

using namespace ringtrack;

void decode(benchmark::State& state, const std::string& profile, bool recycle,
            bool reference = false) {
  test::OusterEncoderOptions eo;
  eo.profile = profile;
  eo.pixels_per_column = 128;
  const auto meta =
      sensors::ouster::parse_ouster_metadata(test::ouster_metadata_json(eo), "bench.json");
  std::vector<std::vector<std::uint8_t>> packets;
  for (int frame = 0; frame < 10; ++frame) {
    eo.frame_id = frame;
    for (int m = 0; m < 1024; m += 16) {
      packets.push_back(test::encode_ouster_packet(
          eo, m, frame * 100'000'000LL + m * 97'656LL, [](int mm, int beam) {
            const auto h =
                static_cast<std::uint32_t>((mm * 2654435761LL + beam * 40503) & 0xFFFFFFFF);
            const std::uint32_t r = h % 10 == 0 ? 0 : 800 + 8 * ((h >> 8) % 6000);
            return test::OusterEcho{r, r + 400, static_cast<std::uint8_t>(h >> 24)};
          }));
    }
  }
  sensors::ouster::OusterDecoderOptions options;
  options.reference_kernel = reference;
  sensors::ouster::OusterDecoder decoder(meta, options);
  std::size_t scans = 0;
  for (auto _ : state) {
    for (const auto& p : packets) {
      decoder.add_packet(p, 0);
      while (auto scan = decoder.pop_scan()) {
        benchmark::DoNotOptimize(scan->ranges().data());
        ++scans;
        if (recycle) decoder.recycle(std::move(*scan));
      }
    }
  }
  const auto n = state.iterations() * static_cast<std::int64_t>(packets.size());
  state.SetItemsProcessed(n);
  state.counters["x_real_time"] =
      benchmark::Counter(static_cast<double>(n) / 640.0, benchmark::Counter::kIsRate);
  state.counters["scans_per_s"] =
      static_cast<double>(scans) / static_cast<double>(state.iterations());
}

void BM_DecodeOusterOs1_128(benchmark::State& state) {
  decode(state, "RNG19_RFL8_SIG16_NIR16", true);
}
BENCHMARK(BM_DecodeOusterOs1_128)->Unit(benchmark::kMillisecond);

void BM_DecodeOusterOs1_128FreshScans(benchmark::State& state) {
  decode(state, "RNG19_RFL8_SIG16_NIR16", false);
}
BENCHMARK(BM_DecodeOusterOs1_128FreshScans)->Unit(benchmark::kMillisecond);

void BM_DecodeOusterOs1_128LowBandwidth(benchmark::State& state) {
  decode(state, "RNG15_RFL8_NIR8", true);
}
BENCHMARK(BM_DecodeOusterOs1_128LowBandwidth)->Unit(benchmark::kMillisecond);

// The per-pixel reference kernel (OusterDecoderOptions::reference_kernel), the decoder's kernel
// before issue 13's fast one, for side-by-side figures from one binary.
void BM_DecodeOusterOs1_128Reference(benchmark::State& state) {
  decode(state, "RNG19_RFL8_SIG16_NIR16", true, true);
}
BENCHMARK(BM_DecodeOusterOs1_128Reference)->Unit(benchmark::kMillisecond);

}  // namespace
