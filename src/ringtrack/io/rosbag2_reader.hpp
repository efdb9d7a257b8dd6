#pragma once
/// ROS 2 bags (rosbag2 with sqlite3 .db3 storage) read with libsqlite3 alone, without ROS 2.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "ringtrack/io/rosbag_reader.hpp"

namespace ringtrack::io {

/// Reads a rosbag2 folder (metadata.yaml and the .db3 files it lists, or without metadata.yaml
/// every .db3 file of the folder by name) or a single .db3 file. Messages come file by file,
/// each file in (timestamp, id) order. Bags rosbag2 compressed with zstd are read: per file (each
/// .db3.zstd expanded to a temporary folder, removed with the reader) and per message. Other
/// storage plugins and compression formats are rejected.
class Rosbag2Reader final : public RosbagReader {
 public:
  /// Opens the bag and reads its topics; throws core::InputError naming the file and what was
  /// expected (missing or malformed metadata, missing files, not a rosbag2 database).
  explicit Rosbag2Reader(const std::filesystem::path& path);
  ~Rosbag2Reader() override;
  Rosbag2Reader(const Rosbag2Reader&) = delete;
  Rosbag2Reader& operator=(const Rosbag2Reader&) = delete;

  [[nodiscard]] const std::vector<RosbagTopicInfo>& topics() const override;
  [[nodiscard]] RosSerialization serialization() const override { return RosSerialization::kCdr; }
  void select_topic(const std::string& name) override;
  bool next(RosbagMessage& out) override;
  [[nodiscard]] std::uint64_t other_messages() const override;
  [[nodiscard]] const std::filesystem::path& path() const override;
  [[nodiscard]] const std::filesystem::path& current_file() const override;
  /// The .db3 files in reading order.
  [[nodiscard]] const std::vector<std::filesystem::path>& files() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ringtrack::io
