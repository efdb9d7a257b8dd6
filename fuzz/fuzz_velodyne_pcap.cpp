// libFuzzer target: capture files through libpcap, the frame parser and the Velodyne source.
// Input byte 0 selects a raw file (the input as is) or a valid classic pcap header (Ethernet,
// Linux cooked, raw IP; us or ns) followed by the input as records. Documented errors
// (core::Error) are fine; crashes and sanitizer reports are bugs.
#include <unistd.h>

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
    const std::uint32_t links[4] = {1, 113, 101, 276};
    const std::uint32_t magic = (control & 2) != 0 ? 0xA1B23C4D : 0xA1B2C3D4;
    const std::uint32_t header[6] = {magic, 0x00040002, 0, 0, 65535, links[(control >> 2) & 3]};
    const auto* h = reinterpret_cast<const std::uint8_t*>(header);
    file.assign(h, h + sizeof header);
  }
  file.insert(file.end(), data + 1, data + size);
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
