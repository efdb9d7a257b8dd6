#include "ringtrack/io/hesai_udp_source.hpp"

#include <utility>

#include "ringtrack/io/hesai_pcap_source.hpp"

namespace ringtrack::io {
namespace {

// The Hesai decoder behind the receiver. Hesai packets carry no absolute time the decoder uses:
// it stamps each firing from the packet's receive time (the kernel's, here; the capture's in a
// pcap), so live scans hold the same cells as a capture of the same packets, at other stamps.
// Damaged packets are counted, as in a capture, not fatal: one bad datagram on a live network
// must not end a run.
class HesaiUdpDecoder final : public UdpPacketDecoder {
 public:
  explicit HesaiUdpDecoder(sensors::hesai::HesaiDecoderOptions options)
      : decoder_(std::move(options)) {}
  void add_packet(std::span<const std::uint8_t> payload, std::int64_t stamp_ns) override {
    (void)decoder_.add_packet(payload, stamp_ns);  // the status is counted in stats()
  }
  std::optional<core::OrganizedScan> pop_scan() override { return decoder_.pop_scan(); }
  void finish() override { decoder_.finish(); }
  [[nodiscard]] std::optional<core::SensorModel> model() const override {
    if (!decoder_.has_model()) return std::nullopt;
    return decoder_.model();
  }
  [[nodiscard]] std::string summary(const UdpStats& socket) const override {
    const auto& d = decoder_.stats();
    std::string s = std::to_string(socket.datagrams) + " datagrams, " +
                    std::to_string(d.decoded_packets) + " Hesai packets decoded, " +
                    std::to_string(d.scans) + " scans";
    if (socket.dropped_scans > 0) {
      s += ", " + std::to_string(socket.dropped_scans) + " scans dropped (consumer behind)";
    }
    s += hesai_problem_counts(d);
    if (socket.receive_errors > 0) {
      s += ", " + std::to_string(socket.receive_errors) + " receive errors";
    }
    return s;
  }
  [[nodiscard]] const sensors::hesai::HesaiDecoderStats& stats() const { return decoder_.stats(); }

 private:
  sensors::hesai::HesaiDecoder decoder_;
};

}  // namespace

HesaiUdpSource::HesaiUdpSource(const UdpOptions& options,
                               sensors::hesai::HesaiDecoderOptions decoder_options)
    : UdpPacketSource(options, std::make_unique<HesaiUdpDecoder>(std::move(decoder_options))) {}

sensors::hesai::HesaiDecoderStats HesaiUdpSource::decoder_stats() const {
  const auto lock = lock_decoder();
  return static_cast<const HesaiUdpDecoder&>(decoder()).stats();
}

std::unique_ptr<ScanSource> open_hesai_udp_source(const std::string& url,
                                                  sensors::hesai::HesaiDecoderOptions decoder,
                                                  const VelodyneSourceOptions& live) {
  UdpOptions udp = parse_udp_url(url);
  udp.max_queued_scans = live.udp_max_queued_scans;
  return std::make_unique<UdpScanSource>(std::make_unique<HesaiUdpSource>(udp, std::move(decoder)),
                                         url + " (live Hesai UDP)", live.interrupt);
}

}  // namespace ringtrack::io
