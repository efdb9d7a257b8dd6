#include "ringtrack/io/scan_source.hpp"

#include <cmath>
#include <filesystem>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/hesai_pcap_source.hpp"
#include "ringtrack/io/hesai_udp_source.hpp"
#include "ringtrack/io/mcap_bag_reader.hpp"
#include "ringtrack/io/ouster_pcap_source.hpp"
#include "ringtrack/io/ouster_udp_source.hpp"
#include "ringtrack/io/rosbag1_reader.hpp"
#include "ringtrack/io/rosbag2_reader.hpp"
#include "ringtrack/io/rosbag_reader.hpp"
#include "ringtrack/io/rosbag_source.hpp"
#include "ringtrack/io/sequence_source.hpp"
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
  // Any other folder: the folder reader says best what it lacks (an incomplete sequence, no
  // scan files, both .pcd and .bin files).
  if (fs::is_directory(path, ec)) return ScanInputFormat::kFolder;
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
    case VelodyneReturnSelection::kSecond:
      throw core::ConfigError(
          "return 'second': Hesai streams carry strongest, last and first returns; the second "
          "strongest return is Ouster's (_DUAL profile)");
  }
  h.cut_azimuth_deg = v.cut_azimuth_deg;
  h.scan_rate_hz = v.scan_rate_hz;
  h.keep_partial_scans = v.keep_partial_scans;
  return h;
}

// Ouster decoder options from the shared ones: auto and strongest are return 1.
sensors::ouster::OusterDecoderOptions ouster_options(const ScanSourceOptions& options) {
  const VelodyneDecoderOptions& v = options.velodyne.decoder;
  sensors::ouster::OusterDecoderOptions o;
  o.keep_partial_scans = v.keep_partial_scans;
  switch (v.return_selection) {
    case VelodyneReturnSelection::kAuto:
    case VelodyneReturnSelection::kStrongest:
      o.return_selection = sensors::ouster::OusterReturn::kStrongest;
      break;
    case VelodyneReturnSelection::kLast:
      o.return_selection = sensors::ouster::OusterReturn::kLast;
      break;
    case VelodyneReturnSelection::kSecond:
      o.return_selection = sensors::ouster::OusterReturn::kSecond;
      break;
  }
  return o;
}

// A live stream: nothing to recognise before it flows, so the files given decide: Ouster with
// its metadata, Hesai with its angle corrections (or a Hesai model named, which then needs
// them), Velodyne otherwise.
std::unique_ptr<ScanSource> open_udp(const std::string& uri, const ScanSourceOptions& options) {
  if (!options.metadata.empty()) {
    return open_ouster_udp_source(uri, sensors::ouster::read_ouster_metadata(options.metadata),
                                  ouster_options(options), options.velodyne);
  }
  if (!options.calibration.empty() || is_hesai_model_name(options.velodyne.decoder.model)) {
    if (options.calibration.empty()) {
      throw core::InputError(uri + ": Hesai " + options.velodyne.decoder.model +
                             " packets; give the sensor's angle-correction file with "
                             "--calibration FILE");
    }
    auto h = hesai_options(options);
    h.calibration = sensors::hesai::read_hesai_calibration(options.calibration);
    return open_hesai_udp_source(uri, std::move(h), options.velodyne);
  }
  return open_velodyne_udp_source(uri, options.velodyne);
}

// A capture: Ouster when its metadata is given, Hesai when named or recognised (its angle
// corrections are required), Velodyne otherwise.
std::unique_ptr<ScanSource> open_pcap(const std::string& input, const ScanSourceOptions& options) {
  if (!options.metadata.empty()) {
    return std::make_unique<OusterPcapSource>(
        input, sensors::ouster::read_ouster_metadata(options.metadata), ouster_options(options));
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
    return std::make_unique<HesaiPcapSource>(input, options.velodyne.pcap.data_port, std::move(h),
                                             options.velodyne.pcap.allow_truncated);
  }
  return open_velodyne_pcap_source(input, options.velodyne);
}

