#pragma once
/// Reads MCAP files (mcap.dev/spec): messages in file order from chunked (none, lz4, zstd) or
/// unchunked files, with or without a summary; a file cut off (no footer) yields every complete
/// record before the cut and a warning. Every chunk CRC, the data section CRC and the summary CRC
/// are checked. See docs/formats.md, "MCAP".

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/io/mcap_writer.hpp"

namespace ringtrack::io {

/// A Schema record.
struct McapSchema {
  std::uint16_t id{0};             ///< from 1
  std::string name;                ///< e.g. velodyne_msgs/msg/VelodyneScan
  std::string encoding;            ///< e.g. ros2msg, protobuf
  std::vector<std::uint8_t> data;  ///< the schema text or descriptor
};

/// A Channel record.
struct McapChannel {
  std::uint16_t id{0};           ///< channel id
  std::uint16_t schema_id{0};    ///< 0: no schema
  std::string topic;             ///< e.g. /velodyne_packets
  std::string message_encoding;  ///< e.g. cdr
  McapStringMap metadata;        ///< e.g. offered_qos_profiles
};

/// One Message record.
struct McapMessage {
  std::uint16_t channel_id{0};         ///< its channel
  std::uint32_t sequence{0};           ///< the writer's counter
  std::uint64_t log_time_ns{0};        ///< when it was recorded
  std::uint64_t publish_time_ns{0};    ///< when it was published
  std::span<const std::uint8_t> data;  ///< payload; valid until the reader's next call
  std::uint64_t offset{0};             ///< file offset of the record, or of the chunk holding it
  bool in_chunk{false};                ///< read from a chunk
  std::uint64_t offset_in_chunk{0};    ///< in_chunk: the record's offset in the chunk's records
};

/// A Chunk Index record of the summary: where a chunk and its Message Index records are.
struct McapChunkIndex {
  std::uint64_t message_start_time_ns{0};  ///< earliest log time in the chunk
  std::uint64_t message_end_time_ns{0};    ///< latest log time in the chunk
  std::uint64_t chunk_offset{0};           ///< file offset of the Chunk record
  std::uint64_t chunk_length{0};           ///< bytes of the Chunk record (opcode and length too)
  /// Per channel: the file offset of its Message Index record.
  std::vector<std::pair<std::uint16_t, std::uint64_t>> message_index_offsets;
  std::uint64_t message_index_length{0};  ///< bytes of all the chunk's Message Index records
  std::string compression;                ///< "", "lz4" or "zstd"
  std::uint64_t compressed_size{0};       ///< bytes of the chunk's records as stored
  std::uint64_t uncompressed_size{0};     ///< bytes of the chunk's records uncompressed
};

/// One Message Index entry: a message's log time and its record's offset in the chunk's records.
struct McapIndexEntry {
  std::uint64_t log_time_ns{0};  ///< the message's log time
  std::uint64_t offset{0};       ///< offset in the uncompressed records of the chunk
};

/// Options of an McapReader.
struct McapReaderOptions {
  /// Largest uncompressed chunk accepted (a corrupt size must not allocate gigabytes).
  std::uint64_t max_chunk_bytes{std::uint64_t{512} << 20};
  /// Read channels and message counts from the summary when the file has a valid one (else
  /// one linear pass over the file finds them).
  bool use_summary{true};
};

/// Reads one MCAP file from disk or memory. Errors are core::InputError naming the file, the
/// byte offset and what was expected.
class McapReader {
 public:
  /// Opens a file: checks the magic, reads the summary when there is one, or else scans the file
  /// once for its channels and message counts.
  explicit McapReader(const std::filesystem::path& path, McapReaderOptions options = {});
  /// Reads the file at path, naming it `name` in messages (an expanded temporary copy named
  /// after the file the user has).
  McapReader(const std::filesystem::path& path, std::string name, McapReaderOptions options = {});
  /// The same over bytes in memory (kept by the caller while the reader lives); `name` is used in
  /// messages.
  McapReader(std::span<const std::uint8_t> bytes, std::string name, McapReaderOptions options = {});
  ~McapReader();
  McapReader(const McapReader&) = delete;
  McapReader& operator=(const McapReader&) = delete;

  /// The Header's profile (e.g. "ros2").
  [[nodiscard]] const std::string& profile() const;
  /// Every channel, by id order.
  [[nodiscard]] const std::vector<McapChannel>& channels() const;
  /// A schema by id, nullptr when unknown or 0.
  [[nodiscard]] const McapSchema* schema(std::uint16_t id) const;
  /// Messages of a channel in the file.
  [[nodiscard]] std::uint64_t message_count(std::uint16_t channel_id) const;
  /// True when channels and counts came from a valid summary (with a Statistics record).
  [[nodiscard]] bool used_summary() const;
  /// The summary's Chunk Index records in file order (empty when the summary was not used).
  [[nodiscard]] const std::vector<McapChunkIndex>& chunk_indexes() const;
  /// The Message Index records a Chunk Index points to: per channel, its entries. Errors
  /// (core::InputError) name the offset of a record that is not the Message Index expected.
  std::vector<std::pair<std::uint16_t, std::vector<McapIndexEntry>>> message_indexes(
      const McapChunkIndex& chunk);
  /// The next message in file order; false at the end (or where a cut-off file ends).
  bool next(McapMessage& out);
  /// Starts reading from the first message again.
  void rewind();
  /// Why the file ended early ("" when it did not), one line naming the offset.
  [[nodiscard]] const std::string& warning() const;
  /// The name given (the path for files).
  [[nodiscard]] const std::string& name() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// True when the file starts with the MCAP magic.
bool is_mcap_file(const std::filesystem::path& path);

}  // namespace ringtrack::io
