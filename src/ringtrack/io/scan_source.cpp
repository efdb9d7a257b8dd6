#include "ringtrack/io/scan_source.hpp"

#include <cctype>
#include <filesystem>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/hesai_pcap_source.hpp"
#include "ringtrack/io/mcap_bag_reader.hpp"
#include "ringtrack/io/ouster_pcap_source.hpp"
#include "ringtrack/io/rosbag1_reader.hpp"
#include "ringtrack/io/rosbag2_reader.hpp"
#include "ringtrack/io/rosbag_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/sensors/hesai/hesai_calibration.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"

namespace ringtrack::io {

namespace fs = std::filesystem;

ScanInputFormat parse_scan_input_format(const std::string& name) {
  if (name.empty() || name == "auto") return ScanInputFormat::kAuto;
  if (name == "pcap" || name == "pcapng") return ScanInputFormat::kPcap;
  if (name == "udp") return ScanInputFormat::kUdp;
  if (name == "bag" || name == "rosbag" || name == "rosbag1" || name == "ros1") {
    return ScanInputFormat::kRosbag1;
  }
  if (name == "rosbag2" || name == "bag2" || name == "ros2" || name == "db3" || name == "mcap") {
    return ScanInputFormat::kRosbag2;
  }
  if (name == "folder" || name == "pcd" || name == "bin") return ScanInputFormat::kFolder;
  throw core::ConfigError("input format '" + name +
                          "': expected auto, pcap, udp, bag (ROS 1), rosbag2, mcap or folder");
}

namespace {

// A sequence folder, or a folder holding at least one .pcd or .bin file.
bool is_scan_folder(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_directory(path, ec)) return false;
  if (fs::exists(path / "sequence.yaml", ec)) return true;
  for (const auto& entry : fs::directory_iterator(path, ec)) {
    std::string ext = entry.path().extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    if ((ext == ".pcd" || ext == ".bin") && entry.is_regular_file(ec)) return true;
  }
  return false;
}

}  // namespace

ScanInputFormat guess_scan_input_format(const std::string& input) {
  if (input.rfind("udp://", 0) == 0) return ScanInputFormat::kUdp;
  const fs::path path(input);
  std::error_code ec;
  if (!fs::exists(path, ec)) throw core::InputError(input + ": no such file or folder");
  const std::string ext = path.extension().string();
  if (ext == ".pcap" || ext == ".pcapng" || ext == ".cap") return ScanInputFormat::kPcap;
  if (is_rosbag1_file(path) || ext == ".bag") return ScanInputFormat::kRosbag1;
  if (is_mcap_bag(path)) return ScanInputFormat::kRosbag2;  // by its magic, whatever the name
  if (is_rosbag2_path(path)) return ScanInputFormat::kRosbag2;
  if (is_scan_folder(path)) return ScanInputFormat::kFolder;
  throw core::InputError(input +
                         ": cannot tell the input format (expected udp://HOST:PORT, a .pcap/"
                         ".pcapng file, a ROS 1 .bag file, a rosbag2 folder or a folder of "
                         "PCD or .bin files); name it with --format");
}

bool is_hesai_model_name(const std::string& name) {
  return !name.empty() && sensors::hesai::hesai_format_by_name(name) != nullptr;
}

namespace {

// Hesai decoder options from the shared ones: the model name, return, cut and rate.
sensors::hesai::HesaiDecoderOptions hesai_options(const ScanSourceOptions& options) {
  const VelodyneDecoderOptions& v = options.velodyne.decoder;
  sensors::hesai::HesaiDecoderOptions h;
  h.model = is_hesai_model_name(v.model) ? v.model : "";
  switch (v.return_selection) {
    case VelodyneReturnSelection::kAuto:
      h.return_selection = sensors::hesai::HesaiReturnSelection::kAuto;
      break;
    case VelodyneReturnSelection::kStrongest:
      h.return_selection = sensors::hesai::HesaiReturnSelection::kStrongest;
      break;
    case VelodyneReturnSelection::kLast:
      h.return_selection = sensors::hesai::HesaiReturnSelection::kLast;
      break;
  }
  h.cut_azimuth_deg = v.cut_azimuth_deg;
  h.scan_rate_hz = v.scan_rate_hz;
  h.keep_partial_scans = v.keep_partial_scans;
  return h;
}

// A folder of scan files as a stream of scans (stamps from its stamps.txt or the scan rate).
class FolderScanSource : public ScanSource {
 public:
  FolderScanSource(const std::string& input, SequenceReadOptions options)
      : reader_(input, std::move(options)) {}
  std::optional<core::OrganizedScan> next() override {
    SequenceScan item;
    if (!reader_.next(item)) return std::nullopt;
    return std::move(item.scan);
  }
  [[nodiscard]] const core::SensorModel& model() const override { return reader_.sensor(); }
  [[nodiscard]] std::string summary() const override {
    std::string line = std::to_string(reader_.size()) + " scan files";
    if (const auto organized = reader_.summary(); !organized.empty()) line += "; " + organized;
    return line;
  }

