#include "ringtrack/io/mcap_bag_reader.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <set>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/paths.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

// The storage a rosbag2 metadata.yaml names ("sqlite3" when it names none: the old default).
std::string metadata_storage(const fs::path& metadata) {
  try {
    const YAML::Node info = YAML::LoadFile(metadata.string())["rosbag2_bagfile_information"];
    if (!info || !info.IsMap()) return "";
    return info["storage_identifier"].as<std::string>("sqlite3");
  } catch (const YAML::Exception&) {
    return "";  // the sqlite3 reader reports the malformed file
  }
}

// The .mcap files a bag folder's metadata.yaml lists; compressed bags are rejected.
std::vector<fs::path> files_from_metadata(const fs::path& folder) {
  const fs::path metadata = folder / "metadata.yaml";
  const std::string name = metadata.string();
  try {
    const YAML::Node info = YAML::LoadFile(name)["rosbag2_bagfile_information"];
    if (!info || !info.IsMap()) {
      throw core::InputError(name + ": expected a rosbag2_bagfile_information map");
    }
    const std::string compression = info["compression_format"].as<std::string>("");
    if (!compression.empty()) {
      throw core::InputError(name + ": bags compressed by rosbag2 (" + compression +
                             ", per file or per message) are not supported; decompress with `ros2 "
                             "bag convert` (MCAP chunk compression is supported)");
    }
    const YAML::Node paths = info["relative_file_paths"];
    if (!paths || !paths.IsSequence() || paths.size() == 0) {
      throw core::InputError(name + ": expected relative_file_paths to list the .mcap files");
    }
    std::vector<fs::path> files;
    for (const auto& node : paths) {
      const fs::path file = folder / node.as<std::string>();
      if (!is_file(file)) {
        throw core::InputError(name + ": lists " + node.as<std::string>() + ", which is missing");
      }
      files.push_back(file);
    }
    return files;
  } catch (const YAML::Exception& e) {
    throw core::InputError(name + ": not valid rosbag2 metadata (" + e.what() + ")");
  }
}

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
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    if (fs::exists(path / "metadata.yaml", ec))
      return metadata_storage(path / "metadata.yaml") == "mcap";
    return !mcap_files_in(path).empty();
  }
  return is_mcap_file(path);
}

struct McapBagReader::Impl {
  fs::path path;
  std::vector<fs::path> files;
  std::vector<std::unique_ptr<McapReader>> readers;
  std::vector<RosbagTopicInfo> topics;
  std::string selected;
  std::size_t file_index{0};
  std::set<std::uint16_t> wanted;  // channel ids of the selected topic in the current file
  std::size_t known_channels{0};   // channels of the current file when `wanted` was made
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
    m.files = is_file(path / "metadata.yaml") ? files_from_metadata(path) : mcap_files_in(path);
    if (m.files.empty()) throw core::InputError(path.string() + ": no .mcap files in the folder");
  } else {
    m.files.push_back(path);
  }
  for (const auto& file : m.files) {
    m.readers.push_back(std::make_unique<McapReader>(file));
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
      out.data = message.data;
      out.index = ++m.index;
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
