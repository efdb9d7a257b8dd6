#pragma once
/// A file written through stdio that reports every failure (open, write, flush, close) as an error.

#include <cstdio>
#include <filesystem>
#include <string_view>

namespace ringtrack::io {

/// Output file whose open, write, flush and close failures throw core::Error naming the path and
/// the system's reason (e.g. "No space left on device"). Buffered writes can fail late, so only a
/// successful close() means the data reached the file.
class OutputFile {
 public:
  /// Creates or truncates the file.
  explicit OutputFile(std::filesystem::path path);
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;
  /// Closes quietly if close() was not called (errors are lost: call close()).
  ~OutputFile();

  /// Appends bytes.
  void write(const void* data, std::size_t size);
  /// Appends text.
  void write(std::string_view text) { write(text.data(), text.size()); }
  /// Pushes buffered data to the operating system.
  void flush();
  /// Flushes and closes; the file is complete only when this returns.
  void close();
  /// Closes without reporting errors and deletes the file if it is a regular file, so that a
  /// half-written output is never left looking complete.
  void discard() noexcept;
  /// The path given at construction.
  [[nodiscard]] const std::filesystem::path& path() const { return path_; }
  /// True until close() or discard().
  [[nodiscard]] bool is_open() const { return file_ != nullptr; }

 private:
  [[noreturn]] void fail(const char* what, int error_number);

  std::filesystem::path path_;
  std::FILE* file_{nullptr};
};

/// Writes a whole file at once; on any failure the partial file is deleted and the error rethrown.
void write_file(const std::filesystem::path& path, std::string_view bytes);

}  // namespace ringtrack::io
