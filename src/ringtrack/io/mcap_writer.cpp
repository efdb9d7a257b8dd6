#include "ringtrack/io/mcap_writer.hpp"

#include <lz4frame.h>
#include <zstd.h>

#include <algorithm>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/mcap_format.hpp"
#include "ringtrack/io/output_file.hpp"

namespace ringtrack::io {

McapCompression parse_mcap_compression(const std::string& name) {
  if (name == "none" || name.empty()) return McapCompression::kNone;
  if (name == "lz4") return McapCompression::kLz4;
  if (name == "zstd") return McapCompression::kZstd;
  throw core::ConfigError("MCAP compression '" + name + "': expected none, lz4 or zstd");
}

const char* mcap_compression_name(McapCompression compression) {
  switch (compression) {
    case McapCompression::kNone:
      return "";
    case McapCompression::kLz4:
      return "lz4";
    case McapCompression::kZstd:
      return "zstd";
  }
  return "";
}

namespace {

using mcap::Buffer;
using mcap::Op;

// A chunk ready to be compressed and written: its records and the message index entries.
struct ChunkJob {
  Buffer records;
  std::vector<std::pair<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>>>
      index;  // per channel in order of first message: (log time, offset in records)
  std::uint64_t start_ns{0};
  std::uint64_t end_ns{0};
  bool raw{false};            // not a chunk: `records` is one record to write as is (Metadata)
  std::string metadata_name;  // raw Metadata records: for the Metadata Index
};

struct ChunkIndexEntry {
  std::uint64_t start_ns, end_ns, offset, length;
  std::vector<std::pair<std::uint16_t, std::uint64_t>> index_offsets;
  std::uint64_t index_length, compressed_size, uncompressed_size;
};

struct MetadataIndexEntry {
  std::uint64_t offset, length;
  std::string name;
};

}  // namespace

struct McapWriter::Impl {
  McapWriterOptions options;
  OutputFile file;
  McapWriterStats stats;

  // Caller side: the chunk being filled.
  ChunkJob current;
  std::vector<int> current_slot;  // channel id -> index in current.index, -1 when absent
  bool current_has_messages{false};
  Buffer schema_records;   // serialized, for the summary
  Buffer channel_records;  // serialized, for the summary
  std::uint16_t schemas{0};
  std::vector<std::uint32_t> sequence;          // per channel
  std::vector<std::uint64_t> channel_messages;  // per channel
  std::uint64_t first_ns{std::numeric_limits<std::uint64_t>::max()};
  std::uint64_t last_ns{0};

  // Writer side (the worker thread when background): the file position and what it wrote.
  std::uint64_t offset{0};
  std::uint32_t data_crc{0};
  std::vector<ChunkIndexEntry> chunk_index;
  std::vector<MetadataIndexEntry> metadata_index;
  ByteBuffer compressed;
  ZSTD_CCtx* zstd{nullptr};

  // Background writing.
  std::thread worker;
  std::mutex mutex;
  std::condition_variable changed;
  std::deque<ChunkJob> queue;
  std::vector<ChunkJob> spare;  // emptied jobs whose buffers are reused
  bool stopping{false};
  bool busy{false};  // the worker is writing a job it took from the queue
  std::exception_ptr error;
  bool closed{false};

  Impl(std::filesystem::path path, McapWriterOptions o)
      : options(std::move(o)), file(std::move(path)) {}

  ~Impl() {
    stop_worker();
    if (zstd != nullptr) ZSTD_freeCCtx(zstd);
  }

  void emit(std::span<const std::uint8_t> bytes) {
    file.write(bytes.data(), bytes.size());
    data_crc = mcap::crc32(bytes, data_crc);
    offset += bytes.size();
  }

  [[noreturn]] void fail(const std::string& what) const {
    throw core::Error(file.path().string() + ": " + what);
  }

  std::span<const std::uint8_t> compress(std::span<const std::uint8_t> in) {
    switch (options.compression) {
      case McapCompression::kNone:
        return in;
      case McapCompression::kLz4: {
        LZ4F_preferences_t prefs{};
        prefs.frameInfo.blockSizeID = LZ4F_max4MB;
        prefs.frameInfo.contentSize = in.size();
        const std::size_t bound = LZ4F_compressFrameBound(in.size(), &prefs);
        compressed.clear();
        compressed.grow(bound);
        const std::size_t n =
            LZ4F_compressFrame(compressed.data(), bound, in.data(), in.size(), &prefs);
        if (LZ4F_isError(n) != 0U) fail(std::string("lz4 compression: ") + LZ4F_getErrorName(n));
        return {compressed.data(), n};
      }
      case McapCompression::kZstd: {
        if (zstd == nullptr) zstd = ZSTD_createCCtx();
        const std::size_t bound = ZSTD_compressBound(in.size());
        compressed.clear();
        compressed.grow(bound);
        const std::size_t n = ZSTD_compressCCtx(zstd, compressed.data(), bound, in.data(),
                                                in.size(), options.zstd_level);
        if (ZSTD_isError(n) != 0U) fail(std::string("zstd compression: ") + ZSTD_getErrorName(n));
        return {compressed.data(), n};
      }
    }
    return in;
  }

