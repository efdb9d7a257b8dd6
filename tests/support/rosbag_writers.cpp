#include "support/rosbag_writers.hpp"

#include <bzlib.h>
#include <lz4frame.h>
#include <sqlite3.h>

#include <algorithm>
#include <cstring>
#include <fstream>
#include <map>
#include <stdexcept>

namespace ringtrack::test {
namespace {

// Appends primitives in ROS 1 (packed) or CDR (aligned, after a 4-byte header) form.
class Serializer {
 public:
  explicit Serializer(RosEncoding encoding) : encoding_(encoding) {
    if (encoding_ == RosEncoding::kCdr) bytes_ = {0x00, 0x01, 0x00, 0x00};  // CDR little endian
  }
  void u8(std::uint8_t v) { bytes_.push_back(v); }
  void u32(std::uint32_t v) {
    align(4);
    for (int i = 0; i < 4; ++i) bytes_.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
  }
  void time(std::int64_t ns) {
    u32(static_cast<std::uint32_t>(ns / 1'000'000'000));
    u32(static_cast<std::uint32_t>(ns % 1'000'000'000));
  }
  void string(const std::string& s) {
    const bool cdr = encoding_ == RosEncoding::kCdr;
    u32(static_cast<std::uint32_t>(s.size() + (cdr ? 1 : 0)));
    bytes_.insert(bytes_.end(), s.begin(), s.end());
    if (cdr) bytes_.push_back(0);
  }
  void raw(const std::vector<std::uint8_t>& b) { bytes_.insert(bytes_.end(), b.begin(), b.end()); }
  void header(std::uint32_t seq, std::int64_t stamp_ns, const std::string& frame) {
    if (encoding_ == RosEncoding::kRos1) u32(seq);
    time(stamp_ns);
    string(frame);
  }
  std::vector<std::uint8_t> take() { return std::move(bytes_); }

 private:
  void align(std::size_t n) {
    if (encoding_ != RosEncoding::kCdr) return;
    while ((bytes_.size() - 4) % n != 0) bytes_.push_back(0);
  }
  RosEncoding encoding_;
  std::vector<std::uint8_t> bytes_;
};

void put32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

void put_time(std::vector<std::uint8_t>& b, std::int64_t ns) {
  put32(b, static_cast<std::uint32_t>(ns / 1'000'000'000));
  put32(b, static_cast<std::uint32_t>(ns % 1'000'000'000));
}

// A record header field: uint32 length, "name=", value bytes.
void field(std::vector<std::uint8_t>& b, const std::string& name,
           const std::vector<std::uint8_t>& value) {
  put32(b, static_cast<std::uint32_t>(name.size() + 1 + value.size()));
  b.insert(b.end(), name.begin(), name.end());
  b.push_back('=');
  b.insert(b.end(), value.begin(), value.end());
}

std::vector<std::uint8_t> v8(std::uint8_t v) {
  return {v};
}
std::vector<std::uint8_t> v32(std::uint32_t v) {
  std::vector<std::uint8_t> b;
  put32(b, v);
  return b;
}
std::vector<std::uint8_t> v64(std::uint64_t v) {
  std::vector<std::uint8_t> b;
  put32(b, static_cast<std::uint32_t>(v));
  put32(b, static_cast<std::uint32_t>(v >> 32));
  return b;
}
std::vector<std::uint8_t> vtime(std::int64_t ns) {
  std::vector<std::uint8_t> b;
  put_time(b, ns);
  return b;
}
std::vector<std::uint8_t> vstr(const std::string& s) {
  return {s.begin(), s.end()};
}

// A record: header length, header, data length, data.
void record(std::vector<std::uint8_t>& out, const std::vector<std::uint8_t>& header,
            const std::vector<std::uint8_t>& data) {
  put32(out, static_cast<std::uint32_t>(header.size()));
  out.insert(out.end(), header.begin(), header.end());
  put32(out, static_cast<std::uint32_t>(data.size()));
  out.insert(out.end(), data.begin(), data.end());
}

std::vector<std::uint8_t> connection_record(std::uint32_t conn, const TestBagTopic& topic) {
  std::vector<std::uint8_t> header;
  field(header, "op", v8(0x07));
  field(header, "conn", v32(conn));
  field(header, "topic", vstr(topic.name));
  std::vector<std::uint8_t> data;
  field(data, "topic", vstr(topic.name));
  field(data, "type", vstr(topic.type));
  field(data, "md5sum", vstr("0123456789abcdef0123456789abcdef"));
  field(data, "message_definition", vstr("# test\n"));
  std::vector<std::uint8_t> out;
  record(out, header, data);
  return out;
}

std::vector<std::uint8_t> compress(const std::vector<std::uint8_t>& in, const std::string& how) {
  if (how == "none") return in;
  if (how == "lz4") {
    std::vector<std::uint8_t> out(LZ4F_compressFrameBound(in.size(), nullptr));
    const std::size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr);
    if (LZ4F_isError(n)) throw std::runtime_error("lz4 compression failed");
    out.resize(n);
    return out;
  }
  if (how == "bz2") {
    std::vector<std::uint8_t> out(in.size() + in.size() / 100 + 600);
    auto n = static_cast<unsigned int>(out.size());
    std::vector<std::uint8_t> src = in;
    if (BZ2_bzBuffToBuffCompress(reinterpret_cast<char*>(out.data()), &n,
                                 reinterpret_cast<char*>(src.data()),
                                 static_cast<unsigned int>(src.size()), 9, 0, 30) != BZ_OK) {
      throw std::runtime_error("bz2 compression failed");
    }
    out.resize(n);
    return out;
  }
  throw std::runtime_error("unknown compression " + how);
}

}  // namespace

TestPointCloud2 make_xyzirt_cloud(const std::vector<TestPoint>& points, std::uint32_t height,
                                  std::uint32_t width, std::int64_t stamp_ns, bool with_ring,
                                  bool with_time) {
  if (points.size() != static_cast<std::size_t>(height) * width) {
    throw std::runtime_error("make_xyzirt_cloud: points != height x width");
  }
  TestPointCloud2 c;
  c.stamp_ns = stamp_ns;
  c.height = height;
  c.width = width;
  c.fields = {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}, {"intensity", 12, 7, 1}};
  if (with_ring) c.fields.push_back({"ring", 16, 4, 1});
  if (with_time) c.fields.push_back({"time", 18, 7, 1});
  c.point_step = 24;
  c.row_step = 24 * width;
  c.data.assign(static_cast<std::size_t>(c.row_step) * height, 0);
  for (std::size_t i = 0; i < points.size(); ++i) {
    std::uint8_t* p = c.data.data() + 24 * i;
    const TestPoint& q = points[i];
    std::memcpy(p, &q.x, 4);
    std::memcpy(p + 4, &q.y, 4);
    std::memcpy(p + 8, &q.z, 4);
    std::memcpy(p + 12, &q.intensity, 4);
    std::memcpy(p + 16, &q.ring, 2);
    std::memcpy(p + 18, &q.time_s, 4);
  }
  c.is_dense = false;
  return c;
}

std::vector<std::uint8_t> serialize_velodyne_scan(const TestVelodyneScan& scan,
                                                  RosEncoding encoding) {
  Serializer s(encoding);
  s.header(scan.seq, scan.stamp_ns, scan.frame_id);
  s.u32(static_cast<std::uint32_t>(scan.packets.size()));
  for (const auto& p : scan.packets) {
    s.time(p.stamp_ns);
    s.raw(p.data);  // uint8[1206]: fixed size, no length
  }
  return s.take();
}

std::vector<std::uint8_t> serialize_pointcloud2(const TestPointCloud2& c, RosEncoding encoding) {
  Serializer s(encoding);
  s.header(c.seq, c.stamp_ns, c.frame_id);
  s.u32(c.height);
  s.u32(c.width);
  s.u32(static_cast<std::uint32_t>(c.fields.size()));
  for (const auto& f : c.fields) {
    s.string(f.name);
    s.u32(f.offset);
    s.u8(f.datatype);
    s.u32(f.count);
  }
  s.u8(c.is_bigendian ? 1 : 0);
  s.u32(c.point_step);
  s.u32(c.row_step);
  s.u32(static_cast<std::uint32_t>(c.data.size()));
  s.raw(c.data);
  s.u8(c.is_dense ? 1 : 0);
  return s.take();
}

std::vector<std::uint8_t> serialize_ouster_packet(const std::vector<std::uint8_t>& buf,
                                                  RosEncoding encoding) {
  Serializer s(encoding);
  s.u32(static_cast<std::uint32_t>(buf.size()));
  s.raw(buf);
  return s.take();
}

std::vector<std::uint8_t> serialize_string(const std::string& text, RosEncoding encoding) {
  Serializer s(encoding);
  s.string(text);
  return s.take();
}

std::vector<TestBagMessage> velodyne_scan_messages(
    const std::vector<EncodedVelodynePacket>& packets, std::size_t topic, RosEncoding encoding,
    std::size_t packets_per_message) {
  if (packets_per_message == 0) throw std::invalid_argument("packets_per_message must be > 0");
  std::vector<TestBagMessage> out;
  for (std::size_t i = 0; i < packets.size(); i += packets_per_message) {
    TestVelodyneScan s;
    s.seq = static_cast<std::uint32_t>(out.size());
    s.stamp_ns = packets[i].host_stamp_ns;
    for (std::size_t k = i; k < std::min(packets.size(), i + packets_per_message); ++k) {
      s.packets.push_back({packets[k].host_stamp_ns, packets[k].payload});
    }
    out.push_back({topic, s.packets.back().stamp_ns, serialize_velodyne_scan(s, encoding)});
  }
  return out;
}

void write_rosbag1(const std::filesystem::path& path, const std::vector<TestBagTopic>& topics,
                   const std::vector<TestBagMessage>& messages,
                   const Rosbag1WriteOptions& options) {
  constexpr std::size_t kBagHeaderRecord = 4096;
  const std::string magic = "#ROSBAG V2.0\n";
  std::vector<std::uint8_t> out(magic.begin(), magic.end());
  const std::size_t bag_header_at = out.size();
  out.resize(out.size() + kBagHeaderRecord);  // written at the end

  struct ChunkInfo {
    std::uint64_t pos{0};
    std::int64_t start_ns{0}, end_ns{0};
    std::map<std::uint32_t, std::uint32_t> counts;
  };
  std::vector<ChunkInfo> chunks;
  std::vector<bool> written(topics.size(), false);
  std::size_t next = 0;
  while (next < messages.size()) {
    std::vector<std::uint8_t> inner;
    ChunkInfo info;
    info.start_ns = messages[next].stamp_ns;
    info.end_ns = messages[next].stamp_ns;
    std::map<std::uint32_t, std::vector<std::pair<std::int64_t, std::uint32_t>>> index;
    while (next < messages.size() && inner.size() < options.chunk_bytes) {
      const TestBagMessage& m = messages[next++];
      const auto conn = static_cast<std::uint32_t>(m.topic);
      if (!written[m.topic]) {
        const auto c = connection_record(conn, topics[m.topic]);
        inner.insert(inner.end(), c.begin(), c.end());
        written[m.topic] = true;
      }
      index[conn].emplace_back(m.stamp_ns, static_cast<std::uint32_t>(inner.size()));
      std::vector<std::uint8_t> header;
      field(header, "op", v8(0x02));
      field(header, "conn", v32(conn));
      field(header, "time", vtime(m.stamp_ns));
      record(inner, header, m.data);
      ++info.counts[conn];
      info.start_ns = std::min(info.start_ns, m.stamp_ns);
      info.end_ns = std::max(info.end_ns, m.stamp_ns);
    }
    info.pos = out.size();
    std::vector<std::uint8_t> header;
    field(header, "op", v8(0x05));
    field(header, "compression", vstr(options.compression));
    field(header, "size", v32(static_cast<std::uint32_t>(inner.size())));
    record(out, header, compress(inner, options.compression));
    for (const auto& [conn, entries] : index) {
      std::vector<std::uint8_t> h;
      field(h, "op", v8(0x04));
      field(h, "ver", v32(1));
      field(h, "conn", v32(conn));
      field(h, "count", v32(static_cast<std::uint32_t>(entries.size())));
      std::vector<std::uint8_t> data;
      for (const auto& [ns, offset] : entries) {
        put_time(data, ns);
        put32(data, offset);
      }
      record(out, h, data);
    }
    chunks.push_back(std::move(info));
  }

  std::uint64_t index_pos = 0;
  if (options.indexed) {
    index_pos = out.size();
    for (std::size_t t = 0; t < topics.size(); ++t) {
      const auto c = connection_record(static_cast<std::uint32_t>(t), topics[t]);
      out.insert(out.end(), c.begin(), c.end());
    }
    for (const auto& info : chunks) {
      std::vector<std::uint8_t> h;
      field(h, "op", v8(0x06));
      field(h, "ver", v32(1));
      field(h, "chunk_pos", v64(info.pos));
      field(h, "start_time", vtime(info.start_ns));
      field(h, "end_time", vtime(info.end_ns));
      field(h, "count", v32(static_cast<std::uint32_t>(info.counts.size())));
      std::vector<std::uint8_t> data;
      for (const auto& [conn, n] : info.counts) {
        put32(data, conn);
        put32(data, n);
      }
      record(out, h, data);
    }
  }
  // The bag header record, padded with spaces to 4096 bytes.
  std::vector<std::uint8_t> h;
  field(h, "op", v8(0x03));
  field(h, "index_pos", v64(index_pos));
  field(h, "conn_count", v32(options.indexed ? static_cast<std::uint32_t>(topics.size()) : 0));
  field(h, "chunk_count", v32(options.indexed ? static_cast<std::uint32_t>(chunks.size()) : 0));
  std::vector<std::uint8_t> bag_header;
  record(bag_header, h, std::vector<std::uint8_t>(kBagHeaderRecord - 8 - h.size(), ' '));
  std::copy(bag_header.begin(), bag_header.end(), out.begin() + static_cast<long>(bag_header_at));

  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(out.data()), static_cast<std::streamsize>(out.size()));
  if (!f) throw std::runtime_error("cannot write " + path.string());
}

void write_rosbag2(const std::filesystem::path& folder, const std::vector<TestBagTopic>& topics,
                   const std::vector<TestBagMessage>& messages, bool metadata) {
  std::filesystem::create_directories(folder);
  const std::string db_name = folder.filename().string() + "_0.db3";
  const std::filesystem::path file = folder / db_name;
  std::filesystem::remove(file);
  sqlite3* db = nullptr;
  const auto check = [&db](int rc, const char* what) {
    if (rc != SQLITE_OK && rc != SQLITE_DONE) {
      const std::string msg = std::string(what) + ": " + sqlite3_errmsg(db);
      sqlite3_close(db);
      throw std::runtime_error(msg);
    }
  };
  check(sqlite3_open(file.string().c_str(), &db), "open");
  check(
      sqlite3_exec(db,
                   "CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT "
                   "NULL);"
                   "INSERT INTO schema VALUES(3, 'humble');"
                   "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT "
                   "NULL, serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT "
                   "NULL);"
                   "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
                   "timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
                   "CREATE INDEX timestamp_idx ON messages (timestamp ASC);",
                   nullptr, nullptr, nullptr),
      "schema");
  sqlite3_stmt* stmt = nullptr;
  check(sqlite3_prepare_v2(db, "INSERT INTO topics VALUES(?, ?, ?, 'cdr', '')", -1, &stmt, nullptr),
        "prepare topics");
  for (std::size_t t = 0; t < topics.size(); ++t) {
    sqlite3_bind_int64(stmt, 1, static_cast<sqlite3_int64>(t + 1));
    sqlite3_bind_text(stmt, 2, topics[t].name.c_str(), -1, SQLITE_TRANSIENT);
    sqlite3_bind_text(stmt, 3, topics[t].type.c_str(), -1, SQLITE_TRANSIENT);
    check(sqlite3_step(stmt), "insert topic");
    sqlite3_reset(stmt);
  }
  sqlite3_finalize(stmt);
  check(sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?, ?, ?)",
                           -1, &stmt, nullptr),
        "prepare messages");
  std::map<std::size_t, std::size_t> counts;
  for (const auto& m : messages) {
    sqlite3_bind_int64(stmt, 1, static_cast<sqlite3_int64>(m.topic + 1));
    sqlite3_bind_int64(stmt, 2, m.stamp_ns);
    sqlite3_bind_blob(stmt, 3, m.data.data(), static_cast<int>(m.data.size()), SQLITE_TRANSIENT);
    check(sqlite3_step(stmt), "insert message");
    sqlite3_reset(stmt);
    ++counts[m.topic];
  }
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  if (!metadata) return;
  std::ofstream y(folder / "metadata.yaml");
  y << "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
    << "  relative_file_paths:\n    - " << db_name << "\n"
    << "  duration:\n    nanoseconds: 0\n  starting_time:\n    nanoseconds_since_epoch: 0\n"
    << "  message_count: " << messages.size() << "\n  topics_with_message_count:\n";
  for (std::size_t t = 0; t < topics.size(); ++t) {
    y << "    - topic_metadata:\n        name: " << topics[t].name
      << "\n        type: " << topics[t].type << "\n        serialization_format: cdr\n"
      << "        offered_qos_profiles: \"\"\n      message_count: " << counts[t] << "\n";
  }
  y << "  compression_format: \"\"\n  compression_mode: \"\"\n";
}

}  // namespace ringtrack::test
