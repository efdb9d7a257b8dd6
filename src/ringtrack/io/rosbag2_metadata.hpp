#pragma once
/// What a rosbag2 bag folder's metadata.yaml says about its storage files, and the zstd
/// compression rosbag2 itself applies (`ros2 bag record --compression-mode file|message
/// --compression-format zstd`), shared by the sqlite3 and the MCAP bag readers. See
/// docs/inputs.md, "ROS 2 bags".

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace ringtrack::io {

/// How rosbag2 compressed a bag (metadata compression_mode; only the zstd format exists).
enum class Rosbag2Compression {
  kNone,     ///< storage files and messages as written
  kFile,     ///< each storage file is one zstd stream ("bag_0.db3.zstd")
  kMessage,  ///< each message's serialized data is one zstd frame
};

/// The parts of metadata.yaml the readers need.
struct Rosbag2Metadata {
  std::string storage;  ///< storage_identifier ("sqlite3" when absent, as before Humble)
  Rosbag2Compression compression{Rosbag2Compression::kNone};
  std::vector<std::filesystem::path> files;  ///< relative_file_paths, resolved, each existing
};

/// Reads folder/metadata.yaml of a bag of `storage` ("sqlite3" or "mcap"). Throws
/// core::InputError naming the file and what was expected: not YAML, no
/// rosbag2_bagfile_information map, another storage, no relative_file_paths, a listed file
/// missing, a compression format other than zstd or an unknown compression mode.
[[nodiscard]] Rosbag2Metadata read_rosbag2_metadata(const std::filesystem::path& folder,
                                                    const std::string& storage);

/// The storage_identifier of folder/metadata.yaml, or "" when the file cannot be read as
/// rosbag2 metadata (the reader that opens the bag reports why). Never throws.
[[nodiscard]] std::string rosbag2_storage(const std::filesystem::path& metadata);

/// A folder under the system's temporary directory, removed with everything in it when this is
/// destroyed: where file-compressed storage files are expanded for reading.
class TemporaryFolder {
 public:
  /// Creates a new, empty folder named after `stem`; throws core::Error when it cannot.
  explicit TemporaryFolder(const std::string& stem);
  ~TemporaryFolder();
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  /// The folder.
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

/// Expands the zstd stream of `compressed` (one or more frames) into the new file `out`. Throws
/// core::InputError naming `compressed` and the byte offset where its data went wrong, or
/// ending before its last frame did; core::Error when `out` cannot be written.
void decompress_zstd_file(const std::filesystem::path& compressed,
                          const std::filesystem::path& out);

/// Expands one zstd-compressed message into out (replaced). Throws core::InputError starting
/// with `what` (which message of which file) when the data is not one complete zstd frame.
void decompress_zstd_message(std::span<const std::uint8_t> compressed,
                             std::vector<std::uint8_t>& out, const std::string& what);

}  // namespace ringtrack::io
