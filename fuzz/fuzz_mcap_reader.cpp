// libFuzzer target: the MCAP reader over bytes in memory. Input byte 0 selects the raw input
// (bit 0 clear) or the input behind a valid magic and Header record, so that most inputs reach
// the record parser, chunk decompression (none, lz4, zstd) and the summary; bit 1 reads without
// the summary. Documented errors (core::InputError) are fine; crashes, leaks and sanitizer
// reports are bugs. Chunks are limited to 1 MiB so that a claimed size cannot exhaust memory.
#include <cstdint>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/mcap_format.hpp"
#include "ringtrack/io/mcap_reader.hpp"

using namespace ringtrack;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::uint8_t control = data[0];
  io::mcap::Buffer file;
  if ((control & 1) != 0) {
    file.raw(io::mcap::kMagic);
    const auto at = file.begin_record(io::mcap::Op::kHeader);
    file.string("ros2");
    file.string("fuzz");
    file.end_record(at);
  }
  file.raw({data + 1, size - 1});
  io::McapReaderOptions options;
  options.max_chunk_bytes = std::uint64_t{1} << 20;
  options.use_summary = (control & 2) == 0;
  try {
    io::McapReader reader(file.bytes(), "fuzz.mcap", options);
    io::McapMessage message;
    std::size_t bytes = 0;
    while (reader.next(message)) bytes += message.data.size();
    for (const auto& channel : reader.channels()) bytes += reader.message_count(channel.id);
    if (bytes == 0xFFFFFFFF) return 1;  // keeps the loop from being optimized away
  } catch (const core::InputError&) {
  }
  return 0;
}
