// Velodyne decoding benchmarks: packets per second into OrganizedScans. Real time for a VLP-16
// at 600 rpm is 754 packets/s (single return) or 1508 packets/s (dual); goal >= 100x.

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"
#include "support/velodyne_encoder.hpp"

namespace {

using namespace ringtrack;

// One second of a VLP-16 at 600 rpm: mostly valid returns, some empty and some dual pairs.
std::vector<test::EncodedVelodynePacket> one_second(std::uint8_t return_mode) {
  test::VelodyneEncoderOptions eo;
  eo.return_mode = return_mode;
  const test::VelodyneEncoder enc(eo);
  const long long packets = return_mode == 0x39 ? 1508 : 754;
  return enc.encode(0, packets, [](long long s, int laser) {
    const auto h = static_cast<std::uint32_t>((s * 2654435761LL + laser * 40503) & 0xFFFFFFFF);
    const auto d = static_cast<std::uint16_t>(h % 10 == 0 ? 0 : 500 + (h >> 8) % 15000);
    const auto r = static_cast<std::uint8_t>(h >> 24);
    const bool two = h % 7 == 0 && d != 0;
    return test::VelodyneEchoPair{{static_cast<std::uint16_t>(two ? d + 300 : d), r},
                                  {d, static_cast<std::uint8_t>(two ? r / 2 : r)}};
  });
}

void decode(benchmark::State& state, std::uint8_t return_mode, double real_time_packets_per_s) {
  const auto packets = one_second(return_mode);
  std::size_t scans = 0;
  for (auto _ : state) {
    io::VelodyneDecoder decoder;
    for (const auto& p : packets) {
      decoder.add_packet(p.payload, p.host_stamp_ns);
      while (auto scan = decoder.pop_scan()) {
        benchmark::DoNotOptimize(scan->ranges().data());
        ++scans;
      }
    }
    decoder.finish();
  }
  benchmark::DoNotOptimize(scans);
  const auto n = state.iterations() * static_cast<std::int64_t>(packets.size());
  state.SetItemsProcessed(n);
  state.counters["x_real_time"] = benchmark::Counter(
      static_cast<double>(n) / real_time_packets_per_s, benchmark::Counter::kIsRate);
}

void BM_DecodeVlp16(benchmark::State& state) {
  decode(state, 0x37, 754.0);
}
BENCHMARK(BM_DecodeVlp16)->Unit(benchmark::kMillisecond);

void BM_DecodeVlp16Dual(benchmark::State& state) {
  decode(state, 0x39, 1508.0);
}
BENCHMARK(BM_DecodeVlp16Dual)->Unit(benchmark::kMillisecond);

// The whole source: libpcap, Ethernet/IP/UDP framing and the decoder, from a file in /tmp.
void BM_DecodeVlp16Pcap(benchmark::State& state) {
  const auto packets = one_second(0x37);
  const auto path = std::filesystem::temp_directory_path() /
                    ("ringtrack_bench_vlp16_" + std::to_string(::getpid()) + ".pcap");
  test::write_pcap(path, test::PcapLink::kEthernet,
                   test::frame_packets(test::PcapLink::kEthernet, packets));
  for (auto _ : state) {
    io::VelodynePcapSource source(path);
    while (auto scan = source.next()) benchmark::DoNotOptimize(scan->ranges().data());
  }
  std::filesystem::remove(path);
  const auto n = state.iterations() * static_cast<std::int64_t>(packets.size());
  state.SetItemsProcessed(n);
  state.counters["x_real_time"] =
      benchmark::Counter(static_cast<double>(n) / 754.0, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_DecodeVlp16Pcap)->Unit(benchmark::kMillisecond);

}  // namespace
