#include "ringtrack/io/velodyne_source.hpp"

#include <chrono>
#include <filesystem>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/rosbag_reader.hpp"
#include "ringtrack/io/scan_source.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

class PcapInput final : public VelodyneScanSource {
 public:
  PcapInput(const std::string& input, const VelodyneSourceOptions& o)
      : source_(input, o.pcap, o.decoder) {}
  std::optional<core::OrganizedScan> next() override { return source_.next(); }
  [[nodiscard]] const core::SensorModel& model() const override {
    return source_.decoder().model();
  }
  [[nodiscard]] std::string summary() const override { return source_.summary(); }

 private:
  VelodynePcapSource source_;
};

class UdpInput final : public VelodyneScanSource {
 public:
  UdpInput(const std::string& input, const VelodyneSourceOptions& o)
      : source_(udp_options(input, o), o.decoder), interrupt_(o.interrupt) {}
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
  std::optional<core::SensorModel> model_;  // copied from the receiver's decoder once known
};

}  // namespace

VelodyneInputFormat parse_velodyne_input_format(const std::string& name) {
  if (name == "auto" || name.empty()) return VelodyneInputFormat::kAuto;
  if (name == "pcap" || name == "pcapng") return VelodyneInputFormat::kPcap;
  if (name == "rosbag2" || name == "bag2" || name == "ros2") return VelodyneInputFormat::kRosbag2;
  if (name == "udp") return VelodyneInputFormat::kUdp;
  throw core::ConfigError("input format '" + name + "': expected auto, pcap, rosbag2 or udp");
}

VelodyneInputFormat guess_velodyne_input_format(const std::string& input) {
  if (input.rfind("udp://", 0) == 0) return VelodyneInputFormat::kUdp;
  const fs::path path(input);
  const std::string ext = path.extension().string();
  if (ext == ".pcap" || ext == ".pcapng" || ext == ".cap") return VelodyneInputFormat::kPcap;
  if (is_rosbag2_path(path)) return VelodyneInputFormat::kRosbag2;
  throw core::InputError(input +
                         ": not a Velodyne input (expected udp://HOST:PORT, a .pcap/.pcapng "
                         "file or a ROS 2 bag); name the format explicitly");
}

std::unique_ptr<VelodyneScanSource> open_velodyne_source(const std::string& input,
                                                         const VelodyneSourceOptions& options) {
  const VelodyneInputFormat format = options.format == VelodyneInputFormat::kAuto
                                         ? guess_velodyne_input_format(input)
                                         : options.format;
  switch (format) {
    case VelodyneInputFormat::kPcap:
      return std::make_unique<PcapInput>(input, options);
    case VelodyneInputFormat::kRosbag2: {
      // Bags have one reader for every front end: the generic bag source (rosbag_source.hpp).
      ScanSourceOptions bag;
      bag.format = ScanInputFormat::kRosbag2;
      bag.velodyne = options;
      bag.topic = options.topic;
      return open_scan_source(input, bag);
    }
    case VelodyneInputFormat::kUdp:
      return std::make_unique<UdpInput>(input, options);
    case VelodyneInputFormat::kAuto:
      break;
  }
  throw core::InputError(input + ": cannot tell the input format");
}

}  // namespace ringtrack::io
