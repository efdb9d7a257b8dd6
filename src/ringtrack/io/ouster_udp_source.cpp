#include "ringtrack/io/ouster_udp_source.hpp"

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

// The Ouster decoder behind the receiver. Its scans carry the sensor's column stamps, so the
// receive stamps are not used and live scans equal those of a capture of the same packets.
class OusterUdpDecoder final : public UdpPacketDecoder {
 public:
  OusterUdpDecoder(std::string where, sensors::ouster::OusterMetadata metadata,
                   sensors::ouster::OusterDecoderOptions options)
      : where_(std::move(where)), decoder_(std::move(metadata), options) {}
  void add_packet(std::span<const std::uint8_t> payload, std::int64_t stamp_ns) override {
    try {
      decoder_.add_packet(payload, stamp_ns);
    } catch (const core::InputError& e) {
      throw core::InputError(where_ + ": " + e.what());  // name the input, as the pcap path does
    }
  }
  std::optional<core::OrganizedScan> pop_scan() override { return decoder_.pop_scan(); }
  void finish() override { decoder_.finish(); }
  [[nodiscard]] std::optional<core::SensorModel> model() const override { return decoder_.model(); }
  [[nodiscard]] std::string summary(const UdpStats& socket) const override {
    const auto& d = decoder_.stats();
    std::string s = std::to_string(socket.datagrams) + " datagrams, " +
                    std::to_string(d.decoded_packets) + " Ouster lidar packets decoded (" +
                    sensors::ouster::to_string(decoder_.metadata().profile) + "), " +
                    std::to_string(d.scans) + " scans";
    const auto add = [&s](const char* what, std::uint64_t n) {
      if (n > 0) s += ", " + std::to_string(n) + " " + what;
    };
    add("scans dropped (consumer behind)", socket.dropped_scans);
    add("wrong-size packets", d.wrong_size);
    add("columns flagged invalid", d.invalid_columns);
    add("bad measurement ids", d.bad_measurement_id);
    add("lost columns", d.lost_columns);
    add("partial scans dropped", d.partial_scans_dropped);
    add("receive errors", socket.receive_errors);
    return s;
  }
  [[nodiscard]] const sensors::ouster::OusterDecoderStats& stats() const {
    return decoder_.stats();
  }

 private:
  std::string where_;
  sensors::ouster::OusterDecoder decoder_;
};

}  // namespace

OusterUdpSource::OusterUdpSource(const UdpOptions& options,
                                 sensors::ouster::OusterMetadata metadata,
                                 sensors::ouster::OusterDecoderOptions decoder_options)
    : UdpPacketSource(options, std::make_unique<OusterUdpDecoder>(
                                   "udp://" + options.host + ":" + std::to_string(options.port),
                                   std::move(metadata), decoder_options)) {}

sensors::ouster::OusterDecoderStats OusterUdpSource::decoder_stats() const {
  const auto lock = lock_decoder();
  return static_cast<const OusterUdpDecoder&>(decoder()).stats();
}

std::unique_ptr<ScanSource> open_ouster_udp_source(const std::string& url,
                                                   sensors::ouster::OusterMetadata metadata,
                                                   sensors::ouster::OusterDecoderOptions decoder,
                                                   const VelodyneSourceOptions& live) {
  UdpOptions udp = parse_udp_url(url, kOusterLidarPort);
  udp.max_queued_scans = live.udp_max_queued_scans;
  return std::make_unique<UdpScanSource>(
      std::make_unique<OusterUdpSource>(std::move(udp), std::move(metadata), decoder),
      url + " (live Ouster UDP)", live.interrupt);
}

}  // namespace ringtrack::io
