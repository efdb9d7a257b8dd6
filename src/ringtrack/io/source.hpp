#pragma once
/// The one interface every scan input implements (pcap captures of Velodyne, Hesai and Ouster
/// sensors, live Velodyne and Ouster UDP, ROS 1 and ROS 2 bags, sequence folders, folders of PCD or
/// KITTI-style .bin files). Open one with io::open_source (scan_source.hpp), which guesses the
/// kind of input from its name and contents; front ends then read scans without knowing which
/// kind it is.

#include <cstdint>
#include <optional>
#include <string>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/sensor_model.hpp"

namespace ringtrack::io {

class SequenceReader;

/// A stream of organized scans (the fixed structure-of-arrays scan, core/organized_scan.hpp),
/// each stamped, with the sensor's pose when the input carries one.
class ScanSource {
 public:
  virtual ~ScanSource() = default;
  /// The next scan; nullopt at the end (files) or once interrupted and drained (live). Throws
  /// core::InputError naming the file and offset, message or scan that cannot be read.
  virtual std::optional<core::OrganizedScan> next() = 0;
  /// The pose (sensor in world, at the scan's stamp) of the scan next() returned last, when the
  /// input carries poses (a sequence folder's poses.txt); nullopt otherwise.
  [[nodiscard]] virtual std::optional<core::Pose> pose() const { return std::nullopt; }
  /// The sensor model (for packet inputs known after the first scan).
  [[nodiscard]] virtual const core::SensorModel& model() const = 0;
  /// What the input is, for messages: its name and kind ("x.pcap (Velodyne pcap)").
  [[nodiscard]] virtual std::string description() const = 0;
  /// One line of counters for the log (packets, drops, organized clouds, ...); may be "".
  [[nodiscard]] virtual std::string summary() const = 0;
  /// True for a live input (no end of its own).
  [[nodiscard]] virtual bool live() const { return false; }
  /// A problem the input survived, in one line (e.g. a bag file cut off); "" when none. Known
  /// once next() returned nothing.
  [[nodiscard]] virtual std::string warning() const { return {}; }
  /// Messages or files taken from the container so far, nullopt when the input cannot tell. A
  /// scan that failed can be read past (ScanReader, --on-bad-scan skip) only when this count
  /// moved: the next call then starts after the bad item instead of failing on it again.
  [[nodiscard]] virtual std::optional<std::uint64_t> items_taken() const { return std::nullopt; }
  /// Number of scans when known in advance (folders), 0 otherwise (recordings, streams).
  [[nodiscard]] virtual std::size_t size() const { return 0; }
  /// The folder reader behind a folder input (every scan's pose for motion compensation, the
  /// sensor height a sequence states, whether columns carry real times); nullptr otherwise.
  [[nodiscard]] virtual const SequenceReader* sequence() const { return nullptr; }
};

}  // namespace ringtrack::io
