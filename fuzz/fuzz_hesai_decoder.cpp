// libFuzzer target: Hesai packets through format recognition, the packet parser, the flat point
// decoder and the scan assembler, and calibration text through the CSV parser. Documented errors
// (core::Error) are fine; crashes, sanitizer reports and hangs are bugs. Input: one control byte
// (model, return selection, options), a length byte and that much calibration text, then packets,
// each led by a byte choosing its size and whether to repair its header, block flags, azimuths
// and return mode (so that the fuzzer reaches scan assembly, not only the rejection paths).
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "ringtrack/sensors/hesai/hesai_calibration.hpp"
#include "ringtrack/sensors/hesai/hesai_decoder.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"

using namespace ringtrack;
using namespace ringtrack::sensors::hesai;

namespace {

std::string calibration_text(int channels) {
  std::string s = "Channel,Elevation,Azimuth\n";
  for (int c = 1; c <= channels; ++c) {
    s += std::to_string(c) + "," + std::to_string(15 - c % 40) + "," + std::to_string(c % 3) + "\n";
  }
  return s;
}

// Makes a packet acceptable to the parser of `f` (header, flags, azimuths, dual pairs, mode).
void repair(std::vector<std::uint8_t>& p, const HesaiFormat& f, std::uint8_t mode) {
  if (f.block_flag) {
  } else if (f.protocol_major == 0) {
    p[0] = 0xEE, p[1] = 0xFF, p[2] = static_cast<std::uint8_t>(f.channels);
    p[3] = static_cast<std::uint8_t>(f.blocks), p[5] = static_cast<std::uint8_t>(1 + p[5] % 8);
  } else {
    p[0] = 0xEE, p[1] = 0xFF, p[2] = f.protocol_major, p[3] = f.protocol_minor;
    p[6] = static_cast<std::uint8_t>(f.channels), p[7] = static_cast<std::uint8_t>(f.blocks);
    p[9] = static_cast<std::uint8_t>(1 + p[9] % 8);
  }
  for (int b = 0; b < f.blocks; ++b) {
    std::uint8_t* block = p.data() + f.header_bytes + b * f.block_bytes();
    if (f.block_flag) {
      block[0] = 0xFF, block[1] = 0xEE;
      block += 2;
    }
    block[1] = static_cast<std::uint8_t>(block[1] % 141);  // < 36000
    if (hesai_dual_return_mode(mode) && b % 2 == 1) {
      const std::uint8_t* prev = block - f.block_bytes();
      block[0] = prev[0], block[1] = prev[1];
    }
  }
  p[f.header_bytes + f.blocks * f.block_bytes() + f.tail_return_mode] = mode;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  fuzz::FuzzInput in(data, size);
  const std::uint8_t control = in.byte();
  const auto formats = hesai_formats();
  const HesaiFormat& f = formats[control % formats.size()];
  const std::uint8_t modes[] = {0x37, 0x38, 0x39, 0x3B, 0x33, 0x3C};
  const std::uint8_t mode = modes[(control >> 3) % 6];
  const std::string text = in.text(in.byte());
  fuzz::expect_errors([&] { parse_hesai_calibration(text, "fuzz.csv"); });
  HesaiDecoderOptions options;
  options.calibration = parse_hesai_calibration(calibration_text(f.channels), "fuzz.csv");
  options.return_selection = static_cast<HesaiReturnSelection>((control >> 6) % 3);
  options.keep_partial_scans = (control & 0x04) != 0;
  options.cut_azimuth_deg = (control >> 5) * 45.0;
  fuzz::expect_errors([&] {
    HesaiDecoder decoder(options);
    HesaiParsedPacket parsed;
    std::vector<HesaiPoint> points;
    std::vector<std::uint8_t> packet;
    std::int64_t stamp_ns = 1'700'000'000'000'000'000;
    while (!in.done()) {
      const std::uint8_t head = in.byte();
      const std::size_t n = (head & 0x80) != 0 ? static_cast<std::size_t>(head & 0x3F) * 23
                                               : f.packet_bytes() + ((head & 0x20) != 0 ? 4 : 0);
      in.chunk(n, packet);
      if ((head & 0x40) != 0 && n >= f.packet_bytes()) repair(packet, f, mode);
      stamp_ns += static_cast<std::int64_t>(head & 0x0F) * 400'000;
      if (const HesaiFormat* g = identify_hesai_packet(packet)) {
        if (parse_hesai_packet(packet, *g, parsed) == HesaiPacketStatus::kOk &&
            g->channels == f.channels) {
          points.clear();
          append_hesai_points(parsed, options.calibration, points);
        }
      }
      decoder.add_packet(packet, stamp_ns);
      fuzz::drain_decoder(decoder);
    }
    decoder.finish();
    fuzz::drain_decoder(decoder);
  });
  return 0;
}
