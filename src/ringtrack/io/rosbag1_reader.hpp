#pragma once
/// ROS 1 bags (format 2.0) read without ROS: records, connections, chunks (uncompressed, bz2,
/// lz4 frames). Written from the format's public description; see docs/inputs.md.

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/io/rosbag_reader.hpp"

namespace ringtrack::io {

/// Record kinds of a ROS 1 bag (the `op` header field).
enum class Rosbag1Op : std::uint8_t {
  kMessageData = 0x02,
  kBagHeader = 0x03,
  kIndexData = 0x04,
  kChunk = 0x05,
  kChunkInfo = 0x06,
  kConnection = 0x07,
};

/// One connection (a publisher's topic and type) of a ROS 1 bag.
struct Rosbag1Connection {
  std::uint32_t id{0};
  std::string topic;
  std::string type;    ///< e.g. velodyne_msgs/VelodyneScan
  std::string md5sum;  ///< of the message definition
  std::uint64_t messages{0};
};

/// Counters of a ROS 1 bag reader.
struct Rosbag1Stats {
  std::uint64_t chunks{0};              ///< chunks read
  std::uint64_t uncompressed_bytes{0};  ///< bytes of chunk data after decompression
  std::uint64_t unknown_records{0};     ///< records of unknown kinds (index, chunks), skipped
  std::uint64_t truncated_at{0};  ///< unindexed bags: offset of a last record cut off by the end
                                  ///< of the file (an interrupted recording), else 0
};

/// Reads a ROS 1 bag file. The connections come from the bag's index (at index_pos); a bag
/// without an index (recording interrupted) is scanned once to find them, and its data ends
/// before a last record cut off by the end of the file (counted in stats().truncated_at). Messages
/// come in file order, which is recording order. An indexed file that ends inside a record is an
/// error naming the offset.
class Rosbag1Reader final : public RosbagReader {
 public:
  /// Opens the bag and reads its connections; throws core::InputError naming the file, the
  /// offset and what was expected.
  explicit Rosbag1Reader(const std::filesystem::path& path);
  ~Rosbag1Reader() override;
  Rosbag1Reader(const Rosbag1Reader&) = delete;
  Rosbag1Reader& operator=(const Rosbag1Reader&) = delete;

  [[nodiscard]] const std::vector<RosbagTopicInfo>& topics() const override { return topics_; }
  [[nodiscard]] RosSerialization serialization() const override { return RosSerialization::kRos1; }
  void select_topic(const std::string& name) override;
  bool next(RosbagMessage& out) override;
  [[nodiscard]] std::uint64_t other_messages() const override { return other_; }
  [[nodiscard]] const std::filesystem::path& path() const override { return path_; }
  /// The connections by id.
  [[nodiscard]] const std::map<std::uint32_t, Rosbag1Connection>& connections() const {
    return connections_;
  }
  /// True when the bag had an index (false: it was scanned to find its connections).
  [[nodiscard]] bool indexed() const { return indexed_; }
  /// Counters.
  [[nodiscard]] const Rosbag1Stats& stats() const { return stats_; }

 private:
  struct FileCloser {
    void operator()(std::FILE* f) const;
  };
  struct Record;  // a parsed record header and where its data lies

  bool read_record(Record& record, bool tail_ok = false);
  void read_bytes(std::uint64_t offset, std::size_t n, std::vector<std::uint8_t>& out);
  void load_chunk(const Record& record);
  void add_connection(const Record& record, std::span<const std::uint8_t> data);
  void scan_for_connections();
  // Checks the '#ROSBAG V2.0' line (another version is named in the error).
  void check_magic();
  // Reads the index section at index_pos_ (connections, chunk infos) and checks its counts
  // against the bag header's.
  void read_index(std::uint32_t conn_count, std::uint32_t chunk_count);
  // One topic per connection name, with its type and message count.
  void collect_topics();
  bool next_in_chunk(RosbagMessage& out);

  std::filesystem::path path_;
  std::unique_ptr<std::FILE, FileCloser> file_;
  std::uint64_t file_size_{0};
  std::uint64_t first_record_{0};  // offset of the record after the bag header
  std::uint64_t index_pos_{0};     // start of the index section (end of the data section)
  bool indexed_{false};
  std::map<std::uint32_t, Rosbag1Connection> connections_;
  std::vector<RosbagTopicInfo> topics_;
  std::string selected_;
  bool started_{false};
  std::uint64_t offset_{0};          // next top-level record
  std::uint64_t chunk_offset_{0};    // file offset of the chunk being read (for messages)
  std::vector<std::uint8_t> raw_;    // compressed chunk data
  std::vector<std::uint8_t> chunk_;  // uncompressed chunk data
  std::size_t chunk_at_{0};          // next record inside chunk_
  bool in_chunk_{false};
  std::vector<std::uint8_t> message_;  // data of a message outside chunks
  std::uint64_t index_{0};
  std::uint64_t other_{0};
  Rosbag1Stats stats_;
};

}  // namespace ringtrack::io
