#include "ringtrack/io/velodyne_rosbag2_source.hpp"

#include <sqlite3.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/velodyne_packet.hpp"

namespace ringtrack::io {
namespace {

constexpr const char* kVelodyneScanType = "velodyne_msgs/msg/VelodyneScan";

// Reads CDR (XCDR1) primitives; alignment is relative to the end of the encapsulation header.
class CdrReader {
 public:
  CdrReader(std::span<const std::uint8_t> message, const std::string& where) : where_(where) {
    if (message.size() < 4) fail("shorter than the CDR encapsulation header");
    if (message[0] != 0 || message[1] > 1) {
      fail("unsupported CDR encapsulation " + std::to_string(message[0]) + "," +
           std::to_string(message[1]) + " (expected plain CDR)");
    }
    little_ = message[1] == 1;
    body_ = message.subspan(4);
  }

  std::uint32_t u32() {
    align(4);
    need(4);
    const std::uint8_t* p = body_.data() + at_;
    at_ += 4;
    return little_ ? static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
                         (static_cast<std::uint32_t>(p[2]) << 16) |
                         (static_cast<std::uint32_t>(p[3]) << 24)
                   : static_cast<std::uint32_t>(p[3]) | (static_cast<std::uint32_t>(p[2]) << 8) |
                         (static_cast<std::uint32_t>(p[1]) << 16) |
                         (static_cast<std::uint32_t>(p[0]) << 24);
  }
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  std::span<const std::uint8_t> bytes(std::size_t n) {
    need(n);
    const auto out = body_.subspan(at_, n);
    at_ += n;
    return out;
  }
  void skip_string() {
    const std::uint32_t n = u32();
    bytes(n);
  }
  [[nodiscard]] std::size_t remaining() const { return body_.size() - at_; }
  [[noreturn]] void fail(const std::string& what) const {
    throw core::InputError(where_ + ": VelodyneScan message " + what);
  }

 private:
  void align(std::size_t n) { at_ = (at_ + n - 1) / n * n; }
  void need(std::size_t n) const {
    if (at_ > body_.size() || body_.size() - at_ < n) {
      fail("is truncated at byte " + std::to_string(at_ + 4) + " (needs " + std::to_string(n) +
           " more)");
    }
  }

