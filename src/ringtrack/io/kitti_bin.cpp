#include "ringtrack/io/kitti_bin.hpp"

#include <cstring>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/output_file.hpp"
#include "ringtrack/io/text.hpp"

namespace ringtrack::io {

core::UnorganizedCloud decode_kitti_bin(std::span<const std::uint8_t> bytes,
                                        const std::string& name) {
  const std::size_t whole = bytes.size() / kKittiBinPointBytes;
  if (bytes.size() % kKittiBinPointBytes != 0) {
    const std::size_t offset = whole * kKittiBinPointBytes;
    throw core::InputError(name + ": " + std::to_string(bytes.size()) +
                           " bytes is not a multiple of 16 (x y z intensity as float32): the "
                           "point at offset " +
                           std::to_string(offset) + " is truncated (" +
                           std::to_string(bytes.size() - offset) + " of 16 bytes)");
  }
  core::UnorganizedCloud cloud;
  cloud.xyz.resize(whole);
  cloud.intensity.resize(whole);
  const std::uint8_t* p = bytes.data();
  for (std::size_t i = 0; i < whole; ++i, p += kKittiBinPointBytes) {
    float v[4];
    std::memcpy(v, p, sizeof v);  // little-endian host (checked at build: x86-64 / arm64)
    cloud.xyz[i] = Eigen::Vector3f(v[0], v[1], v[2]);
    cloud.intensity[i] = v[3];
  }
  return cloud;
}

core::UnorganizedCloud read_kitti_bin(const std::filesystem::path& path) {
  const auto bytes = read_file_bytes(path);
  return decode_kitti_bin(bytes, path.string());
}

std::string encode_kitti_bin(const core::UnorganizedCloud& cloud) {
  if (!cloud.intensity.empty() && cloud.intensity.size() != cloud.size()) {
    throw core::Error("encode_kitti_bin: " + std::to_string(cloud.intensity.size()) +
                      " intensities for " + std::to_string(cloud.size()) + " points");
  }
  std::string out(cloud.size() * kKittiBinPointBytes, '\0');
  char* p = out.data();
  for (std::size_t i = 0; i < cloud.size(); ++i, p += kKittiBinPointBytes) {
    const float v[4] = {cloud.xyz[i].x(), cloud.xyz[i].y(), cloud.xyz[i].z(),
                        cloud.intensity.empty() ? 0.0f : cloud.intensity[i]};
    std::memcpy(p, v, sizeof v);
  }
  return out;
}

void write_kitti_bin(const std::filesystem::path& path, const core::UnorganizedCloud& cloud) {
  write_file(path, encode_kitti_bin(cloud));
}

}  // namespace ringtrack::io