// A bag of either ROS version; the decoder options serve its packets, the cloud options its
// PointCloud2 topics.
std::unique_ptr<ScanSource> open_bag(const std::string& input, ScanInputFormat format,
                                     const ScanSourceOptions& options) {
  RosbagSourceOptions b;
  b.topic = options.topic;
  b.decoder = options.velodyne.decoder;
  if (is_hesai_model_name(b.decoder.model)) b.decoder.model.clear();
  // The second return comes with Ouster metadata (validate()), which excludes a Hesai
  // calibration, so such a bag never reaches the Hesai decoder.
  if (b.decoder.return_selection != VelodyneReturnSelection::kSecond) {
    b.hesai = hesai_options(options);
  }
  b.calibration_path = options.calibration;
  b.metadata_path = options.metadata;
  b.ouster = ouster_options(options);
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

// A folder of scan files with its poses (or the poses file given in their place).
std::unique_ptr<ScanSource> open_folder(const std::string& input,
                                        const ScanSourceOptions& options) {
  SequenceReadOptions f;
  f.scan_rate_hz = options.velodyne.decoder.scan_rate_hz;  // plain folders without stamps
  if (!options.velodyne.decoder.model.empty()) {
    f.sensor = core::SensorModel::by_name(options.velodyne.decoder.model, f.scan_rate_hz);
  }
  f.poses = options.poses;
  f.poses_format = options.poses_format;
  return std::make_unique<SequenceSource>(input, std::move(f));
}

}  // namespace

void ScanSourceOptions::validate() const {
  const double rate = velodyne.decoder.scan_rate_hz;
  if (!std::isfinite(rate) || rate <= 0.0) {
    throw core::ConfigError("scan rate " + std::to_string(rate) +
                            " Hz: expected a positive number of revolutions per second");
  }
  if (velodyne.pcap.data_port == 0) throw core::ConfigError("data port 0: expected 1..65535");
  if (velodyne.udp_max_queued_scans == 0) {
    throw core::ConfigError("udp_max_queued_scans 0: expected at least one queued scan");
  }
  if (ring_field.empty()) {
    throw core::ConfigError("ring field '': expected the name of a PointCloud2 field (ring)");
  }
  if (velodyne.decoder.return_selection == VelodyneReturnSelection::kSecond && metadata.empty()) {
    throw core::ConfigError(
        "return 'second': only Ouster's RNG19_RFL8_SIG16_NIR16_DUAL profile reports a second "
        "strongest return (give the sensor's metadata JSON)");
  }
  if (!calibration.empty() && !metadata.empty()) {
    throw core::ConfigError(
        "calibration (Hesai) and metadata (Ouster) given together: expected the one file of "
        "the sensor that recorded the input");
  }
}

std::unique_ptr<ScanSource> open_source(const std::string& uri, const ScanSourceOptions& options) {
  options.validate();
  const ScanInputFormat format =
      options.format == ScanInputFormat::kAuto ? guess_scan_input_format(uri) : options.format;
  if (format != ScanInputFormat::kFolder && !options.poses.empty()) {
    throw core::ConfigError("poses " + options.poses.string() + ": " + uri +
                            " is not a folder; recordings carry no poses (match a TUM "
                            "trajectory to their stamps)");
  }
  switch (format) {
    case ScanInputFormat::kPcap:
      return open_pcap(uri, options);
    case ScanInputFormat::kUdp:
      return open_udp(uri, options);
    case ScanInputFormat::kRosbag1:
    case ScanInputFormat::kRosbag2:
      return open_bag(uri, format, options);
    case ScanInputFormat::kFolder:
      return open_folder(uri, options);
    case ScanInputFormat::kAuto:
      break;
  }
  throw core::InputError(uri + ": cannot tell the input format");
}

}  // namespace ringtrack::io
