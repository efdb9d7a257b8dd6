// libFuzzer target: Hesai and Ouster captures through their pcap sources, with the sensor's
// calibration text through its reader (Hesai angle-correction CSV, Ouster metadata JSON). Input:
// a control byte (bit 0: Ouster, else Hesai; bit 1: the rest is a raw capture file, else UDP
// records built around chunks; bit 2: keep partial scans; bit 3: allow a truncated capture), a
// uint16 length and that much calibration or metadata text, then the capture: raw, or chunks
// each led by a byte choosing its size (the format's packet size, or a short odd one) and port.
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_support.hpp"
#include "ringtrack/io/hesai_pcap_source.hpp"
#include "ringtrack/io/ouster_pcap_source.hpp"
#include "ringtrack/sensors/hesai/hesai_calibration.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"
#include "ringtrack/sensors/ouster/ouster_metadata.hpp"

using namespace ringtrack;
using namespace ringtrack::sensors;

namespace {

// The capture: the rest of the input as is, or UDP records to `port` (or `other_port`) around
// chunks of `packet_bytes`.
std::vector<std::uint8_t> capture(fuzz::FuzzInput& in, bool raw, std::size_t packet_bytes,
                                  std::uint16_t port, std::uint16_t other_port) {
  if (raw) {
    const auto rest = in.rest();
    return {rest.begin(), rest.end()};
  }
  std::vector<std::uint8_t> file = fuzz::pcap_file_header(1, false);
  std::vector<std::uint8_t> payload;
  std::uint32_t second = 1'700'000'000;
  while (!in.done()) {
    const std::uint8_t head = in.byte();
    const std::size_t n =
        (head & 0x80) != 0 ? static_cast<std::size_t>(head & 0x3F) * 23 : packet_bytes;
    in.chunk(n, payload);
    fuzz::append_udp_record(file, second++, (head & 0x40) != 0 ? other_port : port, payload);
  }
  return file;
}

void fuzz_hesai(fuzz::FuzzInput& in, std::uint8_t control, const std::string& text) {
  hesai::HesaiDecoderOptions options;
  try {
    options.calibration = hesai::parse_hesai_calibration(text, "fuzz.csv");
  } catch (const core::Error&) {
    return;
  }
  options.keep_partial_scans = (control & 4) != 0;
  std::size_t packet_bytes = 1080;
  for (const auto& f : hesai::hesai_formats()) {
    if (f.channels == options.calibration.channels()) packet_bytes = f.packet_bytes();
  }
  const auto path =
      fuzz::write_scratch("input.pcap", capture(in, (control & 2) != 0, packet_bytes, 2368, 2369));
  fuzz::expect_errors([&] { (void)io::pcap_holds_hesai(path, 2368); });
  fuzz::expect_errors([&] {
    io::HesaiPcapSource source(path, 2368, options, (control & 8) != 0);
    fuzz::drain_source(source);
  });
}

void fuzz_ouster(fuzz::FuzzInput& in, std::uint8_t control, const std::string& text) {
  ouster::OusterMetadata metadata;
  try {
    metadata = ouster::parse_ouster_metadata(text, "fuzz.json");
    (void)ouster::ouster_sensor_model(metadata);
  } catch (const core::Error&) {
    return;
  }
  const auto path = fuzz::write_scratch(
      "input.pcap", capture(in, (control & 2) != 0, metadata.packet_bytes(), 7502, 7503));
  fuzz::expect_errors([&] { (void)io::pcap_holds_ouster(path); });
  fuzz::expect_errors([&] {
    io::OusterPcapSource source(path, metadata, {.keep_partial_scans = (control & 4) != 0});
    fuzz::drain_source(source);
  });
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  fuzz::FuzzInput in(data, size);
  const std::uint8_t control = in.byte();
  const std::string text = in.text(in.u16());
  if ((control & 1) != 0) {
    fuzz_ouster(in, control, text);
  } else {
    fuzz_hesai(in, control, text);
  }
  return 0;
}
