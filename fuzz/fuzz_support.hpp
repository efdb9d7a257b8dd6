#pragma once
// Shared harness code of the libFuzzer targets: reading the input as a stream of size-led chunks,
// scratch files for readers that take paths, pcap framing, and the checks every target makes.
// Documented errors (core::Error) are expected; anything else (another exception, a crash, a
// sanitizer report, a hang, an allocation above -malloc_limit_mb) is a bug.

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/core/organized_scan.hpp"

namespace ringtrack::fuzz {

/// Runs `f`, accepting the documented errors (core::Error and its kinds).
template <class F>
void expect_errors(F&& f) {
  try {
    f();
  } catch (const core::Error&) {
  }
}

/// Runs `f`, an oracle step on data the code under test wrote itself (a round trip): any error
/// there is a bug, reported with its message.
template <class F>
void must_succeed(F&& f) {
  try {
    f();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "round trip failed: %s\n", e.what());
    __builtin_trap();
  }
}

/// Traps unless `condition` holds (an oracle's verdict).
inline void require(bool condition, const char* what) {
  if (!condition) {
    std::fprintf(stderr, "oracle failed: %s\n", what);
    __builtin_trap();
  }
}

/// The input as a byte stream: control bytes, length-prefixed text and size-led chunks.
class FuzzInput {
 public:
  FuzzInput(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  /// Bytes not read yet.
  [[nodiscard]] std::size_t remaining() const { return size_ - at_; }
  /// True when everything has been read.
  [[nodiscard]] bool done() const { return at_ >= size_; }
  /// The next byte (0 past the end).
  std::uint8_t byte() { return at_ < size_ ? data_[at_++] : 0; }
  /// A little-endian uint16 (missing bytes read as 0).
  std::uint16_t u16() { return static_cast<std::uint16_t>(byte() | byte() << 8); }
  /// The next `n` bytes (fewer at the end) as text.
  std::string text(std::size_t n) {
    const std::size_t take = std::min(n, remaining());
    std::string s(reinterpret_cast<const char*>(data_ + at_), take);
    at_ += take;
    return s;
  }
  /// The next `n` bytes into `out`, zero-padded to `n` when the input ends first.
  void chunk(std::size_t n, std::vector<std::uint8_t>& out) {
    const std::size_t take = std::min(n, remaining());
    out.assign(n, 0);
    // A zero-length vector has no buffer: memcpy from or to null is undefined even for 0 bytes.
    if (take > 0) std::memcpy(out.data(), data_ + at_, take);
    at_ += take;
  }
  /// Everything not read yet.
  std::span<const std::uint8_t> rest() {
    const std::span<const std::uint8_t> r(data_ + at_, remaining());
    at_ = size_;
    return r;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_{0};
};

/// Traps (a crash libFuzzer reports) when a scan's arrays disagree with its shape.
inline void check_scan(const core::OrganizedScan& scan) {
  if (scan.size() != static_cast<std::size_t>(scan.rings()) * scan.columns()) __builtin_trap();
}

/// Pops and checks every scan a decoder holds.
template <class Decoder>
void drain_decoder(Decoder& decoder) {
  while (auto scan = decoder.pop_scan()) check_scan(*scan);
}

/// Reads and checks every scan of a source.
template <class Source>
void drain_source(Source& source) {
  while (auto scan = source.next()) check_scan(*scan);
  (void)source.summary();
}

/// A folder of this process's own under the temporary directory, removed at exit: readers that
/// take paths read the input from files written here.
inline const std::filesystem::path& scratch_dir() {
  static const struct Scratch {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("ringtrack_fuzz_" + std::to_string(::getpid()));
    Scratch() { std::filesystem::create_directories(path); }
    ~Scratch() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  } scratch;
  return scratch.path;
}

/// Writes bytes to `name` in the scratch folder and returns its path.
inline std::filesystem::path write_scratch(const std::string& name,
                                           std::span<const std::uint8_t> bytes) {
  const std::filesystem::path path = scratch_dir() / name;
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  return path;
}

/// Same for text.
inline std::filesystem::path write_scratch(const std::string& name, std::string_view text) {
  return write_scratch(name,
                       std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()));
}

/// A classic pcap file header (version 2.4, snap length 65535) for a link type (1 Ethernet,
/// 113 Linux cooked, 101 raw IP, 276 SLL2), with micro- or nanosecond stamps.
inline std::vector<std::uint8_t> pcap_file_header(std::uint32_t link, bool nanoseconds) {
  const std::uint32_t magic = nanoseconds ? 0xA1B23C4D : 0xA1B2C3D4;
  const std::uint32_t header[6] = {magic, 0x00040002, 0, 0, 65535, link};
  const auto* h = reinterpret_cast<const std::uint8_t*>(header);
  return {h, h + sizeof header};
}

/// Appends a pcap record: an Ethernet/IPv4/UDP frame carrying `payload` to `port`.
inline void append_udp_record(std::vector<std::uint8_t>& file, std::uint32_t second,
                              std::uint16_t port, std::span<const std::uint8_t> payload) {
  const std::size_t n = payload.size();
  std::vector<std::uint8_t> frame(14 + 20 + 8 + n, 0);
  frame[12] = 0x08;  // IPv4
  frame[14] = 0x45;
  const std::size_t ip_len = 20 + 8 + n;
  frame[16] = static_cast<std::uint8_t>(ip_len >> 8);
  frame[17] = static_cast<std::uint8_t>(ip_len & 0xFF);
  frame[23] = 17;  // UDP
  frame[36] = static_cast<std::uint8_t>(port >> 8);
  frame[37] = static_cast<std::uint8_t>(port & 0xFF);
  frame[38] = static_cast<std::uint8_t>((8 + n) >> 8);
  frame[39] = static_cast<std::uint8_t>((8 + n) & 0xFF);
  std::copy(payload.begin(), payload.end(), frame.begin() + 42);
  const std::uint32_t record[4] = {second, 0, static_cast<std::uint32_t>(frame.size()),
                                   static_cast<std::uint32_t>(frame.size())};
  const auto* r = reinterpret_cast<const std::uint8_t*>(record);
  file.insert(file.end(), r, r + sizeof record);
  file.insert(file.end(), frame.begin(), frame.end());
}

}  // namespace ringtrack::fuzz
