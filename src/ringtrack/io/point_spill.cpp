#include "ringtrack/io/point_spill.hpp"

#include <bit>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/pcd.hpp"
#include "ringtrack/io/ply.hpp"

namespace ringtrack::io {
namespace {

// PLY binary_little_endian and PCD binary both store a point as four floats in a row; on a
// little-endian host that is the bytes of the floats as they are in memory.
static_assert(std::endian::native == std::endian::little,
              "point_spill writes floats in host order as little-endian PLY");

constexpr std::size_t kPointBytes = 16;

void put(unsigned char* out, const Eigen::Vector3f& p, float intensity) {
  const float record[4] = {p.x(), p.y(), p.z(), intensity};
  std::memcpy(out, record, kPointBytes);
}

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

}  // namespace

PointSpill::PointSpill(std::filesystem::path scratch)
    : scratch_(std::move(scratch)), file_(scratch_) {}

PointSpill::~PointSpill() {
  file_.discard();
  std::error_code ec;
  std::filesystem::remove(scratch_, ec);
}

void PointSpill::append(const Eigen::Vector3f& position, float intensity) {
  unsigned char record[kPointBytes];
  put(record, position, intensity);
  file_.write(record, kPointBytes);
  ++size_;
}

void PointSpill::copy_into(OutputFile& out, std::span<const Eigen::Vector3f> points,
                           std::span<const float> intensities) const {
  errno = 0;
  const std::unique_ptr<std::FILE, FileCloser> in(std::fopen(scratch_.c_str(), "rb"));
  if (!in) {
    throw core::Error(scratch_.string() +
                      ": cannot read the map's spilled points: " + std::strerror(errno));
  }
  std::vector<unsigned char> block(kPointBytes << 14);
  std::uint64_t copied = 0;
  while (copied < size_) {
    const std::size_t want = static_cast<std::size_t>(
        std::min<std::uint64_t>(size_ - copied, block.size() / kPointBytes));
    if (std::fread(block.data(), kPointBytes, want, in.get()) != want) {
      throw core::Error(scratch_.string() + ": the map's spilled points end after " +
                        std::to_string(copied) + " of " + std::to_string(size_));
    }
    out.write(block.data(), want * kPointBytes);
    copied += want;
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    put(block.data(), points[i], intensities.empty() ? 0.0f : intensities[i]);
    out.write(block.data(), kPointBytes);
  }
}

void PointSpill::write(const std::filesystem::path& ply, const std::filesystem::path& pcd,
                       std::span<const Eigen::Vector3f> points, std::span<const float> intensities,
                       std::string_view comment) {
  if (!intensities.empty() && intensities.size() != points.size()) {
    throw core::Error("PointSpill: " + std::to_string(intensities.size()) + " intensities for " +
                      std::to_string(points.size()) + " points");
  }
  file_.close();
  const std::uint64_t n = size_ + points.size();
  for (const auto& [path, header] :
       {std::pair{ply, ply_header(n, PlyEncoding::kBinaryLittleEndian, comment)},
        std::pair{pcd, pcd.empty() ? std::string()
                                   : pcd_points_header(n, PcdEncoding::kBinary, comment)}}) {
    if (path.empty()) continue;
    OutputFile out(path);
    try {
      out.write(header);
      copy_into(out, points, intensities);
      out.close();
    } catch (...) {
      out.discard();
      throw;
    }
  }
  std::error_code ec;
  std::filesystem::remove(scratch_, ec);
}

}  // namespace ringtrack::io