  // Writes a chunk and its message indexes, and remembers its Chunk Index.
  void write_chunk(const ChunkJob& job) {
    const auto records = job.records.bytes();
    const std::uint32_t crc = mcap::crc32(records);
    const auto data = compress(records);
    const std::string_view compression = mcap_compression_name(options.compression);
    Buffer head;
    head.u8(static_cast<std::uint8_t>(Op::kChunk));
    head.u64(8 + 8 + 8 + 4 + 4 + compression.size() + 8 + data.size());
    head.u64(job.start_ns);
    head.u64(job.end_ns);
    head.u64(records.size());
    head.u32(crc);
    head.string(compression);
    head.u64(data.size());
    ChunkIndexEntry entry{job.start_ns, job.end_ns, offset,      head.size() + data.size(),
                          {},           0,          data.size(), records.size()};
    emit(head.bytes());
    emit(data);
    Buffer indexes;
    for (const auto& [channel, entries] : job.index) {
      entry.index_offsets.emplace_back(channel, offset + indexes.size());
      const std::size_t at = indexes.begin_record(Op::kMessageIndex);
      indexes.u16(channel);
      const std::size_t group = indexes.begin_group();
      for (const auto& [time, position] : entries) {
        indexes.u64(time);
        indexes.u64(position);
      }
      indexes.end_group(group);
      indexes.end_record(at);
    }
    entry.index_length = indexes.size();
    emit(indexes.bytes());
    chunk_index.push_back(std::move(entry));
  }

  void write_job(const ChunkJob& job) {
    if (!job.raw) {
      write_chunk(job);
      return;
    }
    metadata_index.push_back({offset, job.records.size(), job.metadata_name});
    emit(job.records.bytes());
  }

  void run_worker() {
    std::unique_lock lock(mutex);
    for (;;) {
      changed.wait(lock, [&] { return stopping || !queue.empty(); });
      if (queue.empty()) return;
      ChunkJob job = std::move(queue.front());
      queue.pop_front();
      busy = true;
      lock.unlock();
      try {
        if (!error) write_job(job);
      } catch (...) {
        lock.lock();
        error = std::current_exception();
        lock.unlock();
      }
      lock.lock();
      // Reused as a chunk: only the buffers' capacity is kept.
      job.records.clear();
      job.index.clear();
      job.raw = false;
      job.metadata_name.clear();
      job.start_ns = job.end_ns = 0;
      spare.push_back(std::move(job));
      busy = false;
      changed.notify_all();
    }
  }

  void stop_worker() {
    if (!worker.joinable()) return;
    {
      std::lock_guard lock(mutex);
      stopping = true;
    }
    changed.notify_all();
    worker.join();
  }

  void rethrow_worker_error() {
    std::lock_guard lock(mutex);
    if (error) std::rethrow_exception(error);
  }

  // Hands a job to the worker (waiting while two are queued: memory stays bounded when the disk
  // is slower than the pipeline) or writes it here.
  void submit(ChunkJob job) {
    if (!options.background) {
      write_job(job);
      return;
    }
    std::unique_lock lock(mutex);
    if (error) std::rethrow_exception(error);
    if (!worker.joinable()) worker = std::thread([this] { run_worker(); });
    changed.wait(lock, [&] { return queue.size() < 2 || error; });
    if (error) std::rethrow_exception(error);
    queue.push_back(std::move(job));
    changed.notify_all();
  }

  ChunkJob fresh_job() {
    std::lock_guard lock(mutex);
    if (spare.empty()) return {};
    ChunkJob job = std::move(spare.back());
    spare.pop_back();
    return job;
  }

  // The summary's Statistics record: counts, time range, messages per channel.
  void write_statistics(Buffer& s) const {
    const std::size_t r = s.begin_record(Op::kStatistics);
    s.u64(stats.messages);
    s.u16(schemas);
    s.u32(static_cast<std::uint32_t>(sequence.size()));
    s.u32(0);  // attachments
    s.u32(stats.metadata);
    s.u32(static_cast<std::uint32_t>(chunk_index.size()));
    s.u64(stats.messages > 0 ? first_ns : 0);
    s.u64(stats.messages > 0 ? last_ns : 0);
    const std::size_t counts = s.begin_group();
    for (std::size_t c = 0; c < channel_messages.size(); ++c) {
      s.u16(static_cast<std::uint16_t>(c));
      s.u64(channel_messages[c]);
    }
    s.end_group(counts);
    s.end_record(r);
  }

