#include "ringtrack/io/velodyne_udp_source.hpp"

namespace ringtrack::io {
namespace {

// The Velodyne decoder behind the receiver; the summary line is the one live Velodyne runs
// always printed.
class VelodyneUdpDecoder final : public UdpPacketDecoder {
 public:
  explicit VelodyneUdpDecoder(VelodyneDecoderOptions options) : decoder_(std::move(options)) {}
  [[nodiscard]] const VelodyneDecoderStats& stats() const { return decoder_.stats(); }
  void add_packet(std::span<const std::uint8_t> payload, std::int64_t stamp_ns) override {
    decoder_.add_packet(payload, stamp_ns);
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
                    std::to_string(d.decoded_packets) + " data packets decoded, " +
                    std::to_string(d.scans) + " scans";
    const auto add = [&s](const char* what, std::uint64_t n) {
      if (n > 0) s += ", " + std::to_string(n) + " " + what;
    };
    add("scans dropped (consumer behind)", socket.dropped_scans);
    add("skipped packets", d.skipped_packets());
    add("lost firing sequences", d.lost_sequences);
    add("invalid columns", d.invalid_columns);
    add("receive errors", socket.receive_errors);
    return s;
  }

 private:
  VelodyneDecoder decoder_;
};

}  // namespace

VelodyneUdpSource::VelodyneUdpSource(VelodyneUdpOptions options,
                                     VelodyneDecoderOptions decoder_options)
    : UdpPacketSource(std::move(options),
                      std::make_unique<VelodyneUdpDecoder>(std::move(decoder_options))) {}

VelodyneDecoderStats VelodyneUdpSource::decoder_stats() const {
  const auto lock = lock_decoder();
  return static_cast<const VelodyneUdpDecoder&>(decoder()).stats();
}

}  // namespace ringtrack::io
