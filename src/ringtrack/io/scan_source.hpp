#pragma once
/// Opens any scan input by name through one call, io::open_source: Velodyne, Hesai or Ouster
/// pcap/pcapng files, live Velodyne or Ouster UDP (udp://HOST:PORT), ROS 1 bags and ROS 2 bags in
/// sqlite3 or MCAP (VelodyneScan, PandarScan, Ouster PacketMsg or PointCloud2 topics), and folders
/// of scan files (sequence folders with their poses, PCD or KITTI-style .bin files). Every input is
/// an io::ScanSource (source.hpp). The kind of input is guessed from the name and contents; the
/// sensor is recognised from the packets (Velodyne factory bytes, Hesai header) or named
/// (`velodyne.decoder.model`). See docs/inputs.md, docs/hesai.md and docs/cpp.md.

#include <filesystem>
#include <memory>
#include <string>

#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/source.hpp"
#include "ringtrack/io/velodyne_source.hpp"

namespace ringtrack::io {

/// Kinds of input.
enum class ScanInputFormat {
  kAuto,     ///< from the name and contents (guess_scan_input_format)
  kPcap,     ///< .pcap / .pcapng capture of Velodyne, Hesai or Ouster packets
  kUdp,      ///< live Velodyne or (with metadata) Ouster packets: udp://HOST:PORT
  kRosbag1,  ///< ROS 1 .bag file
  kRosbag2,  ///< rosbag2 folder (sqlite3 or mcap storage), .db3 file or MCAP file
  kFolder,   ///< sequence folder, folder of PCD files or of KITTI-style .bin files (sequence.hpp)
};

/// Everything an input needs; each kind of input reads the fields that concern it.
struct ScanSourceOptions {
  ScanInputFormat format{ScanInputFormat::kAuto};
  /// Packet decoding, pcap ports, UDP queue and interrupt flag; the decoder's model, scan rate
  /// and cut azimuth apply to point clouds and folders too.
  VelodyneSourceOptions velodyne;
  std::string topic;               ///< bags: the topic (default: the first supported one)
  std::string ring_field{"ring"};  ///< bags with PointCloud2: the ring field's name
  /// Hesai inputs: the sensor's angle-correction CSV (required for them).
  std::string calibration;
  /// Ouster inputs: the sensor's metadata JSON (required for them).
  std::string metadata;
  /// Folders: a poses file replacing the folder's poses.txt (empty: the folder's own, if any).
  /// Recordings carry no poses: match a TUM trajectory to their stamps (io::read_tum).
  std::filesystem::path poses;
  PoseFileFormat poses_format{PoseFileFormat::kTum};  ///< format of `poses` / poses.txt

  /// Checks the values that do not depend on the input; throws core::ConfigError naming the
  /// option and what was expected.
  void validate() const;
};

/// Parses a format name: auto, pcap (pcapng), udp, bag (rosbag, rosbag1, ros1), rosbag2 (bag2,
/// ros2, db3, mcap), folder (pcd, bin); throws core::ConfigError.
ScanInputFormat parse_scan_input_format(const std::string& name);
/// The format an input implies: udp:// URLs, pcap files by extension, bags by their magic or
/// layout, any other folder as a folder of scan files; throws core::InputError when it cannot
/// tell.
ScanInputFormat guess_scan_input_format(const std::string& input);
/// True when a sensor name is a Hesai model (sensors/hesai).
bool is_hesai_model_name(const std::string& name);
/// Opens an input (options.format, or guessed) as the ScanSource for its kind; throws
/// core::InputError / core::ConfigError naming the input or option and what was expected.
std::unique_ptr<ScanSource> open_source(const std::string& uri, const ScanSourceOptions& options);

}  // namespace ringtrack::io