  // One Chunk Index record per chunk written: where it is and where its message indexes are.
  void write_chunk_indexes(Buffer& s) const {
    for (const auto& e : chunk_index) {
      const std::size_t r = s.begin_record(Op::kChunkIndex);
      s.u64(e.start_ns);
      s.u64(e.end_ns);
      s.u64(e.offset);
      s.u64(e.length);
      const std::size_t map = s.begin_group();
      for (const auto& [channel, off] : e.index_offsets) {
        s.u16(channel);
        s.u64(off);
      }
      s.end_group(map);
      s.u64(e.index_length);
      s.string(mcap_compression_name(options.compression));
      s.u64(e.compressed_size);
      s.u64(e.uncompressed_size);
      s.end_record(r);
    }
  }

  // One Metadata Index record per Metadata record.
  void write_metadata_indexes(Buffer& s) const {
    for (const auto& e : metadata_index) {
      const std::size_t r = s.begin_record(Op::kMetadataIndex);
      s.u64(e.offset);
      s.u64(e.length);
      s.string(e.name);
      s.end_record(r);
    }
  }

  void flush_chunk() {
    if (current.records.size() == 0) return;
    ++stats.chunks;
    ChunkJob job = std::move(current);
    current = fresh_job();
    current_has_messages = false;
    std::fill(current_slot.begin(), current_slot.end(), -1);
    submit(std::move(job));
  }