 private:
  SequenceReader reader_;
};

}  // namespace

std::unique_ptr<ScanSource> open_scan_source(const std::string& input,
                                             const ScanSourceOptions& options) {
  const ScanInputFormat format =
      options.format == ScanInputFormat::kAuto ? guess_scan_input_format(input) : options.format;
  switch (format) {
    case ScanInputFormat::kPcap:
      if (!options.metadata.empty()) {
        return std::make_unique<OusterPcapSource>(
            input, sensors::ouster::read_ouster_metadata(options.metadata));
      }
      if (pcap_holds_ouster(input)) {
        throw core::InputError(input +
                               ": Ouster lidar packets (port 7502); give the sensor's metadata "
                               "JSON with --metadata FILE");
      }
      if (is_hesai_model_name(options.velodyne.decoder.model) ||
          pcap_holds_hesai(input, options.velodyne.pcap.data_port)) {
        if (options.calibration.empty()) {
          throw core::InputError(input +
                                 ": Hesai packets; give the sensor's angle-correction file with "
                                 "--calibration FILE");
        }
        auto h = hesai_options(options);
        h.calibration = sensors::hesai::read_hesai_calibration(options.calibration);
        return std::make_unique<HesaiPcapSource>(input, options.velodyne.pcap.data_port,
                                                 std::move(h),
                                                 options.velodyne.pcap.allow_truncated);
      }
      [[fallthrough]];
    case ScanInputFormat::kUdp: {
      VelodyneSourceOptions v = options.velodyne;
      v.format =
          format == ScanInputFormat::kPcap ? VelodyneInputFormat::kPcap : VelodyneInputFormat::kUdp;
      return open_velodyne_source(input, v);
    }
    case ScanInputFormat::kRosbag1:
    case ScanInputFormat::kRosbag2: {
      RosbagSourceOptions b;
      b.topic = options.topic;
      b.decoder = options.velodyne.decoder;
      if (is_hesai_model_name(b.decoder.model)) b.decoder.model.clear();
      b.hesai = hesai_options(options);
      b.calibration_path = options.calibration;
      b.cloud.model = is_hesai_model_name(options.velodyne.decoder.model)
                          ? std::string()
                          : options.velodyne.decoder.model;
      b.cloud.scan_rate_hz = options.velodyne.decoder.scan_rate_hz;
      b.cloud.cut_azimuth_deg = options.velodyne.decoder.cut_azimuth_deg;
      b.cloud.ring_field = options.ring_field;
      std::unique_ptr<RosbagReader> reader;
      if (format == ScanInputFormat::kRosbag1) {
        reader = std::make_unique<Rosbag1Reader>(input);
      } else if (is_mcap_bag(input)) {
        reader = std::make_unique<McapBagReader>(input);
      } else {
        reader = std::make_unique<Rosbag2Reader>(input);
      }
      return std::make_unique<RosbagScanSource>(std::move(reader), std::move(b));
    }
    case ScanInputFormat::kFolder: {
      SequenceReadOptions f;
      f.scan_rate_hz = options.velodyne.decoder.scan_rate_hz;
      if (!options.velodyne.decoder.model.empty()) {
        f.sensor = core::SensorModel::by_name(options.velodyne.decoder.model, f.scan_rate_hz);
      }
      return std::make_unique<FolderScanSource>(input, std::move(f));
    }
    case ScanInputFormat::kAuto:
      break;
  }
  throw core::InputError(input + ": cannot tell the input format");
}

}  // namespace ringtrack::io
