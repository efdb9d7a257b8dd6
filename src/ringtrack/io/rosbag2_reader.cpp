#include "ringtrack/io/rosbag2_reader.hpp"

#include <sqlite3.h>

#include <algorithm>
#include <map>
#include <optional>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/paths.hpp"
#include "ringtrack/io/rosbag2_metadata.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

struct DbCloser {
  void operator()(sqlite3* db) const { sqlite3_close(db); }
};
struct StmtCloser {
  void operator()(sqlite3_stmt* stmt) const { sqlite3_finalize(stmt); }
};
using Db = std::unique_ptr<sqlite3, DbCloser>;
using Stmt = std::unique_ptr<sqlite3_stmt, StmtCloser>;

// A read-only URI with immutable=1: no locks and no journal files, so bags on read-only media
// (and bags another process still holds open) can be read.
std::string sqlite_uri(const fs::path& path) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string uri = "file:";
  for (const char c : fs::absolute(path).string()) {
    if (c == '%' || c == '?' || c == '#') {
      uri += '%';
      uri += kHex[(static_cast<unsigned char>(c) >> 4) & 0xF];
      uri += kHex[static_cast<unsigned char>(c) & 0xF];
    } else {
      uri += c;
    }
  }
  return uri + "?immutable=1";
}

std::string column_text(sqlite3_stmt* stmt, int column) {
  const unsigned char* s = sqlite3_column_text(stmt, column);
  return s != nullptr ? std::string(reinterpret_cast<const char*>(s)) : std::string();
}

// One topic as a .db3 file stores it (ids are per file in split bags).
struct FileTopic {
  std::int64_t id{0};
  std::string name;
  std::string type;
  std::string serialization_format;
  std::uint64_t messages{0};
};

// An open .db3 file.
struct DbFile {
  fs::path path;
  Db db;
  std::vector<FileTopic> topics;

  Stmt prepare(const char* sql) const {
    sqlite3_stmt* stmt = nullptr;
    if (sqlite3_prepare_v2(db.get(), sql, -1, &stmt, nullptr) != SQLITE_OK) {
      sqlite3_finalize(stmt);
      throw core::InputError(path.string() + ": not a rosbag2 sqlite3 database (" +
                             sqlite3_errmsg(db.get()) + ")");
    }
    return Stmt(stmt);
  }
};

// Opens storage (a .db3 file, or the expanded copy of a file-compressed one); messages name
// `path`, the file the user has.
DbFile open_db(const fs::path& storage, const fs::path& path) {
  DbFile file;
  file.path = path;
  sqlite3* db = nullptr;
  const int rc = sqlite3_open_v2(sqlite_uri(storage).c_str(), &db,
                                 SQLITE_OPEN_READONLY | SQLITE_OPEN_URI, nullptr);
  file.db.reset(db);
  if (rc != SQLITE_OK) {
    throw core::InputError(path.string() + ": cannot open as sqlite3 (" +
                           (db != nullptr ? sqlite3_errmsg(db) : "out of memory") + ")");
  }
  {
    const Stmt q = file.prepare("SELECT id, name, type, serialization_format FROM topics");
    int step = 0;
    while ((step = sqlite3_step(q.get())) == SQLITE_ROW) {
      FileTopic t;
      t.id = sqlite3_column_int64(q.get(), 0);
      t.name = column_text(q.get(), 1);
      t.type = column_text(q.get(), 2);
      t.serialization_format = column_text(q.get(), 3);
      file.topics.push_back(std::move(t));
    }
    if (step != SQLITE_DONE) {
      throw core::InputError(path.string() +
                             ": reading the topics table: " + sqlite3_errmsg(file.db.get()));
    }
  }
  {
    const Stmt q = file.prepare("SELECT topic_id, COUNT(*) FROM messages GROUP BY topic_id");
    int step = 0;
    while ((step = sqlite3_step(q.get())) == SQLITE_ROW) {
      const std::int64_t id = sqlite3_column_int64(q.get(), 0);
      const auto n = static_cast<std::uint64_t>(sqlite3_column_int64(q.get(), 1));
      for (auto& t : file.topics) {
        if (t.id == id) t.messages += n;
      }
    }
    if (step != SQLITE_DONE) {
      throw core::InputError(path.string() +
                             ": reading the messages table: " + sqlite3_errmsg(file.db.get()));
    }
  }
  return file;
}

std::string list_topics(const std::vector<RosbagTopicInfo>& topics) {
  std::string s;
  for (const auto& t : topics) s += (s.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  return s.empty() ? "none" : s;
}

}  // namespace

struct Rosbag2Reader::Impl {
  fs::path path;
  std::vector<fs::path> files;
  Rosbag2Compression compression{Rosbag2Compression::kNone};
  std::optional<TemporaryFolder> expanded;  // file-compressed bags: the .db3 files expanded
  std::vector<DbFile> dbs;                  // every file stays open: split bags are few files
  std::vector<RosbagTopicInfo> topics;
  std::string selected;
  std::size_t file_index{0};
  Stmt stmt;  // messages of the selected topic in dbs[file_index - 1]
  std::vector<std::uint8_t> message;
  std::uint64_t index{0};
  std::uint64_t other{0};
  bool started{false};

