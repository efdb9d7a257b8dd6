#pragma once
/// Test support: ROS message serializers (ROS 1 and CDR) and writers of ROS 1 bags (format 2.0,
/// chunks uncompressed, bz2 or lz4 frames) and rosbag2 folders (sqlite3), written from the
/// formats' public descriptions independently of src/ringtrack/io.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "support/velodyne_encoder.hpp"

namespace ringtrack::test {

/// Message serialization.
enum class RosEncoding { kRos1, kCdr };

/// One packet of a velodyne_msgs/VelodyneScan.
struct TestVelodynePacket {
  std::int64_t stamp_ns{0};
  std::vector<std::uint8_t> data;  ///< 1206 bytes
};

/// A velodyne_msgs/VelodyneScan.
struct TestVelodyneScan {
  std::uint32_t seq{0};  ///< ROS 1 only
  std::int64_t stamp_ns{0};
  std::string frame_id{"velodyne"};
  std::vector<TestVelodynePacket> packets;
};

/// One sensor_msgs/PointField.
struct TestPointField {
  std::string name;
  std::uint32_t offset{0};
  std::uint8_t datatype{7};  ///< 7 = FLOAT32
  std::uint32_t count{1};
};

/// A sensor_msgs/PointCloud2.
struct TestPointCloud2 {
  std::uint32_t seq{0};  ///< ROS 1 only
  std::int64_t stamp_ns{0};
  std::string frame_id{"velodyne"};
  std::uint32_t height{1};
  std::uint32_t width{0};
  std::vector<TestPointField> fields;
  bool is_bigendian{false};
  std::uint32_t point_step{0};
  std::uint32_t row_step{0};
  std::vector<std::uint8_t> data;
  bool is_dense{true};
};

/// A point of an XYZIRT cloud (velodyne_pointcloud's layout).
struct TestPoint {
  float x{0}, y{0}, z{0};
  float intensity{0};
  std::uint16_t ring{0};
  float time_s{0};  ///< seconds after the header stamp
};

/// A cloud of height x width points with fields x y z intensity (float32, offsets 0..12), ring
/// (uint16, 16) and time (float32, 18) in 24-byte records; `points` row-major.
TestPointCloud2 make_xyzirt_cloud(const std::vector<TestPoint>& points, std::uint32_t height,
                                  std::uint32_t width, std::int64_t stamp_ns, bool with_ring = true,
                                  bool with_time = true);

/// Serializes a VelodyneScan (CDR: little endian, with the encapsulation header).
std::vector<std::uint8_t> serialize_velodyne_scan(const TestVelodyneScan& scan,
                                                  RosEncoding encoding);
/// Serializes a PointCloud2 (CDR: little endian, with the encapsulation header).
std::vector<std::uint8_t> serialize_pointcloud2(const TestPointCloud2& cloud, RosEncoding encoding);
/// Serializes an ouster_sensor_msgs/PacketMsg (ROS 1: ouster_ros/PacketMsg): `uint8[] buf`.
std::vector<std::uint8_t> serialize_ouster_packet(const std::vector<std::uint8_t>& buf,
                                                  RosEncoding encoding);
/// Serializes a std_msgs/String.
std::vector<std::uint8_t> serialize_string(const std::string& text, RosEncoding encoding);

/// A topic of a test bag.
struct TestBagTopic {
  std::string name;
  std::string type;  ///< ROS 1: pkg/Type, ROS 2: pkg/msg/Type
};

/// A message of a test bag.
struct TestBagMessage {
  std::size_t topic{0};  ///< index into the topics
  std::int64_t stamp_ns{0};
  std::vector<std::uint8_t> data;
};

/// Packs encoded packets into VelodyneScan messages of `packets_per_message` consecutive packets
/// (75: about one VLP-16 revolution, like the ROS driver's) on topic index `topic`; each message's
/// header stamp is its first packet's receive time, its record stamp its last one's, its ROS 1
/// seq its position.
std::vector<TestBagMessage> velodyne_scan_messages(
    const std::vector<EncodedVelodynePacket>& packets, std::size_t topic, RosEncoding encoding,
    std::size_t packets_per_message = 75);

/// How write_rosbag1 lays out the bag.
struct Rosbag1WriteOptions {
  std::string compression{"none"};  ///< none | bz2 | lz4
  std::size_t chunk_bytes{4096};    ///< a chunk is closed once its records exceed this
  bool indexed{true};  ///< false: no index (index_pos 0), like an interrupted recording
};

/// Writes a ROS 1 bag (format 2.0).
void write_rosbag1(const std::filesystem::path& path, const std::vector<TestBagTopic>& topics,
                   const std::vector<TestBagMessage>& messages,
                   const Rosbag1WriteOptions& options = {});

/// Writes a rosbag2 folder: `folder`/`folder name`_0.db3 and, when `metadata`, metadata.yaml.
void write_rosbag2(const std::filesystem::path& folder, const std::vector<TestBagTopic>& topics,
                   const std::vector<TestBagMessage>& messages, bool metadata = true);

}  // namespace ringtrack::test
