#pragma once
/// Writes MCAP files (mcap.dev/spec): messages in compressed chunks, each followed by its message
/// indexes; a summary with schemas, channels, statistics, chunk and metadata indexes and summary
/// offsets; CRCs of every chunk, the data section and the summary. See docs/formats.md, "MCAP".

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace ringtrack::io {

/// How chunk records are compressed.
enum class McapCompression : std::uint8_t {
  kNone,  ///< stored as is
  kLz4,   ///< LZ4 frame format ("lz4")
  kZstd,  ///< Zstandard frame ("zstd")
};

/// Parses none | lz4 | zstd; throws core::ConfigError naming the choices.
McapCompression parse_mcap_compression(const std::string& name);
/// The name the specification uses in Chunk records: "", "lz4" or "zstd".
const char* mcap_compression_name(McapCompression compression);

/// A Map<string, string> of the specification, in the order given.
using McapStringMap = std::vector<std::pair<std::string, std::string>>;

/// Options of an McapWriter.
struct McapWriterOptions {
  std::string profile;                                  ///< Header profile ("" or e.g. "ros2")
  std::string library{"ringtrack"};                     ///< Header library: who wrote the file
  McapCompression compression{McapCompression::kZstd};  ///< of every chunk
  std::size_t chunk_bytes{std::size_t{1} << 20};        ///< uncompressed bytes that close a chunk
  int zstd_level{1};  ///< Zstandard level (1 is fast; higher levels rarely pay for point clouds)
  /// Compress, checksum and write chunks on a worker thread, so that the caller pays only for
  /// copying its messages (see docs/visualisation.md, "Cost").
  bool background{true};
};

/// Counts of what was written.
struct McapWriterStats {
  std::uint64_t messages{0};            ///< Message records
  std::uint32_t chunks{0};              ///< Chunk records
  std::uint32_t metadata{0};            ///< Metadata records
  std::uint64_t uncompressed_bytes{0};  ///< records inside chunks
  std::uint64_t file_bytes{0};          ///< the whole file (after close)
};

/// Writes one MCAP file. Schemas and channels go into the chunk being filled when they are added
/// (and into the summary at close), so a reader that scans linearly meets them before their
/// first message. Every failure throws core::Error naming the file; a writer destroyed without
/// close() deletes its file, so a half-written MCAP is never left looking complete.
class McapWriter {
 public:
  /// Creates the file and writes the magic and the Header.
  explicit McapWriter(std::filesystem::path path, McapWriterOptions options = {});
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Adds a schema (ids from 1); `data` as its encoding defines (e.g. a FileDescriptorSet).
  std::uint16_t add_schema(std::string_view name, std::string_view encoding,
                           std::span<const std::uint8_t> data);
  /// Adds a channel on a schema (0 = none); ids from 0.
  std::uint16_t add_channel(std::uint16_t schema_id, std::string_view topic,
                            std::string_view message_encoding, const McapStringMap& metadata = {});
  /// Appends a message; its sequence number is the channel's count so far. Log times should not
  /// decrease (chunk and statistics time ranges take the minimum and maximum either way).
  void write_message(std::uint16_t channel_id, std::uint64_t log_time_ns,
                     std::uint64_t publish_time_ns, std::span<const std::uint8_t> data);
  /// Writes a Metadata record (outside chunks, as the specification requires).
  void write_metadata(std::string_view name, const McapStringMap& entries);
  /// Writes the last chunk, the Data End, the summary and the Footer, and closes the file; the
  /// file is complete only when this returns.
  void close();

  /// Counts so far (file_bytes after close).
  [[nodiscard]] const McapWriterStats& stats() const;
  /// The file's path.
  [[nodiscard]] const std::filesystem::path& path() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace ringtrack::io
