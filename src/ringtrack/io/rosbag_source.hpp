#pragma once
/// Organized scans from ROS bags (ROS 1 .bag or rosbag2): velodyne_msgs/VelodyneScan topics
/// through the Velodyne decoder, pandar_msgs/PandarScan through the Hesai decoder, Ouster
/// PacketMsg topics through the Ouster decoder, sensor_msgs/PointCloud2 topics through
/// PointCloud2Organizer.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/io/pointcloud2.hpp"
#include "ringtrack/io/rosbag_reader.hpp"
#include "ringtrack/io/source.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"
#include "ringtrack/sensors/hesai/hesai_decoder.hpp"
#include "ringtrack/sensors/ouster/ouster_decoder.hpp"

namespace ringtrack::io {

/// velodyne_msgs/VelodyneScan (type name without "/msg/").
inline constexpr const char* kVelodyneScanRosType = "velodyne_msgs/VelodyneScan";
/// pandar_msgs/PandarScan (type name without "/msg/"): Hesai packets.
inline constexpr const char* kPandarScanRosType = "pandar_msgs/PandarScan";
/// ouster_sensor_msgs/PacketMsg (type name without "/msg/"): one raw Ouster packet (ouster-ros,
/// ROS 2); lidar packets on /ouster/lidar_packets, IMU packets of the same type on another topic.
inline constexpr const char* kOusterPacketRosType = "ouster_sensor_msgs/PacketMsg";
/// ouster_ros/PacketMsg: the same message as ouster-ros's ROS 1 driver names it.
inline constexpr const char* kOusterRos1PacketRosType = "ouster_ros/PacketMsg";
/// sensor_msgs/PointCloud2 (type name without "/msg/").
inline constexpr const char* kPointCloud2RosType = "sensor_msgs/PointCloud2";

/// One packet of a velodyne_msgs/VelodyneScan message.
struct VelodyneScanPacket {
  std::int64_t stamp_ns{0};            ///< the packet's header time
  std::span<const std::uint8_t> data;  ///< its 1206 bytes (points into the message)
};

/// Parses a serialized velodyne_msgs/VelodyneScan (Header, then VelodynePacket[] of {time
/// stamp, uint8[1206] data}) in either serialization; throws core::InputError naming `where`,
/// the byte offset and what was expected.
std::vector<VelodyneScanPacket> parse_velodyne_scan(std::span<const std::uint8_t> message,
                                                    RosSerialization serialization,
                                                    const std::string& where);

/// One packet of a pandar_msgs/PandarScan message.
struct PandarScanPacket {
  std::int64_t stamp_ns{0};            ///< the packet's stamp
  std::span<const std::uint8_t> data;  ///< its `size` bytes of the uint8[1500] buffer
};

/// Parses a serialized pandar_msgs/PandarScan (Header, then PandarPacket[] of {time stamp,
/// uint8[1500] data, uint32 size}); throws core::InputError naming `where`, the byte offset and
/// what was expected (also for a size above 1500).
std::vector<PandarScanPacket> parse_pandar_scan(std::span<const std::uint8_t> message,
                                                RosSerialization serialization,
                                                const std::string& where);

/// Parses a serialized Ouster PacketMsg (`uint8[] buf`) into its buffer (pointing into the
/// message); throws core::InputError naming `where`, the byte offset and what was expected.
std::span<const std::uint8_t> parse_ouster_packet_msg(std::span<const std::uint8_t> message,
                                                      RosSerialization serialization,
                                                      const std::string& where);

/// What to read from a bag and how.
struct RosbagSourceOptions {
  std::string topic;  ///< "" = the first topic of a supported type (in the bag's order)
  VelodyneDecoderOptions decoder;  ///< for VelodyneScan topics
  PointCloud2Options cloud;        ///< for PointCloud2 topics
  /// For PandarScan topics (its calibration, or calibration_path, is required there).
  sensors::hesai::HesaiDecoderOptions hesai;
  std::string calibration_path;  ///< read into hesai.calibration when that is empty
  /// For Ouster PacketMsg topics: the sensor's metadata JSON (required there).
  std::string metadata_path;
  sensors::ouster::OusterDecoderOptions ouster;  ///< for Ouster PacketMsg topics
};

/// Counters of a bag source.
struct RosbagSourceStats {
  std::uint64_t messages{0};  ///< messages of the chosen topic read
  std::uint64_t packets{0};   ///< VelodyneScan topics: packets in them
};

/// Reads one topic of a ROS 1 or ROS 2 bag and yields one OrganizedScan per revolution
/// (VelodyneScan: the decoder's scans; PointCloud2: one scan per cloud).
class RosbagScanSource final : public ScanSource {
 public:
  /// Opens a bag (open_rosbag) and chooses the topic; throws core::InputError when the bag or
  /// the topic's type is unusable, core::ConfigError for an unknown topic or bad options.
  explicit RosbagScanSource(const std::filesystem::path& path, RosbagSourceOptions options = {});
  /// Same, over an opened reader.
  RosbagScanSource(std::unique_ptr<RosbagReader> reader, RosbagSourceOptions options);

