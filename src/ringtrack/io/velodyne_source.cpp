#include "ringtrack/io/velodyne_source.hpp"

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {
namespace {

class PcapInput final : public ScanSource {
 public:
  PcapInput(const std::string& input, const VelodyneSourceOptions& o)
      : source_(input, o.pcap, o.decoder), input_(input) {}
  std::optional<core::OrganizedScan> next() override { return source_.next(); }
  [[nodiscard]] const core::SensorModel& model() const override {
    return source_.decoder().model();
  }
  [[nodiscard]] std::string description() const override { return input_ + " (Velodyne pcap)"; }
  [[nodiscard]] std::string summary() const override { return source_.summary(); }

 private:
  VelodynePcapSource source_;
  std::string input_;
};

}  // namespace

std::unique_ptr<ScanSource> open_velodyne_pcap_source(const std::string& path,
                                                      const VelodyneSourceOptions& options) {
  return std::make_unique<PcapInput>(path, options);
}

std::unique_ptr<ScanSource> open_velodyne_udp_source(const std::string& url,
                                                     const VelodyneSourceOptions& options) {
  VelodyneUdpOptions udp = parse_udp_url(url);
  udp.max_queued_scans = options.udp_max_queued_scans;
  return std::make_unique<UdpScanSource>(
      std::make_unique<VelodyneUdpSource>(std::move(udp), options.decoder),
      url + " (live Velodyne UDP)", options.interrupt);
}

}  // namespace ringtrack::io