  void append_to_chunk(std::span<const std::uint8_t> record) {
    current.records.raw(record);
    stats.uncompressed_bytes += record.size();
  }
};

McapWriter::McapWriter(std::filesystem::path path, McapWriterOptions options)
    : impl_(std::make_unique<Impl>(std::move(path), std::move(options))) {
  Impl& m = *impl_;
  if (m.options.chunk_bytes == 0) m.fail("MCAP chunk size must be positive");
  Buffer head;
  head.raw(mcap::kMagic);
  const std::size_t at = head.begin_record(Op::kHeader);
  head.string(m.options.profile);
  head.string(m.options.library);
  head.end_record(at);
  m.emit(head.bytes());
}

McapWriter::~McapWriter() {
  if (!impl_->closed) {
    impl_->stop_worker();
    impl_->file.discard();
  }
}

std::uint16_t McapWriter::add_schema(std::string_view name, std::string_view encoding,
                                     std::span<const std::uint8_t> data) {
  Impl& m = *impl_;
  if (m.schemas == std::numeric_limits<std::uint16_t>::max()) m.fail("too many MCAP schemas");
  const auto id = static_cast<std::uint16_t>(++m.schemas);
  Buffer record;
  const std::size_t at = record.begin_record(Op::kSchema);
  record.u16(id);
  record.string(name);
  record.string(encoding);
  record.u32(static_cast<std::uint32_t>(data.size()));
  record.raw(data);
  record.end_record(at);
  m.append_to_chunk(record.bytes());
  m.schema_records.raw(record.bytes());
  return id;
}

std::uint16_t McapWriter::add_channel(std::uint16_t schema_id, std::string_view topic,
                                      std::string_view message_encoding,
                                      const McapStringMap& metadata) {
  Impl& m = *impl_;
  if (schema_id > m.schemas) m.fail("channel " + std::string(topic) + ": unknown schema id");
  if (m.sequence.size() > std::numeric_limits<std::uint16_t>::max()) {
    m.fail("too many MCAP channels");
  }
  const auto id = static_cast<std::uint16_t>(m.sequence.size());
  Buffer record;
  const std::size_t at = record.begin_record(Op::kChannel);
  record.u16(id);
  record.u16(schema_id);
  record.string(topic);
  record.string(message_encoding);
  const std::size_t map = record.begin_group();
  for (const auto& [key, value] : metadata) {
    record.string(key);
    record.string(value);
  }
  record.end_group(map);
  record.end_record(at);
  m.append_to_chunk(record.bytes());
  m.channel_records.raw(record.bytes());
  m.sequence.push_back(0);
  m.channel_messages.push_back(0);
  m.current_slot.push_back(-1);
  return id;
}

void McapWriter::write_message(std::uint16_t channel_id, std::uint64_t log_time_ns,
                               std::uint64_t publish_time_ns, std::span<const std::uint8_t> data) {
  const auto out = add_message(channel_id, log_time_ns, publish_time_ns, data.size());
  if (!data.empty()) std::memcpy(out.data(), data.data(), data.size());
}

std::span<std::uint8_t> McapWriter::add_message(std::uint16_t channel_id, std::uint64_t log_time_ns,
                                                std::uint64_t publish_time_ns, std::size_t size) {
  Impl& m = *impl_;
  if (channel_id >= m.sequence.size()) {
    m.fail("message on unknown channel " + std::to_string(channel_id));
  }
  // A full chunk is closed here, before the next message, rather than after the last one: the
  // caller is still filling that message's payload inside the chunk when add_message returns.
  if (m.current.records.size() >= m.options.chunk_bytes) m.flush_chunk();
  ChunkJob& c = m.current;
  const std::uint64_t position = c.records.size();
  c.records.u8(static_cast<std::uint8_t>(Op::kMessage));
  c.records.u64(2 + 4 + 8 + 8 + size);
  c.records.u16(channel_id);
  c.records.u32(m.sequence[channel_id]++);
  c.records.u64(log_time_ns);
  c.records.u64(publish_time_ns);
  std::uint8_t* payload = c.records.grow(size);
  m.stats.uncompressed_bytes += c.records.size() - position;
  int& slot = m.current_slot[channel_id];
  if (slot < 0) {
    slot = static_cast<int>(c.index.size());
    c.index.emplace_back(channel_id, std::vector<std::pair<std::uint64_t, std::uint64_t>>{});
  }
  c.index[static_cast<std::size_t>(slot)].second.emplace_back(log_time_ns, position);
  if (!m.current_has_messages) {
    c.start_ns = c.end_ns = log_time_ns;
    m.current_has_messages = true;
  }
  c.start_ns = std::min(c.start_ns, log_time_ns);
  c.end_ns = std::max(c.end_ns, log_time_ns);
  m.first_ns = std::min(m.first_ns, log_time_ns);
  m.last_ns = std::max(m.last_ns, log_time_ns);
  ++m.channel_messages[channel_id];
  ++m.stats.messages;
  return {payload, size};
}

void McapWriter::wait_idle() {
  Impl& m = *impl_;
  std::unique_lock lock(m.mutex);
  m.changed.wait(lock, [&] { return (m.queue.empty() && !m.busy) || m.error; });
  if (m.error) std::rethrow_exception(m.error);
}

void McapWriter::write_metadata(std::string_view name, const McapStringMap& entries) {
  Impl& m = *impl_;
  ChunkJob job = m.fresh_job();
  job.raw = true;
  job.metadata_name = std::string(name);
  const std::size_t at = job.records.begin_record(Op::kMetadata);
  job.records.string(name);
  const std::size_t map = job.records.begin_group();
  for (const auto& [key, value] : entries) {
    job.records.string(key);
    job.records.string(value);
  }
  job.records.end_group(map);
  job.records.end_record(at);
  ++m.stats.metadata;
  // In file order after the messages written so far: close the chunk they are in first.
  m.flush_chunk();
  m.submit(std::move(job));
}

void McapWriter::close() {
  Impl& m = *impl_;
  if (m.closed) return;
  m.flush_chunk();
  m.stop_worker();
  m.rethrow_worker_error();

  Buffer end;
  const std::size_t at = end.begin_record(Op::kDataEnd);
  end.u32(m.data_crc);
  end.end_record(at);
  m.emit(end.bytes());

  // Summary: groups of one opcode each, then a Summary Offset per group.
  const std::uint64_t summary_start = m.offset;
  Buffer s;
  std::vector<std::tuple<Op, std::uint64_t, std::uint64_t>> groups;
  const auto group = [&](Op op, auto&& write) {
    const std::size_t begin = s.size();
    write();
    if (s.size() > begin) groups.emplace_back(op, summary_start + begin, s.size() - begin);
  };
  group(Op::kSchema, [&] { s.raw(m.schema_records.bytes()); });
  group(Op::kChannel, [&] { s.raw(m.channel_records.bytes()); });
  group(Op::kStatistics, [&] { m.write_statistics(s); });
  group(Op::kChunkIndex, [&] { m.write_chunk_indexes(s); });
  group(Op::kMetadataIndex, [&] { m.write_metadata_indexes(s); });
  const std::uint64_t summary_offset_start = summary_start + s.size();
  for (const auto& [op, start, length] : groups) {
    const std::size_t r = s.begin_record(Op::kSummaryOffset);
    s.u8(static_cast<std::uint8_t>(op));
    s.u64(start);
    s.u64(length);
    s.end_record(r);
  }
  s.u8(static_cast<std::uint8_t>(Op::kFooter));
  s.u64(mcap::kFooterContentBytes);
  s.u64(summary_start);
  s.u64(summary_offset_start);
  s.u32(mcap::crc32(s.bytes()));
  s.raw(mcap::kMagic);
  m.emit(s.bytes());
  m.file.close();
  m.closed = true;
  m.stats.file_bytes = m.offset;
}

const McapWriterStats& McapWriter::stats() const {
  return impl_->stats;
}

const std::filesystem::path& McapWriter::path() const {
  return impl_->file.path();
}

}  // namespace ringtrack::io
