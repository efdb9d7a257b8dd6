#pragma once
/// ROS 2 bags stored as MCAP (rosbag2's default storage since Iron): a .mcap file, or a bag
/// folder whose metadata.yaml names the mcap storage, read through the RosbagReader interface
/// with our own MCAP reader (mcap_reader.hpp). Messages are CDR, as in sqlite3 bags.

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "ringtrack/io/mcap_reader.hpp"
#include "ringtrack/io/rosbag_reader.hpp"

namespace ringtrack::io {

/// True for an MCAP file (by its magic) or a folder whose metadata.yaml names mcap storage (or
/// that holds .mcap files and no metadata.yaml).
bool is_mcap_bag(const std::filesystem::path& path);

/// Reads a ROS 2 MCAP bag: topics from its channels (type = the schema name, e.g.
/// velodyne_msgs/msg/VelodyneScan), messages of the selected topic in file order, file by file.
class McapBagReader final : public RosbagReader {
 public:
  /// Opens the bag; throws core::InputError naming the file and what was expected.
  explicit McapBagReader(const std::filesystem::path& path);
  ~McapBagReader() override;
  McapBagReader(const McapBagReader&) = delete;
  McapBagReader& operator=(const McapBagReader&) = delete;

  [[nodiscard]] const std::vector<RosbagTopicInfo>& topics() const override;
  [[nodiscard]] RosSerialization serialization() const override { return RosSerialization::kCdr; }
  void select_topic(const std::string& name) override;
  bool next(RosbagMessage& out) override;
  [[nodiscard]] std::uint64_t other_messages() const override;
  [[nodiscard]] const std::filesystem::path& path() const override;
  [[nodiscard]] const std::filesystem::path& current_file() const override;
  [[nodiscard]] std::string warning() const override;
  /// The .mcap files in reading order.
  [[nodiscard]] const std::vector<std::filesystem::path>& files() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ringtrack::io
