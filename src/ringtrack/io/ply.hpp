#pragma once
/// PLY point-cloud writer (x y z intensity), for the static map.

#include <Eigen/Core>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

namespace ringtrack::io {

/// How write_ply stores the vertices.
enum class PlyEncoding {
  kBinaryLittleEndian,  ///< "format binary_little_endian 1.0": 16 bytes per point
  kAscii,               ///< "format ascii 1.0": one line per point
};

/// The header encode_ply writes for n points (ending with "end_header\n"); throws core::Error for
/// a comment of more than one line.
std::string ply_header(std::size_t n, PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian,
                       std::string_view comment = {});

/// Encodes points as a PLY file with one vertex element of float properties x y z intensity.
/// intensities must be empty (all 0) or hold one value per point; throws core::Error otherwise.
/// A non-empty comment (one line, e.g. the frame's origin) becomes a header comment line.
std::string encode_ply(std::span<const Eigen::Vector3f> points, std::span<const float> intensities,
                       PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian,
                       std::string_view comment = {});

/// Writes encode_ply's bytes to a file; I/O failures throw core::Error and remove the partial file.
void write_ply(const std::filesystem::path& path, std::span<const Eigen::Vector3f> points,
               std::span<const float> intensities,
               PlyEncoding encoding = PlyEncoding::kBinaryLittleEndian,
               std::string_view comment = {});

}  // namespace ringtrack::io
