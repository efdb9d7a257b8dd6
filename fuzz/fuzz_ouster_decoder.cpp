// libFuzzer target: Ouster metadata text through the JSON parser, and lidar packets through the
// decoder of a fixed metadata (profile, beams, partial frames and the return selection chosen by
// the control byte; a selection the profile cannot give is a documented error). Documented errors
// (core::Error) are fine; crashes, sanitizer reports and hangs are bugs. Input: control byte, a
// length byte and that much metadata text, then packets, each led by a byte choosing its size
// (the metadata's, or a short odd one) and whether to make its columns valid with in-range
// measurement ids (so that frame assembly is reached).
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "ringtrack/sensors/ouster/ouster_decoder.hpp"
#include "ringtrack/sensors/ouster/ouster_metadata.hpp"

using namespace ringtrack;
using namespace ringtrack::sensors::ouster;

namespace {

std::string metadata_text(const char* profile, int beams) {
  std::string alt, az, shift;
  for (int i = 0; i < beams; ++i) {
    alt += (i ? "," : "") + std::to_string(20 - 40.0 * i / beams);
    az += (i ? "," : "") + std::string(i % 2 ? "1.5" : "-1.5");
    shift += (i ? "," : "") + std::to_string(4 * (i % 4));
  }
  std::string s = "{\"lidar_mode\":\"512x10\",\"beam_altitude_angles\":[" + alt +
                  "],\"beam_azimuth_angles\":[" + az +
                  "],\"lidar_origin_to_beam_origin_mm\":15,\"lidar_to_sensor_transform\":[-1,0,0,0,"
                  "0,-1,0,0,0,0,1,36,0,0,0,1],\"data_format\":{\"columns_per_frame\":512,"
                  "\"columns_per_packet\":16,\"pixels_per_column\":" +
                  std::to_string(beams) + ",\"pixel_shift_by_row\":[" + shift + "]";
  if (std::string(profile) != "LEGACY")
    s += ",\"udp_profile_lidar\":\"" + std::string(profile) + "\"";
  return s + "}}";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  fuzz::FuzzInput in(data, size);
  const std::uint8_t control = in.byte();
  const char* profiles[] = {"LEGACY", "RNG19_RFL8_SIG16_NIR16", "RNG19_RFL8_SIG16_NIR16_DUAL",
                            "RNG15_RFL8_NIR8"};
  const int beam_choices[] = {8, 16, 32, 64};
  const std::string text = in.text(in.byte());
  fuzz::expect_errors([&] { parse_ouster_metadata(text, "f.json"); });
  fuzz::expect_errors([&] {
    const OusterMetadata meta = parse_ouster_metadata(
        metadata_text(profiles[control % 4], beam_choices[(control >> 2) % 4]), "f.json");
    OusterDecoderOptions options;
    options.keep_partial_scans = (control & 0x10) != 0;
    options.return_selection = static_cast<OusterReturn>((control >> 5) % 3);
    OusterDecoder decoder(meta, options);
    const bool legacy = meta.profile == OusterProfile::kLegacy;
    const std::size_t column = (legacy ? 20 : 12) + meta.pixels_per_column * meta.pixel_bytes();
    std::vector<std::uint8_t> packet;
    while (!in.done()) {
      const std::uint8_t head = in.byte();
      const std::size_t n =
          (head & 0x80) != 0 ? static_cast<std::size_t>(head & 0x3F) * 29 : meta.packet_bytes();
      in.chunk(n, packet);
      if ((head & 0x40) != 0 && n == meta.packet_bytes()) {
        for (int c = 0; c < meta.columns_per_packet; ++c) {
          std::uint8_t* block = packet.data() + (legacy ? 0 : 32) + c * column;
          block[9] = static_cast<std::uint8_t>(block[9] % 2);  // measurement id < 512
          if (legacy) {
            std::memset(block + column - 4, 0xFF, 4);
          } else {
            block[10] |= 1;
          }
        }
      }
      decoder.add_packet(packet, 0);
      fuzz::drain_decoder(decoder);
    }
    decoder.finish();
    fuzz::drain_decoder(decoder);
  });
  return 0;
}
