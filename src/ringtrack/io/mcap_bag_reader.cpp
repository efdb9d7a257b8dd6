#include "ringtrack/io/mcap_bag_reader.hpp"

#include <algorithm>
#include <optional>
#include <set>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/paths.hpp"
#include "ringtrack/io/rosbag2_metadata.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> mcap_files_in(const fs::path& folder) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    if (entry.path().extension() == ".mcap") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string list_topics(const std::vector<RosbagTopicInfo>& topics) {
  std::string s;
  for (const auto& t : topics) s += (s.empty() ? "" : ", ") + t.name + " (" + t.type + ")";
  return s.empty() ? "none" : s;
}

}  // namespace

bool is_mcap_bag(const fs::path& path) {
  if (is_folder(path)) {
    if (is_file(path / "metadata.yaml")) return rosbag2_storage(path / "metadata.yaml") == "mcap";
    return !mcap_files_in(path).empty();
  }
  return is_mcap_file(path);
}

struct McapBagReader::Impl {
  fs::path path;
  std::vector<fs::path> files;
  Rosbag2Compression compression{Rosbag2Compression::kNone};
  std::optional<TemporaryFolder> expanded;  // file-compressed bags: the .mcap files expanded
  std::vector<std::unique_ptr<McapReader>> readers;
  std::vector<RosbagTopicInfo> topics;
  std::string selected;
  std::size_t file_index{0};
  std::set<std::uint16_t> wanted;     // channel ids of the selected topic in the current file
  std::size_t known_channels{0};      // channels of the current file when `wanted` was made
  std::vector<std::uint8_t> message;  // the selected message expanded (per-message compression)
  std::uint64_t index{0};
  std::uint64_t other{0};
  bool started{false};
  std::string warnings;

  // Channels of the selected topic in readers[file_index]; checks their encoding.
  void select_channels() {
    wanted.clear();
    const McapReader& r = *readers[file_index];
    known_channels = r.channels().size();
    for (const auto& c : r.channels()) {
      if (c.topic != selected) continue;
      if (c.message_encoding != "cdr") {
        throw core::InputError(r.name() + ": topic " + selected + " is encoded as '" +
                               c.message_encoding + "', expected cdr");
      }
      wanted.insert(c.id);
    }
  }
};

McapBagReader::McapBagReader(const fs::path& path) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = path;
  if (is_folder(path)) {
    if (is_file(path / "metadata.yaml")) {
      Rosbag2Metadata metadata = read_rosbag2_metadata(path, "mcap");
      m.files = std::move(metadata.files);
      m.compression = metadata.compression;
    } else {
      m.files = mcap_files_in(path);
    }
    if (m.files.empty()) throw core::InputError(path.string() + ": no .mcap files in the folder");
  } else {
    m.files.push_back(path);
  }
  // Each listed "x.mcap.zstd" of a file-compressed bag is expanded to a temporary "x.mcap"
  // (removed with the reader); messages still name the listed file.
  if (m.compression == Rosbag2Compression::kFile) m.expanded.emplace("rosbag2-mcap");
  for (std::size_t i = 0; i < m.files.size(); ++i) {
    const fs::path& file = m.files[i];
    if (m.expanded) {
      // Numbered: listed paths may share a name in different folders.
      const fs::path storage =
          m.expanded->path() / (std::to_string(i) + "_" + file.stem().string());
      decompress_zstd_file(file, storage);
      m.readers.push_back(std::make_unique<McapReader>(storage, file.string()));
    } else {
      m.readers.push_back(std::make_unique<McapReader>(file));
    }
    const McapReader& r = *m.readers.back();
    for (const auto& c : r.channels()) {
      const McapSchema* schema = r.schema(c.schema_id);
      const std::string type = schema != nullptr ? schema->name : "";
      auto it = std::find_if(m.topics.begin(), m.topics.end(),
                             [&](const RosbagTopicInfo& t) { return t.name == c.topic; });
      if (it == m.topics.end()) {
        m.topics.push_back({c.topic, type, 0});
        it = m.topics.end() - 1;
      } else if (it->type != type) {
        throw core::InputError(file.string() + ": topic " + c.topic + " has type " + type +
                               " here but " + it->type + " elsewhere in the bag");
      }
      it->messages += r.message_count(c.id);
    }
  }
}

McapBagReader::~McapBagReader() = default;

const std::vector<RosbagTopicInfo>& McapBagReader::topics() const {
  return impl_->topics;
}

void McapBagReader::select_topic(const std::string& name) {
  Impl& m = *impl_;
  if (m.started) throw core::Error(m.path.string() + ": select_topic after reading began");
  if (std::none_of(m.topics.begin(), m.topics.end(),
                   [&](const RosbagTopicInfo& t) { return t.name == name; })) {
    throw core::ConfigError(m.path.string() + ": no topic '" + name + "'; the bag has " +
                            list_topics(m.topics));
  }
  m.selected = name;
}

bool McapBagReader::next(RosbagMessage& out) {
  Impl& m = *impl_;
  if (m.selected.empty()) throw core::Error(m.path.string() + ": no topic selected");
  if (!m.started) {
    m.started = true;
    m.select_channels();
  }
  McapMessage message;
  while (m.file_index < m.readers.size()) {
    McapReader& r = *m.readers[m.file_index];
    if (r.next(message)) {
      if (m.wanted.count(message.channel_id) == 0) {
        // Channels can appear mid-file (files without summary): look again when new ones came.
        if (r.channels().size() != m.known_channels) m.select_channels();
        if (m.wanted.count(message.channel_id) == 0) {
          ++m.other;
          continue;
        }
      }
      out.stamp_ns = static_cast<std::int64_t>(message.log_time_ns);
      out.index = ++m.index;
      if (m.compression == Rosbag2Compression::kMessage) {
        decompress_zstd_message(
            message.data, m.message,
            r.name() + ": message " + std::to_string(out.index) + " of " + m.selected);
        out.data = m.message;
      } else {
        out.data = message.data;
      }
      return true;
    }
    if (!r.warning().empty()) m.warnings += (m.warnings.empty() ? "" : "; ") + r.warning();
    if (++m.file_index < m.readers.size()) m.select_channels();
  }
  return false;
}

std::uint64_t McapBagReader::other_messages() const {
  return impl_->other;
}

const fs::path& McapBagReader::path() const {
  return impl_->path;
}

const fs::path& McapBagReader::current_file() const {
  const Impl& m = *impl_;
  return m.files[std::min(m.file_index, m.files.size() - 1)];
}

std::string McapBagReader::warning() const {
  return impl_->warnings;
}

const std::vector<fs::path>& McapBagReader::files() const {
  return impl_->files;
}

}  // namespace ringtrack::io
