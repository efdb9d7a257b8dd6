// libFuzzer target: capture files through libpcap, the frame parser and the Velodyne source.
// Input byte 0 selects a raw file (the input as is), a valid classic pcap header (Ethernet,
// Linux cooked, raw IP, SLL2; us or ns) followed by the input as records, or (bit 0x20) valid
// Ethernet/IPv4/UDP records whose payloads are chunks of the input (so that the fuzzer reaches
// the decoder through the reader). Documented errors (core::Error) are fine; crashes and
// sanitizer reports are bugs.
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"

using namespace ringtrack;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  // One scratch file per process, removed at exit.
  static const struct Scratch {
    std::filesystem::path path = std::filesystem::temp_directory_path() /
                                 ("ringtrack_fuzz_" + std::to_string(::getpid()) + ".pcap");
    ~Scratch() {
      std::error_code ec;
      std::filesystem::remove(path, ec);
    }
  } scratch;
  const std::filesystem::path& path = scratch.path;
  std::vector<std::uint8_t> file;
  const std::uint8_t control = data[0];
  if ((control & 1) != 0) {
    const std::uint32_t links[4] = {1, 113, 101, 276};  // Ethernet, SLL, raw IP, SLL2
    const std::uint32_t magic = (control & 2) != 0 ? 0xA1B23C4D : 0xA1B2C3D4;
    const std::uint32_t header[6] = {magic, 0x00040002, 0, 0, 65535, links[(control >> 2) & 3]};
    const auto* h = reinterpret_cast<const std::uint8_t*>(header);
    file.assign(h, h + sizeof header);
  }
  if ((control & 0x21) == 0x21) {
    // Records: 16-byte header, Ethernet, IPv4 (20), UDP (8), payload. A chunk's first byte picks
    // its size (1206 mostly) and port; payload bytes come from the input, zero-padded.
    std::size_t at = 1;
    std::uint32_t second = 1'700'000'000;
    while (at < size) {
      const std::uint8_t head = data[at++];
      const std::size_t n = (head & 0x80) != 0 ? static_cast<std::size_t>(head & 0x3F) * 20 : 1206;
      const std::uint16_t port = (head & 0x40) != 0 ? 8308 : 2368;
      std::vector<std::uint8_t> frame(14 + 20 + 8 + n, 0);
      frame[12] = 0x08;  // IPv4
      frame[14] = 0x45;
      const std::size_t ip_len = 20 + 8 + n;
      frame[16] = static_cast<std::uint8_t>(ip_len >> 8);
      frame[17] = static_cast<std::uint8_t>(ip_len & 0xFF);
      frame[23] = 17;  // UDP
      frame[36] = static_cast<std::uint8_t>(port >> 8);
      frame[37] = static_cast<std::uint8_t>(port & 0xFF);
      frame[38] = static_cast<std::uint8_t>((8 + n) >> 8);
      frame[39] = static_cast<std::uint8_t>((8 + n) & 0xFF);
      const std::size_t take = std::min(n, size - at);
      std::copy(data + at, data + at + take, frame.begin() + 42);
      at += take;
      const std::uint32_t record[4] = {second++, 0, static_cast<std::uint32_t>(frame.size()),
                                       static_cast<std::uint32_t>(frame.size())};
      const auto* r = reinterpret_cast<const std::uint8_t*>(record);
      file.insert(file.end(), r, r + sizeof record);
      file.insert(file.end(), frame.begin(), frame.end());
    }
  } else {
    file.insert(file.end(), data + 1, data + size);
  }
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(file.data()),
              static_cast<std::streamsize>(file.size()));
  }
  try {
    io::VelodynePcapOptions options;
    options.allow_truncated = (control & 0x10) != 0;
    io::VelodynePcapSource source(path, options);
    while (source.next()) {
    }
    (void)source.summary();
  } catch (const core::Error&) {
  }
  return 0;
}
