#pragma once
/// One interface over the Velodyne inputs (pcap/pcapng files, live UDP; ROS 2 bags through the
/// bag source of rosbag_source.hpp), chosen from the input's name. Front ends (`ringtrack run`,
/// `ringtrack convert`) open every input through open_scan_source (scan_source.hpp).

#include <atomic>
#include <memory>
#include <optional>
#include <string>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/io/velodyne_pcap_source.hpp"
#include "ringtrack/io/velodyne_udp_source.hpp"

namespace ringtrack::io {

/// Kinds of Velodyne input.
enum class VelodyneInputFormat {
  kAuto,     ///< from the name: udp://..., *.pcap / *.pcapng, a rosbag2 folder or *.db3
  kPcap,     ///< classic pcap or pcapng
  kRosbag2,  ///< rosbag2 folder or .db3 file (read by RosbagScanSource, like open_scan_source)
  kUdp,      ///< live: udp://HOST:PORT
};

/// Everything a Velodyne input needs.
struct VelodyneSourceOptions {
  VelodyneInputFormat format{VelodyneInputFormat::kAuto};
  VelodyneDecoderOptions decoder;
  VelodynePcapOptions pcap;
  std::string topic;  ///< rosbag2: topic (default: as RosbagSourceOptions::topic)
  std::size_t udp_max_queued_scans{2};
  /// Live input: when set and true, next() stops the source and returns the remaining scans
  /// (set it from a SIGINT handler).
  const std::atomic<bool>* interrupt{nullptr};
};

/// A stream of scans from some Velodyne input.
class VelodyneScanSource {
 public:
  virtual ~VelodyneScanSource() = default;
  /// The next scan; nullopt at the end (files) or once interrupted and drained (live).
  virtual std::optional<core::OrganizedScan> next() = 0;
  /// The sensor model (known after the first scan).
  [[nodiscard]] virtual const core::SensorModel& model() const = 0;
  /// One line of counters for the log.
  [[nodiscard]] virtual std::string summary() const = 0;
  /// True for a live input (no end of its own).
  [[nodiscard]] virtual bool live() const { return false; }
  /// A problem the input survived, in one line (e.g. a bag file cut off); "" when none. Known
  /// once next() returned nothing.
  [[nodiscard]] virtual std::string warning() const { return {}; }
};

/// Parses a format name: auto, pcap, rosbag2 (or bag2, ros2), udp; throws core::ConfigError.
VelodyneInputFormat parse_velodyne_input_format(const std::string& name);
/// The format an input name implies (kAuto resolved); throws core::InputError when unknown.
VelodyneInputFormat guess_velodyne_input_format(const std::string& input);
/// Opens an input; throws core::InputError / core::ConfigError naming it.
std::unique_ptr<VelodyneScanSource> open_velodyne_source(const std::string& input,
                                                         const VelodyneSourceOptions& options);

}  // namespace ringtrack::io
