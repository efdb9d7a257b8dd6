#pragma once
// Filesystem checks that answer "no" instead of throwing. Paths named by outside data (the files
// a bag's metadata.yaml lists) may be ones the system rejects, too long or a loop of links; that
// is bad input to report with the reader's own message, not a std::filesystem_error.
#include <filesystem>
#include <system_error>

namespace ringtrack::io {

inline bool is_file(const std::filesystem::path& path) {
  std::error_code ec;
  return std::filesystem::is_regular_file(path, ec);
}

inline bool is_folder(const std::filesystem::path& path) {
  std::error_code ec;
  return std::filesystem::is_directory(path, ec);
}

}  // namespace ringtrack::io
