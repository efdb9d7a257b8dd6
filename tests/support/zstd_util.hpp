#pragma once
/// Test support: zstd compression with libzstd, the format's reference implementation (ringtrack
/// only decompresses), to build bags the way `ros2 bag record --compression-format zstd` does.

#include <zstd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <stdexcept>
#include <vector>

namespace ringtrack::test {

/// One zstd frame of data (level 3, content size in the header, as rosbag2's compressor writes).
inline std::vector<std::uint8_t> zstd_compress(std::span<const std::uint8_t> data) {
  std::vector<std::uint8_t> out(ZSTD_compressBound(data.size()));
  const std::size_t n = ZSTD_compress(out.data(), out.size(), data.data(), data.size(), 3);
  if (ZSTD_isError(n) != 0) throw std::runtime_error(ZSTD_getErrorName(n));
  out.resize(n);
  return out;
}

/// Writes file `in` compressed as `out` (one frame).
inline void zstd_compress_file(const std::filesystem::path& in, const std::filesystem::path& out) {
  std::ifstream f(in, std::ios::binary);
  const std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(f)),
                                       std::istreambuf_iterator<char>());
  const auto packed = zstd_compress(data);
  std::ofstream(out, std::ios::binary)
      .write(reinterpret_cast<const char*>(packed.data()),
             static_cast<std::streamsize>(packed.size()));
}

}  // namespace ringtrack::test
