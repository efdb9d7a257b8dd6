#include "ringtrack/io/rosbag2_metadata.hpp"

#include <yaml-cpp/yaml.h>
#include <zstd.h>

#include <algorithm>
#include <cctype>
#include <fstream>
#include <memory>
#include <random>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/paths.hpp"

namespace ringtrack::io {
namespace {

namespace fs = std::filesystem;

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

// compression_format and compression_mode. rosbag2 writes "" for both when it did not compress,
// "zstd" (its only built-in plugin) and "FILE" or "MESSAGE" when it did; a format without a
// mode is how bags before Galactic said FILE (their only mode).
Rosbag2Compression compression_of(const YAML::Node& info, const std::string& name) {
  const std::string format = info["compression_format"].as<std::string>("");
  const std::string mode = lower(info["compression_mode"].as<std::string>(""));
  if (format.empty() && (mode.empty() || mode == "none")) return Rosbag2Compression::kNone;
  if (lower(format) != "zstd") {
    throw core::InputError(name + ": compression_format '" + format +
                           "' is not supported, expected zstd (rosbag2's own) or none");
  }
  if (mode == "file" || mode.empty()) return Rosbag2Compression::kFile;
  if (mode == "message") return Rosbag2Compression::kMessage;
  throw core::InputError(name + ": compression_mode '" + mode + "' is unknown, expected FILE or " +
                         "MESSAGE");
}

std::vector<fs::path> listed_files(const YAML::Node& info, const fs::path& folder,
                                   const std::string& name) {
  const YAML::Node paths = info["relative_file_paths"];
  if (!paths || !paths.IsSequence() || paths.size() == 0) {
    throw core::InputError(name + ": expected relative_file_paths to list the bag's files");
  }
  std::vector<fs::path> files;
  for (const auto& node : paths) {
    const fs::path relative(node.as<std::string>());
    // rosbag2 before Foxy listed paths relative to the bag's parent folder.
    fs::path file = folder / relative;
    if (!is_file(file) && is_file(folder.parent_path() / relative)) {
      file = folder.parent_path() / relative;
    }
    if (!is_file(file)) {
      throw core::InputError(name + ": lists " + relative.string() + ", which is missing");
    }
    files.push_back(file);
  }
  return files;
}

struct DCtxFree {
  void operator()(ZSTD_DCtx* c) const { ZSTD_freeDCtx(c); }
};

// A frame header may claim any size, and a small frame can expand enormously: no message of a
// LiDAR bag comes near 1 GiB.
constexpr std::size_t kMaxMessageBytes = std::size_t{1} << 30;

}  // namespace

Rosbag2Metadata read_rosbag2_metadata(const fs::path& folder, const std::string& storage) {
  const std::string name = (folder / "metadata.yaml").string();
  YAML::Node info;
  try {
    info = YAML::LoadFile(name)["rosbag2_bagfile_information"];
  } catch (const YAML::Exception& e) {
    throw core::InputError(name + ": not valid YAML (" + e.what() + ")");
  }
  if (!info || !info.IsMap()) {
    throw core::InputError(name + ": expected a rosbag2_bagfile_information map");
  }
  try {
    Rosbag2Metadata out;
    out.storage = info["storage_identifier"].as<std::string>("sqlite3");
    if (out.storage != storage) {
      throw core::InputError(name + ": storage '" + out.storage +
                             "' is not supported by this reader, expected " + storage);
    }
    out.compression = compression_of(info, name);
    out.files = listed_files(info, folder, name);
    return out;
  } catch (const YAML::Exception& e) {
    throw core::InputError(name + ": unexpected value (" + e.what() + ")");
  }
}

std::string rosbag2_storage(const fs::path& metadata) {
  try {
    const YAML::Node info = YAML::LoadFile(metadata.string())["rosbag2_bagfile_information"];
    if (!info || !info.IsMap()) return "";
    return info["storage_identifier"].as<std::string>("sqlite3");
  } catch (const YAML::Exception&) {
    return "";
  }
}

TemporaryFolder::TemporaryFolder(const std::string& stem) {
  std::error_code ec;
  const fs::path base = fs::temp_directory_path(ec);
  if (ec) throw core::Error("no temporary directory: " + ec.message());
  std::random_device random;
  for (int attempt = 0; attempt < 16; ++attempt) {
    const fs::path candidate = base / ("ringtrack-" + stem + "-" + std::to_string(random()));
    if (fs::create_directory(candidate, ec)) {
      path_ = candidate;
      return;
    }
  }
  throw core::Error("cannot create a temporary folder in " + base.string() +
                    (ec ? ": " + ec.message() : ""));
}

TemporaryFolder::~TemporaryFolder() {
  std::error_code ec;
  fs::remove_all(path_, ec);  // best effort: a destructor must not throw
}

void decompress_zstd_file(const fs::path& compressed, const fs::path& out) {
  const std::string name = compressed.string();
  std::ifstream in(compressed, std::ios::binary);
  if (!in) throw core::InputError(name + ": cannot open");
  std::ofstream sink(out, std::ios::binary | std::ios::trunc);
  if (!sink) throw core::Error(out.string() + ": cannot write the expanded bag file");
  const std::unique_ptr<ZSTD_DCtx, DCtxFree> ctx(ZSTD_createDCtx());
  if (ctx == nullptr) throw core::Error(name + ": out of memory for zstd");
  std::vector<char> input(ZSTD_DStreamInSize());
  std::vector<char> output(ZSTD_DStreamOutSize());
  std::uint64_t offset = 0;   // bytes of the file consumed so far
  std::size_t remaining = 1;  // 0 once the last frame ended
  bool any = false;
  while (in.read(input.data(), static_cast<std::streamsize>(input.size())) || in.gcount() > 0) {
    ZSTD_inBuffer buffer{input.data(), static_cast<std::size_t>(in.gcount()), 0};
    any = true;
    while (buffer.pos < buffer.size) {
      ZSTD_outBuffer produced{output.data(), output.size(), 0};
      remaining = ZSTD_decompressStream(ctx.get(), &produced, &buffer);
      if (ZSTD_isError(remaining) != 0) {
        throw core::InputError(name + ": offset " + std::to_string(offset + buffer.pos) +
                               ": not a valid zstd stream (" + ZSTD_getErrorName(remaining) + ")");
      }
      sink.write(output.data(), static_cast<std::streamsize>(produced.pos));
    }
    offset += buffer.size;
  }
  // Flush what the last input left in the decoder's window.
  while (remaining != 0 && any) {
    ZSTD_inBuffer empty{nullptr, 0, 0};
    ZSTD_outBuffer produced{output.data(), output.size(), 0};
    remaining = ZSTD_decompressStream(ctx.get(), &produced, &empty);
    if (ZSTD_isError(remaining) != 0 || produced.pos == 0) break;
    sink.write(output.data(), static_cast<std::streamsize>(produced.pos));
  }
  if (!any) throw core::InputError(name + ": empty, expected a zstd stream");
  if (remaining != 0) {
    throw core::InputError(name + ": offset " + std::to_string(offset) +
                           ": the zstd stream ends inside a frame (file cut off?)");
  }
  sink.flush();
  if (!sink) throw core::Error(out.string() + ": cannot write the expanded bag file");
}

void decompress_zstd_message(std::span<const std::uint8_t> compressed,
                             std::vector<std::uint8_t>& out, const std::string& what) {
  const unsigned long long size = ZSTD_getFrameContentSize(compressed.data(), compressed.size());
  if (size == ZSTD_CONTENTSIZE_ERROR) {
    throw core::InputError(what + ": not a zstd frame");
  }
  // rosbag2's compressor records the size in the frame header; a frame without one is
  // streamed into a growing buffer.
  if (size != ZSTD_CONTENTSIZE_UNKNOWN) {
    if (size > kMaxMessageBytes) {
      throw core::InputError(what + ": the zstd frame claims " + std::to_string(size) +
                             " bytes, more than a message can hold");
    }
    out.resize(static_cast<std::size_t>(size));
    const std::size_t got =
        ZSTD_decompress(out.data(), out.size(), compressed.data(), compressed.size());
    if (ZSTD_isError(got) != 0 || got != out.size()) {
      throw core::InputError(what + ": corrupt zstd frame (" +
                             (ZSTD_isError(got) != 0 ? ZSTD_getErrorName(got) : "short") + ")");
    }
    return;
  }
  const std::unique_ptr<ZSTD_DCtx, DCtxFree> ctx(ZSTD_createDCtx());
  if (ctx == nullptr) throw core::Error(what + ": out of memory for zstd");
  out.clear();
  std::vector<std::uint8_t> chunk(ZSTD_DStreamOutSize());
  ZSTD_inBuffer input{compressed.data(), compressed.size(), 0};
  std::size_t remaining = 1;
  while (remaining != 0) {
    ZSTD_outBuffer produced{chunk.data(), chunk.size(), 0};
    remaining = ZSTD_decompressStream(ctx.get(), &produced, &input);
    if (ZSTD_isError(remaining) != 0) {
      throw core::InputError(what + ": corrupt zstd frame (" + ZSTD_getErrorName(remaining) + ")");
    }
    out.insert(out.end(), chunk.begin(), chunk.begin() + static_cast<std::ptrdiff_t>(produced.pos));
    if (out.size() > kMaxMessageBytes) {
      throw core::InputError(what + ": the zstd frame expands beyond " +
                             std::to_string(kMaxMessageBytes) + " bytes");
    }
    if (remaining != 0 && input.pos == input.size && produced.pos < produced.size) {
      throw core::InputError(what + ": the zstd frame ends early");
    }
  }
}

}  // namespace ringtrack::io
