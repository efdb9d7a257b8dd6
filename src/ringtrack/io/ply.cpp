#include "ringtrack/io/ply.hpp"

#include <bit>
#include <cstring>

#include "ringtrack/core/error.hpp"
#include "ringtrack/io/output_file.hpp"
#include "ringtrack/io/text.hpp"

namespace ringtrack::io {
namespace {

void append_le(std::string& out, float value) {
  auto bits = std::bit_cast<std::uint32_t>(value);
  char bytes[4];
  for (char& b : bytes) {
    b = static_cast<char>(bits & 0xffu);
    bits >>= 8;
  }
  out.append(bytes, 4);
}

}  // namespace

std::string ply_header(std::size_t n, PlyEncoding encoding, std::string_view comment) {
  if (comment.find_first_of("\r\n") != std::string_view::npos) {
    throw core::Error("encode_ply: a header comment must be one line");
  }
  const bool binary = encoding == PlyEncoding::kBinaryLittleEndian;
  std::string out = "ply\n";
  out += binary ? "format binary_little_endian 1.0\n" : "format ascii 1.0\n";
  out += "comment ringtrack\n";
  if (!comment.empty()) {
    out += "comment ";
    out += comment;
    out += '\n';
  }
  out += "element vertex " + std::to_string(n) +
         "\nproperty float x\nproperty float y\nproperty float z\nproperty float intensity\n"
         "end_header\n";
  return out;
}

std::string encode_ply(std::span<const Eigen::Vector3f> points, std::span<const float> intensities,
                       PlyEncoding encoding, std::string_view comment) {
  if (!intensities.empty() && intensities.size() != points.size()) {
    throw core::Error("encode_ply: " + std::to_string(intensities.size()) + " intensities for " +
                      std::to_string(points.size()) + " points");
  }
  const bool binary = encoding == PlyEncoding::kBinaryLittleEndian;
  std::string out = ply_header(points.size(), encoding, comment);
  out.reserve(out.size() + points.size() * (binary ? 16 : 48));
  for (std::size_t i = 0; i < points.size(); ++i) {
    const float intensity = intensities.empty() ? 0.0f : intensities[i];
    if (binary) {
      append_le(out, points[i].x());
      append_le(out, points[i].y());
      append_le(out, points[i].z());
      append_le(out, intensity);
    } else {
      append_shortest(out, points[i].x());
      out += ' ';
      append_shortest(out, points[i].y());
      out += ' ';
      append_shortest(out, points[i].z());
      out += ' ';
      append_shortest(out, intensity);
      out += '\n';
    }
  }
  return out;
}

void write_ply(const std::filesystem::path& path, std::span<const Eigen::Vector3f> points,
               std::span<const float> intensities, PlyEncoding encoding, std::string_view comment) {
  write_file(path, encode_ply(points, intensities, encoding, comment));
}

}  // namespace ringtrack::io