  // Prepares the message query of the next file holding the selected topic; false at the end.
  bool open_next_file() {
    stmt.reset();
    while (file_index < dbs.size()) {
      const DbFile& file = dbs[file_index++];
      const auto it = std::find_if(file.topics.begin(), file.topics.end(),
                                   [&](const FileTopic& t) { return t.name == selected; });
      for (const auto& t : file.topics) {
        if (t.name != selected) other += t.messages;
      }
      if (it == file.topics.end()) continue;
      if (it->serialization_format != "cdr") {
        throw core::InputError(file.path.string() + ": topic " + selected + " is serialized as '" +
                               it->serialization_format + "', expected cdr");
      }
      stmt = file.prepare(
          "SELECT timestamp, data FROM messages WHERE topic_id = ? "
          "ORDER BY timestamp, id");
      sqlite3_bind_int64(stmt.get(), 1, it->id);
      return true;
    }
    return false;
  }
};

Rosbag2Reader::Rosbag2Reader(const fs::path& path) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = path;
  const std::string name = path.string();
  if (is_folder(path)) {
    if (is_file(path / "metadata.yaml")) {
      Rosbag2Metadata metadata = read_rosbag2_metadata(path, "sqlite3");
      m.files = std::move(metadata.files);
      m.compression = metadata.compression;
    } else {
      std::error_code ec;
      for (const auto& entry : fs::directory_iterator(path, ec)) {
        if (entry.path().extension() == ".db3") m.files.push_back(entry.path());
      }
      std::sort(m.files.begin(), m.files.end());
      if (m.files.empty()) {
        throw core::InputError(name +
                               ": not a rosbag2 folder (expected metadata.yaml or .db3 files)");
      }
    }
  } else if (is_file(path)) {
    m.files.push_back(path);
  } else {
    throw core::InputError(name + ": no such rosbag2 folder or .db3 file");
  }
  if (m.compression == Rosbag2Compression::kFile) {
    // sqlite reads files only: each listed "x.db3.zstd" is expanded to a temporary "x.db3",
    // removed with the reader (the disk needs room for the expanded bag).
    m.expanded.emplace("rosbag2");
    for (std::size_t i = 0; i < m.files.size(); ++i) {
      const fs::path& file = m.files[i];
      // Numbered: listed paths may share a name in different folders.
      const fs::path storage =
          m.expanded->path() / (std::to_string(i) + "_" + file.stem().string());
      decompress_zstd_file(file, storage);
      m.dbs.push_back(open_db(storage, file));
    }
  } else {
    for (const auto& file : m.files) m.dbs.push_back(open_db(file, file));
  }
  // Topics by name over every file (ids differ between the files of a split bag).
  for (const auto& file : m.dbs) {
    for (const auto& t : file.topics) {
      auto it = std::find_if(m.topics.begin(), m.topics.end(),
                             [&](const RosbagTopicInfo& info) { return info.name == t.name; });
      if (it == m.topics.end()) {
        m.topics.push_back({t.name, t.type, 0});
        it = m.topics.end() - 1;
      } else if (it->type != t.type) {
        throw core::InputError(file.path.string() + ": topic " + t.name + " has type " + t.type +
                               " here but " + it->type + " in an earlier file");
      }
      it->messages += t.messages;
    }
  }
}

Rosbag2Reader::~Rosbag2Reader() = default;

const std::vector<RosbagTopicInfo>& Rosbag2Reader::topics() const {
  return impl_->topics;
}

void Rosbag2Reader::select_topic(const std::string& name) {
  Impl& m = *impl_;
  if (m.started) throw core::Error(m.path.string() + ": select_topic after reading began");
  const auto it = std::find_if(m.topics.begin(), m.topics.end(),
                               [&](const RosbagTopicInfo& t) { return t.name == name; });
  if (it == m.topics.end()) {
    throw core::ConfigError(m.path.string() + ": no topic '" + name + "'; the bag has " +
                            list_topics(m.topics));
  }
  m.selected = name;
}

bool Rosbag2Reader::next(RosbagMessage& out) {
  Impl& m = *impl_;
  if (m.selected.empty()) throw core::Error(m.path.string() + ": no topic selected");
  if (!m.started) {
    m.started = true;
    if (!m.open_next_file()) return false;
  }
  while (m.stmt) {
    const int step = sqlite3_step(m.stmt.get());
    if (step == SQLITE_ROW) {
      const auto* blob = static_cast<const std::uint8_t*>(sqlite3_column_blob(m.stmt.get(), 1));
      const auto size = static_cast<std::size_t>(sqlite3_column_bytes(m.stmt.get(), 1));
      if (m.compression == Rosbag2Compression::kMessage) {
        decompress_zstd_message({blob, size}, m.message,
                                m.dbs[m.file_index - 1].path.string() + ": message " +
                                    std::to_string(m.index + 1) + " of " + m.selected);
      } else {
        m.message.assign(blob, blob + size);
      }
      out.stamp_ns = sqlite3_column_int64(m.stmt.get(), 0);
      out.data = m.message;
      out.index = ++m.index;
      return true;
    }
    const DbFile& file = m.dbs[m.file_index - 1];
    if (step != SQLITE_DONE) {
      throw core::InputError(file.path.string() + ": reading message " +
                             std::to_string(m.index + 1) + " of " + m.selected + ": " +
                             sqlite3_errmsg(file.db.get()));
    }
    if (!m.open_next_file()) return false;
  }
  return false;
}

std::uint64_t Rosbag2Reader::other_messages() const {
  return impl_->other;
}

const fs::path& Rosbag2Reader::path() const {
  return impl_->path;
}

const fs::path& Rosbag2Reader::current_file() const {
  const Impl& m = *impl_;
  return m.file_index > 0 ? m.dbs[m.file_index - 1].path : m.path;
}

const std::vector<fs::path>& Rosbag2Reader::files() const {
  return impl_->files;
}

}  // namespace ringtrack::io
