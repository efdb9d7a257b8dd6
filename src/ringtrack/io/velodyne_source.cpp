#include "ringtrack/io/velodyne_source.hpp"

#include <chrono>

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

class UdpInput final : public ScanSource {
 public:
  UdpInput(const std::string& input, const VelodyneSourceOptions& o)
      : source_(udp_options(input, o), o.decoder), interrupt_(o.interrupt), input_(input) {}
  std::optional<core::OrganizedScan> next() override {
    using namespace std::chrono_literals;
    while (true) {
      if (interrupt_ != nullptr && interrupt_->load() && !source_.stopped()) source_.stop();
      if (auto scan = source_.next(100ms)) {
        if (!model_) model_ = source_.model();
        return scan;
      }
      if (source_.stopped()) return source_.next(0ms);
    }
  }
  [[nodiscard]] const core::SensorModel& model() const override {
    if (!model_) throw core::Error("udp input: the model is not known before the first scan");
    return *model_;
  }
  [[nodiscard]] std::string description() const override { return input_ + " (live Velodyne UDP)"; }
  [[nodiscard]] std::string summary() const override { return source_.summary(); }
  [[nodiscard]] bool live() const override { return true; }

 private:
  static VelodyneUdpOptions udp_options(const std::string& input, const VelodyneSourceOptions& o) {
    VelodyneUdpOptions u = parse_udp_url(input);
    u.max_queued_scans = o.udp_max_queued_scans;
    return u;
  }
  VelodyneUdpSource source_;
  const std::atomic<bool>* interrupt_;
  std::string input_;
  std::optional<core::SensorModel> model_;  // copied from the receiver's decoder once known
};

}  // namespace

std::unique_ptr<ScanSource> open_velodyne_pcap_source(const std::string& path,
                                                      const VelodyneSourceOptions& options) {
  return std::make_unique<PcapInput>(path, options);
}

std::unique_ptr<ScanSource> open_velodyne_udp_source(const std::string& url,
                                                     const VelodyneSourceOptions& options) {
  return std::make_unique<UdpInput>(url, options);
}

}  // namespace ringtrack::io
