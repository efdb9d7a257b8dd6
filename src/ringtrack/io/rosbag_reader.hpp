#pragma once
/// One view of ROS bags, ROS 1 (.bag, format 2.0) and ROS 2 (rosbag2 folders, sqlite3): topics and
/// the serialized messages of one chosen topic, in recording order. See docs/inputs.md.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace ringtrack::io {

/// How a bag serializes its messages.
enum class RosSerialization : std::uint8_t {
  kRos1,  ///< ROS 1: little-endian, packed, uint32-length-prefixed strings and arrays
  kCdr,   ///< ROS 2: CDR (XCDR1) after a 4-byte encapsulation header
};

/// One topic of a bag.
struct RosbagTopicInfo {
  std::string name;           ///< e.g. /velodyne_packets
  std::string type;           ///< as the bag stores it: pkg/msg/Type (ROS 2) or pkg/Type (ROS 1)
  std::uint64_t messages{0};  ///< messages of the topic in the bag
};

/// One serialized message of the selected topic.
struct RosbagMessage {
  std::int64_t stamp_ns{0};            ///< the bag's record time (ns since the epoch)
  std::span<const std::uint8_t> data;  ///< serialized bytes; valid until the reader's next call
  std::uint64_t index{0};              ///< 1-based position among the topic's messages
};

/// Reads the messages of one topic of a bag.
class RosbagReader {
 public:
  virtual ~RosbagReader() = default;
  /// Every topic of the bag, in the bag's order.
  [[nodiscard]] virtual const std::vector<RosbagTopicInfo>& topics() const = 0;
  /// The serialization of the bag's messages.
  [[nodiscard]] virtual RosSerialization serialization() const = 0;
  /// Chooses the topic next() returns; throws core::ConfigError naming the bag's topics when
  /// it has no such topic. Call before the first next().
  virtual void select_topic(const std::string& name) = 0;
  /// The next message of the selected topic; false at the end. Throws core::InputError naming
  /// the file and offset on corrupt data.
  virtual bool next(RosbagMessage& out) = 0;
  /// Messages of other topics passed over so far.
  [[nodiscard]] virtual std::uint64_t other_messages() const = 0;
  /// The bag's path, for messages.
  [[nodiscard]] virtual const std::filesystem::path& path() const = 0;
  /// The file the last message came from (a rosbag2 .db3 file; the bag itself for ROS 1).
  [[nodiscard]] virtual const std::filesystem::path& current_file() const { return path(); }
  /// A problem the reading survived, in one line (e.g. an MCAP file cut off); "" when none.
  [[nodiscard]] virtual std::string warning() const { return {}; }
};

/// Reads the fields of one serialized message in either serialization: ROS 1 packs fields
/// without padding; CDR aligns each primitive to its size (counted from after the 4-byte
/// encapsulation header, whose second byte gives the byte order). Strings and sequences are
/// uint32-length-prefixed in both (CDR strings count a terminating NUL). Every error is a
/// core::InputError naming `where`, the byte offset and what was expected.
class RosMessageCursor {
 public:
  /// Starts at the first field (after the encapsulation header for CDR).
  RosMessageCursor(std::span<const std::uint8_t> message, RosSerialization serialization,
                   std::string where);
  /// uint8 / bool.
  std::uint8_t u8();
  /// uint32.
  std::uint32_t u32();
  /// int32.
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  /// A string (without CDR's terminating NUL).
  std::string string();
  /// `n` raw bytes (a uint8 array), pointing into the message.
  std::span<const std::uint8_t> bytes(std::size_t n);
  /// A sequence length, checked against the bytes left (each element needs at least
  /// `min_element_bytes`).
  std::uint32_t sequence_length(std::size_t min_element_bytes, const char* what);
  /// ROS time (ROS 1 time: uint32 s, uint32 ns; ROS 2 builtin_interfaces/Time: int32 s, uint32
  /// ns) as ns since the epoch.
  std::int64_t time_ns();
  /// std_msgs/Header (ROS 1: seq, stamp, frame_id; ROS 2: stamp, frame_id); returns the stamp.
  std::int64_t header_stamp_ns(std::string* frame_id = nullptr);
  /// Bytes not read yet.
  [[nodiscard]] std::size_t remaining() const { return body_.size() - at_; }
  /// Throws core::InputError: "<where>: <what> (at byte N)".
  [[noreturn]] void fail(const std::string& what) const;

 private:
  void align(std::size_t n);
  void need(std::size_t n, const char* what) const;

  std::span<const std::uint8_t> body_;
  RosSerialization serialization_;
  std::string where_;
  std::size_t at_{0};
  std::size_t origin_{0};  // bytes before body_ in the message (the CDR header)
  bool little_{true};
};

/// A type name without the ROS 2 "/msg/" part ("pkg/msg/Type" and "pkg/Type" give "pkg/Type").
std::string normalize_ros_type(std::string_view type);

/// True for a ROS 1 bag file (by its "#ROSBAG V" magic, whatever the extension).
bool is_rosbag1_file(const std::filesystem::path& path);
/// True for a rosbag2 folder (metadata.yaml or .db3 or .mcap files inside), a .db3 file or an
/// MCAP file.
bool is_rosbag2_path(const std::filesystem::path& path);

/// Opens a ROS 1 bag file, a rosbag2 folder (sqlite3 or mcap storage), a .db3 file or an MCAP
/// file, by its contents; throws
/// core::InputError when it is neither.
std::unique_ptr<RosbagReader> open_rosbag(const std::filesystem::path& path);

}  // namespace ringtrack::io
