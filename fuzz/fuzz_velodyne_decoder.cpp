// libFuzzer target: a stream of Velodyne packets through the packet parser, the flat point
// decoder and the scan assembler. Documented errors (core::Error) are fine; crashes, sanitizer
// reports and hangs are bugs. Input: one control byte (options), then packets, each led by a
// byte choosing its size and whether to repair its block flags and factory bytes (so that the
// fuzzer reaches scan assembly, not only the rejection paths).
#include <cstdint>
#include <vector>

#include "fuzz_support.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/io/velodyne_packet.hpp"

using namespace ringtrack;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  fuzz::FuzzInput in(data, size);
  const std::uint8_t control = in.byte();
  io::VelodyneDecoderOptions options;
  options.return_selection = static_cast<io::VelodyneReturnSelection>(control % 3);
  options.keep_partial_scans = (control & 0x04) != 0;
  if ((control & 0x08) != 0) options.model = (control & 0x10) != 0 ? "vlp32c" : "vlp16";
  options.time_source =
      (control & 0x20) != 0 ? io::VelodyneTimeSource::kSensor : io::VelodyneTimeSource::kHost;
  options.cut_azimuth_deg = (control >> 6) * 90.0;
  const std::uint8_t product = (control & 0x10) != 0 ? 0x28 : 0x22;
  const std::uint8_t mode = static_cast<std::uint8_t>(0x37 + (control >> 6) % 3);
  fuzz::expect_errors([&] {
    io::VelodyneDecoder decoder(options);
    const auto model = core::SensorModel::vlp16();
    const auto layout = io::VelodyneLayout::of(model);
    io::VelodyneParsedPacket parsed;
    std::vector<io::VelodynePoint> points;
    std::vector<std::uint8_t> packet;
    std::int64_t stamp_ns = 1'700'000'000'000'000'000;
    while (!in.done()) {
      const std::uint8_t head = in.byte();
      const std::size_t n = (head & 0x80) != 0 ? static_cast<std::size_t>(head & 0x3F) * 23 : 1206;
      in.chunk(n, packet);
      if ((head & 0x40) != 0 && n == 1206) {
        for (std::size_t b = 0; b < 12; ++b) {
          packet[b * 100] = 0xFF;
          packet[b * 100 + 1] = 0xEE;
          packet[b * 100 + 3] = static_cast<std::uint8_t>(packet[b * 100 + 3] % 141);  // < 36000
          if (mode == 0x39 && b % 2 == 1) {
            packet[b * 100 + 2] = packet[b * 100 - 98];
            packet[b * 100 + 3] = packet[b * 100 - 97];
          }
        }
        packet[1204] = mode;
        packet[1205] = product;
      }
      stamp_ns += static_cast<std::int64_t>(head & 0x0F) * 400'000;
      if (io::parse_velodyne_packet(packet, layout, 0.2, parsed) == io::VelodynePacketStatus::kOk) {
        points.clear();
        io::append_velodyne_points(parsed, model, points);
      }
      decoder.add_packet(packet, stamp_ns);
      fuzz::drain_decoder(decoder);
    }
    decoder.finish();
    fuzz::drain_decoder(decoder);
  });
  return 0;
}
