// libFuzzer target: capture files through libpcap, the frame parser and the Velodyne source.
// Input byte 0 selects a raw file (the input as is), a valid classic pcap header (Ethernet,
// Linux cooked, raw IP, SLL2; us or ns) followed by the input as records, or (bit 0x20) valid
// Ethernet/IPv4/UDP records whose payloads are chunks of the input (so that the fuzzer reaches
// the decoder through the reader). Documented errors (core::Error) are fine; crashes and
// sanitizer reports are bugs.
#include <cstdint>
#include <vector>

#include "fuzz_support.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"

using namespace ringtrack;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  fuzz::FuzzInput in(data, size);
  const std::uint8_t control = in.byte();
  std::vector<std::uint8_t> file;
  if ((control & 1) != 0) {
    const std::uint32_t links[4] = {1, 113, 101, 276};  // Ethernet, SLL, raw IP, SLL2
    file = fuzz::pcap_file_header(links[(control >> 2) & 3], (control & 2) != 0);
  }
  if ((control & 0x21) == 0x21) {
    // A chunk's first byte picks its size (1206 mostly) and port; payload bytes come from the
    // input, zero-padded.
    std::uint32_t second = 1'700'000'000;
    std::vector<std::uint8_t> payload;
    while (!in.done()) {
      const std::uint8_t head = in.byte();
      const std::size_t n = (head & 0x80) != 0 ? static_cast<std::size_t>(head & 0x3F) * 20 : 1206;
      in.chunk(n, payload);
      fuzz::append_udp_record(file, second++, (head & 0x40) != 0 ? 8308 : 2368, payload);
    }
  } else {
    const auto rest = in.rest();
    file.insert(file.end(), rest.begin(), rest.end());
  }
  const auto path = fuzz::write_scratch("input.pcap", file);
  fuzz::expect_errors([&] {
    io::VelodynePcapOptions options;
    options.allow_truncated = (control & 0x10) != 0;
    io::VelodynePcapSource source(path, options);
    fuzz::drain_source(source);
  });
  return 0;
}