  /// The next scan, or nullopt at the end; throws core::InputError naming the file, topic and
  /// message index on corrupt messages.
  std::optional<core::OrganizedScan> next() override;
  /// The sensor model (known after the first scan).
  [[nodiscard]] const core::SensorModel& model() const override;
  /// The bag's name and the topic read.
  [[nodiscard]] std::string description() const override;
  /// One line of counters.
  [[nodiscard]] std::string summary() const override;
  /// The bag reader's warning (e.g. an MCAP file cut off).
  [[nodiscard]] std::string warning() const override { return reader_->warning(); }
  /// Messages taken from the topic (counted before decoding, so a bad one can be read past).
  [[nodiscard]] std::optional<std::uint64_t> items_taken() const override {
    return stats_.messages;
  }

  /// The chosen topic.
  [[nodiscard]] const RosbagTopicInfo& topic() const { return topic_; }
  /// True for a VelodyneScan topic.
  [[nodiscard]] bool velodyne_packets() const { return packets_topic_; }
  /// The Hesai decoder of a PandarScan topic (nullptr otherwise).
  [[nodiscard]] const sensors::hesai::HesaiDecoder* hesai_decoder() const {
    return hesai_ ? &*hesai_ : nullptr;
  }
  /// The Ouster decoder of a PacketMsg topic (nullptr otherwise).
  [[nodiscard]] const sensors::ouster::OusterDecoder* ouster_decoder() const {
    return ouster_ ? &*ouster_ : nullptr;
  }
  /// The bag reader.
  [[nodiscard]] const RosbagReader& reader() const { return *reader_; }
  /// The packet decoder (VelodyneScan topics).
  [[nodiscard]] const VelodyneDecoder& decoder() const { return decoder_; }
  /// The cloud organizer (PointCloud2 topics).
  [[nodiscard]] const PointCloud2Organizer& organizer() const { return organizer_; }
  /// Counters.
  [[nodiscard]] const RosbagSourceStats& stats() const { return stats_; }

 private:
  [[nodiscard]] std::string where(std::uint64_t index) const;
  void open_ouster(const RosbagSourceOptions& options);
  std::optional<core::OrganizedScan> next_ouster();
  std::optional<core::OrganizedScan> next_hesai();

  std::unique_ptr<RosbagReader> reader_;
  RosbagTopicInfo topic_;
  bool packets_topic_{false};
  VelodyneDecoder decoder_;
  PointCloud2Organizer organizer_;
  std::optional<sensors::hesai::HesaiDecoder> hesai_;
  std::optional<sensors::ouster::OusterDecoder> ouster_;
  RosbagSourceStats stats_;
  bool finished_{false};
};

}  // namespace ringtrack::io
