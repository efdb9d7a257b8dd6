#pragma once
/// Velodyne packets from ROS 2 bags (rosbag2, sqlite3 storage, CDR), read without ROS 2.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"

struct sqlite3;
struct sqlite3_stmt;

namespace ringtrack::io {

/// One topic of a bag.
struct Rosbag2Topic {
  std::int64_t id{0};
  std::string name;
  std::string type;                  ///< e.g. velodyne_msgs/msg/VelodyneScan
  std::string serialization_format;  ///< cdr
};

/// One packet of a velodyne_msgs/msg/VelodyneScan message.
struct VelodyneScanPacket {
  std::int64_t stamp_ns{0};            ///< the packet's header time
  std::span<const std::uint8_t> data;  ///< its 1206 bytes (points into the message)
};

/// Parses a CDR-serialized velodyne_msgs/msg/VelodyneScan (with its 4-byte encapsulation
/// header); throws core::InputError naming `where` on malformed data.
std::vector<VelodyneScanPacket> parse_velodyne_scan_cdr(std::span<const std::uint8_t> message,
                                                        const std::string& where);

/// Counters of a bag source.
struct Rosbag2Stats {
  std::uint64_t messages{0};        ///< messages of the chosen topic read
  std::uint64_t packets{0};         ///< packets in them
  std::uint64_t other_messages{0};  ///< messages of other topics, ignored
};

/// Reads a rosbag2 folder (metadata.yaml plus .db3 files) or a single .db3 file and yields one
/// OrganizedScan per revolution from its velodyne_msgs/msg/VelodyneScan topic. Compressed bags,
/// other storage plugins and sensor_msgs/msg/PointCloud2 topics are rejected with an error.
class VelodyneRosbag2Source {
 public:
  /// Opens the bag and chooses the topic: `topic` if given, else the only VelodyneScan topic.
  /// Throws core::InputError (bag) or core::ConfigError (topic/options).
  VelodyneRosbag2Source(const std::filesystem::path& path, const std::string& topic = {},
                        VelodyneDecoderOptions decoder_options = {});
  ~VelodyneRosbag2Source();
  VelodyneRosbag2Source(const VelodyneRosbag2Source&) = delete;
  VelodyneRosbag2Source& operator=(const VelodyneRosbag2Source&) = delete;

  /// The next scan, or nullopt at the end; throws core::InputError on corrupt messages.
  std::optional<core::OrganizedScan> next();
  /// The next raw packet of the chosen topic (for tools and tests), bypassing the decoder.
  std::optional<VelodyneScanPacket> next_packet();
  /// Every topic of the bag (of its first file).
  [[nodiscard]] const std::vector<Rosbag2Topic>& topics() const { return topics_; }
  /// The chosen topic.
  [[nodiscard]] const Rosbag2Topic& topic() const { return topic_; }
  /// The decoder (model and counters).
  [[nodiscard]] const VelodyneDecoder& decoder() const { return decoder_; }
  /// Counters.
  [[nodiscard]] const Rosbag2Stats& stats() const { return stats_; }

 private:
  bool open_next_file();
  bool load_message();

  struct DbCloser {
    void operator()(sqlite3* db) const;
  };
  struct StmtCloser {
    void operator()(sqlite3_stmt* stmt) const;
  };

  std::vector<std::filesystem::path> files_;
  std::size_t file_index_{0};
  std::unique_ptr<sqlite3, DbCloser> db_;
  std::unique_ptr<sqlite3_stmt, StmtCloser> stmt_;
  std::string requested_topic_;
  std::vector<Rosbag2Topic> topics_;
  Rosbag2Topic topic_;
  std::vector<std::uint8_t> message_;
  std::vector<VelodyneScanPacket> packets_;
  std::size_t packet_index_{0};
  std::string where_;
  VelodyneDecoder decoder_;
  Rosbag2Stats stats_;
  bool finished_{false};
};

}  // namespace ringtrack::io
