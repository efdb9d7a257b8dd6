#include "ringtrack/io/output_file.hpp"

#include <cerrno>
#include <cstring>
#include <string>
#include <system_error>

#include "ringtrack/core/error.hpp"

namespace ringtrack::io {

OutputFile::OutputFile(std::filesystem::path path) : path_(std::move(path)) {
  errno = 0;
  file_ = std::fopen(path_.c_str(), "wb");
  if (file_ == nullptr) {
    const int e = errno;
    throw core::Error(path_.string() + ": cannot create file: " + std::strerror(e));
  }
  // A large buffer keeps the many small writes of CSV rows and PCD records cheap.
  std::setvbuf(file_, nullptr, _IOFBF, std::size_t{1} << 18);
}

OutputFile::~OutputFile() {
  if (file_ != nullptr) std::fclose(file_);
}

void OutputFile::fail(const char* what, int error_number) {
  std::string reason = error_number != 0 ? std::strerror(error_number) : "unknown error";
  throw core::Error(path_.string() + ": " + what + " failed: " + reason);
}

void OutputFile::write(const void* data, std::size_t size) {
  if (file_ == nullptr) throw core::Error(path_.string() + ": write after close");
  if (size == 0) return;
  errno = 0;
  if (std::fwrite(data, 1, size, file_) != size) fail("write", errno);
}

void OutputFile::flush() {
  if (file_ == nullptr) return;
  errno = 0;
  if (std::fflush(file_) != 0) fail("write", errno);
}

void OutputFile::close() {
  if (file_ == nullptr) return;
  errno = 0;
  const bool flushed = std::fflush(file_) == 0;
  const int flush_errno = errno;
  errno = 0;
  const bool closed = std::fclose(file_) == 0;
  const int close_errno = errno;
  file_ = nullptr;
  if (!flushed) fail("write", flush_errno);
  if (!closed) fail("close", close_errno);
}

void OutputFile::discard() noexcept {
  if (file_ != nullptr) {
    std::fclose(file_);
    file_ = nullptr;
  }
  std::error_code ec;
  // Only regular files: never unlink a device such as /dev/null that the caller wrote to.
  if (std::filesystem::is_regular_file(path_, ec)) std::filesystem::remove(path_, ec);
}

void write_file(const std::filesystem::path& path, std::string_view bytes) {
  OutputFile file(path);
  try {
    file.write(bytes);
    file.close();
  } catch (...) {
    file.discard();
    throw;
  }
}

}  // namespace ringtrack::io