  std::string where_;
  std::span<const std::uint8_t> body_;
  std::size_t at_{0};
  bool little_{true};
};

std::int64_t stamp_ns(std::int32_t sec, std::uint32_t nanosec) {
  return static_cast<std::int64_t>(sec) * 1'000'000'000 + nanosec;
}

std::string sqlite_uri(const std::filesystem::path& path) {
  // immutable=1: no locks, no journal files (bags may lie on read-only media).
  std::string uri = "file:";
  for (char c : std::filesystem::absolute(path).string()) {
    if (c == '%' || c == '?' || c == '#') {
      static const char* hex = "0123456789ABCDEF";
      uri += '%';
      uri += hex[(static_cast<unsigned char>(c) >> 4) & 0xF];
      uri += hex[static_cast<unsigned char>(c) & 0xF];
    } else {
      uri += c;
    }
  }
  return uri + "?immutable=1";
}

bool is_velodyne_scan(const std::string& type) {
  return type == kVelodyneScanType || type == "velodyne_msgs/VelodyneScan";
}

std::string list_topics(const std::vector<Rosbag2Topic>& topics) {
  std::string s;
  for (const auto& t : topics) s += (s.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  return s.empty() ? "none" : s;
}

}  // namespace

std::vector<VelodyneScanPacket> parse_velodyne_scan_cdr(std::span<const std::uint8_t> message,
                                                        const std::string& where) {
  CdrReader cdr(message, where);
  cdr.i32();          // header.stamp.sec
  cdr.u32();          // header.stamp.nanosec
  cdr.skip_string();  // header.frame_id
  const std::uint32_t count = cdr.u32();
  // Each packet needs at least 8 + 1206 bytes: reject absurd counts before allocating.
  if (count > cdr.remaining() / (8 + kVelodyneDataPacketBytes)) {
    cdr.fail("claims " + std::to_string(count) + " packets but holds " +
             std::to_string(cdr.remaining()) + " bytes");
  }
  std::vector<VelodyneScanPacket> packets(count);
  for (auto& p : packets) {
    const std::int32_t sec = cdr.i32();
    const std::uint32_t nanosec = cdr.u32();
    p.stamp_ns = stamp_ns(sec, nanosec);
    p.data = cdr.bytes(kVelodyneDataPacketBytes);
  }
  return packets;
}

void VelodyneRosbag2Source::DbCloser::operator()(sqlite3* db) const {
  sqlite3_close(db);
}
void VelodyneRosbag2Source::StmtCloser::operator()(sqlite3_stmt* stmt) const {
  sqlite3_finalize(stmt);
}

VelodyneRosbag2Source::VelodyneRosbag2Source(const std::filesystem::path& path,
                                             const std::string& topic,
                                             VelodyneDecoderOptions decoder_options)
    : requested_topic_(topic), decoder_(std::move(decoder_options)) {
  namespace fs = std::filesystem;
  const std::string name = path.string();
  if (fs::is_directory(path)) {
    const fs::path metadata = path / "metadata.yaml";
    if (fs::exists(metadata)) {
      YAML::Node info;
      try {
        info = YAML::LoadFile(metadata.string())["rosbag2_bagfile_information"];
      } catch (const YAML::Exception& e) {
        throw core::InputError(metadata.string() + ": " + e.what());
      }
      if (!info) throw core::InputError(metadata.string() + ": no rosbag2_bagfile_information");
      const std::string storage = info["storage_identifier"].as<std::string>("sqlite3");
      if (storage != "sqlite3") {
        throw core::InputError(name + ": storage '" + storage +
                               "' is not supported (only sqlite3 .db3 bags)");
      }
      const std::string compression = info["compression_format"].as<std::string>("");
      if (!compression.empty()) {
        throw core::InputError(name + ": compressed bags (" + compression +
                               ") are not supported; decompress with `ros2 bag convert`");
      }
      for (const auto& file : info["relative_file_paths"]) {
        // Old rosbag2 versions list paths relative to the bag's parent folder.
        const auto relative = file.as<std::string>();
        const bool in_parent =
            !fs::exists(path / relative) && fs::exists(path.parent_path() / relative);
        files_.push_back(in_parent ? path.parent_path() / relative : path / relative);
      }
    } else {
      for (const auto& entry : fs::directory_iterator(path)) {
        if (entry.path().extension() == ".db3") files_.push_back(entry.path());
      }
      std::sort(files_.begin(), files_.end());
    }
  } else if (path.extension() == ".db3" && fs::exists(path)) {
    files_.push_back(path);
  } else {
    throw core::InputError(name + ": expected a rosbag2 folder or a .db3 file");
  }
  if (files_.empty()) throw core::InputError(name + ": no .db3 files in the bag");
  for (const auto& f : files_) {
    if (!fs::exists(f))
      throw core::InputError(f.string() + ": listed in metadata.yaml but missing");
  }
  if (!open_next_file()) throw core::InputError(name + ": the bag holds no messages");
}

VelodyneRosbag2Source::~VelodyneRosbag2Source() = default;

bool VelodyneRosbag2Source::open_next_file() {
  stmt_.reset();
  db_.reset();
  if (file_index_ >= files_.size()) return false;
  const std::filesystem::path file = files_[file_index_++];
  const std::string name = file.string();
  sqlite3* db = nullptr;
  const int rc = sqlite3_open_v2(sqlite_uri(file).c_str(), &db,
                                 SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr);
  db_.reset(db);
  if (rc != SQLITE_OK) {
    throw core::InputError(name + ": cannot open as sqlite3: " +
                           (db != nullptr ? sqlite3_errmsg(db) : "out of memory"));
  }
  const auto prepare = [&](const char* sql) {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr) != SQLITE_OK) {
      throw core::InputError(name + ": not a rosbag2 sqlite3 file (" + sqlite3_errmsg(db) + ")");
    }
    return std::unique_ptr<sqlite3_stmt, StmtCloser>(stmt);
  };
  std::vector<Rosbag2Topic> topics;
  {
    auto q = prepare("SELECT id, name, type, serialization_format FROM topics");
    int step = 0;
    while ((step = sqlite3_step(q.get())) == SQLITE_ROW) {
      Rosbag2Topic t;
      t.id = sqlite3_column_int64(q.get(), 0);
      const auto text = [&](int col) {
        const unsigned char* s = sqlite3_column_text(q.get(), col);
        return s != nullptr ? std::string(reinterpret_cast<const char*>(s)) : std::string();
      };
      t.name = text(1);
      t.type = text(2);
      t.serialization_format = text(3);
      topics.push_back(std::move(t));
    }
    if (step != SQLITE_DONE)
      throw core::InputError(name + ": reading topics: " + sqlite3_errmsg(db));
  }
  if (topics_.empty()) {  // the first file decides the topic
    topics_ = topics;
    if (!requested_topic_.empty()) {
      const auto it = std::find_if(topics_.begin(), topics_.end(),
                                   [&](const auto& t) { return t.name == requested_topic_; });
      if (it == topics_.end()) {
        throw core::ConfigError(name + ": no topic '" + requested_topic_ + "'; the bag has " +
                                list_topics(topics_));
      }
      topic_ = *it;
    } else {
      std::vector<Rosbag2Topic> scans;
      for (const auto& t : topics_) {
        if (is_velodyne_scan(t.type)) scans.push_back(t);
      }
      if (scans.size() != 1) {
        throw core::InputError(name + ": " +
                               (scans.empty()
                                    ? std::string("no ") + kVelodyneScanType + " topic"
                                    : std::string("several VelodyneScan topics; choose one")) +
                               " (topics: " + list_topics(topics_) + ")");
      }
      topic_ = scans.front();
    }
    if (!is_velodyne_scan(topic_.type)) {
      throw core::InputError(name + ": topic " + topic_.name + " has type " + topic_.type +
                             "; only " + kVelodyneScanType +
                             " is supported (sensor_msgs/msg/PointCloud2 not yet)");
    }
    if (topic_.serialization_format != "cdr") {
      throw core::InputError(name + ": topic " + topic_.name + " is serialized as '" +
                             topic_.serialization_format + "', expected cdr");
    }
  }
  // Split bags number their topics per file: find ours by name.
  const auto it = std::find_if(topics.begin(), topics.end(),
                               [&](const auto& t) { return t.name == topic_.name; });
  if (it == topics.end()) return open_next_file();
  {
    auto q = prepare("SELECT COUNT(*) FROM messages WHERE topic_id != ?");
    sqlite3_bind_int64(q.get(), 1, it->id);
    if (sqlite3_step(q.get()) == SQLITE_ROW) {
      stats_.other_messages += static_cast<std::uint64_t>(sqlite3_column_int64(q.get(), 0));
    }
  }
  stmt_ = prepare("SELECT data FROM messages WHERE topic_id = ? ORDER BY timestamp, id");
  sqlite3_bind_int64(stmt_.get(), 1, it->id);
  where_ = name;
  return true;
}

