#pragma once
/// Opens any scan input by name: Velodyne or Hesai pcap/pcapng files, live Velodyne UDP
/// (velodyne_source.hpp), ROS 1 bags and ROS 2 bags (VelodyneScan, PandarScan or PointCloud2
/// topics), and folders of scan files (sequence folders, PCD or KITTI-style .bin files). The sensor
/// is recognised from the packets (Velodyne factory bytes, Hesai header) or named
/// (`velodyne.decoder.model`). See docs/inputs.md and docs/hesai.md.

#include <memory>
#include <string>

#include "ringtrack/io/pointcloud2.hpp"
#include "ringtrack/io/velodyne_source.hpp"

namespace ringtrack::io {

/// Any stream of organized scans: the interface the Velodyne inputs share, which knows nothing
/// of packets (next, model, summary, live).
using ScanSource = VelodyneScanSource;

/// Kinds of input.
enum class ScanInputFormat {
  kAuto,     ///< from the name and contents
  kPcap,     ///< .pcap / .pcapng capture of Velodyne packets
  kUdp,      ///< live Velodyne packets: udp://HOST:PORT
  kRosbag1,  ///< ROS 1 .bag file
  kRosbag2,  ///< rosbag2 folder (sqlite3 or mcap storage), .db3 file or MCAP file
  kFolder,   ///< sequence folder, folder of PCD files or of KITTI-style .bin files (sequence.hpp)
};

/// Everything an input needs.
struct ScanSourceOptions {
  ScanInputFormat format{ScanInputFormat::kAuto};
  /// Packet decoding, pcap ports, UDP queue and interrupt flag; the decoder's model, scan rate
  /// and cut azimuth apply to point clouds too.
  VelodyneSourceOptions velodyne;
  std::string topic;               ///< bags: the topic (default: the first supported one)
  std::string ring_field{"ring"};  ///< bags with PointCloud2: the ring field's name
  /// Hesai inputs: the sensor's angle-correction CSV (required for them).
  std::string calibration;
  /// Ouster inputs: the sensor's metadata JSON (required for them).
  std::string metadata;
};

/// Parses a format name: auto, pcap (pcapng), udp, bag (rosbag, rosbag1, ros1), rosbag2 (bag2,
/// ros2, db3, mcap), folder (pcd, bin); throws core::ConfigError.
ScanInputFormat parse_scan_input_format(const std::string& name);
/// The format an input implies; throws core::InputError when it cannot tell.
ScanInputFormat guess_scan_input_format(const std::string& input);
/// True when a sensor name is a Hesai model (sensors/hesai).
bool is_hesai_model_name(const std::string& name);
/// Opens an input; throws core::InputError / core::ConfigError naming it.
std::unique_ptr<ScanSource> open_scan_source(const std::string& input,
                                             const ScanSourceOptions& options);

}  // namespace ringtrack::io