bool VelodyneRosbag2Source::load_message() {
  while (true) {
    if (!stmt_ && !open_next_file()) return false;
    const int step = sqlite3_step(stmt_.get());
    if (step == SQLITE_DONE) {
      stmt_.reset();
      continue;
    }
    if (step != SQLITE_ROW) {
      throw core::InputError(where_ + ": reading messages: " + sqlite3_errmsg(db_.get()));
    }
    const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(stmt_.get(), 0));
    const auto size = static_cast<std::size_t>(sqlite3_column_bytes(stmt_.get(), 0));
    message_.assign(blob, blob + size);
    ++stats_.messages;
    packets_ =
        parse_velodyne_scan_cdr(message_, where_ + " (message " + std::to_string(stats_.messages) +
                                              " of " + topic_.name + ")");
    stats_.packets += packets_.size();
    packet_index_ = 0;
    return true;
  }
}

std::optional<VelodyneScanPacket> VelodyneRosbag2Source::next_packet() {
  while (packet_index_ >= packets_.size()) {
    if (!load_message()) return std::nullopt;
  }
  return packets_[packet_index_++];
}

std::optional<core::OrganizedScan> VelodyneRosbag2Source::next() {
  if (auto scan = decoder_.pop_scan()) return scan;
  while (!finished_) {
    const auto packet = next_packet();
    if (!packet) {
      finished_ = true;
      if (decoder_.stats().decoded_packets == 0) {
        throw core::InputError(where_ + ": no decodable Velodyne data packets on " + topic_.name);
      }
      decoder_.finish();
      break;
    }
    try {
      decoder_.add_packet(packet->data, packet->stamp_ns);
    } catch (const core::InputError& e) {
      throw core::InputError(where_ + " (" + topic_.name + "): " + e.what());
    }
    if (auto scan = decoder_.pop_scan()) return scan;
  }
  return decoder_.pop_scan();
}

}  // namespace ringtrack::io
