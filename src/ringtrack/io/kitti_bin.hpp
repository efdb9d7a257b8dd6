#pragma once
/// KITTI-style point cloud files (.bin): x y z intensity as float32 little endian, 16 bytes per
/// point, no header (docs/formats.md). Read as unorganized clouds for core::CloudOrganizer.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

#include "ringtrack/core/cloud_organizer.hpp"

namespace ringtrack::io {

/// Bytes of one point record.
inline constexpr std::size_t kKittiBinPointBytes = 16;

/// Decodes .bin bytes into a cloud (stamp 0, no times); throws core::InputError naming `name`
/// and the offset of the incomplete record when the size is not a multiple of 16 bytes.
core::UnorganizedCloud decode_kitti_bin(std::span<const std::uint8_t> bytes,
                                        const std::string& name);
/// Reads a .bin file (see decode_kitti_bin).
core::UnorganizedCloud read_kitti_bin(const std::filesystem::path& path);
/// Encodes a cloud as .bin bytes (intensity 0 when the cloud has none; times are not stored).
std::string encode_kitti_bin(const core::UnorganizedCloud& cloud);
/// Writes encode_kitti_bin's bytes; I/O failures throw core::Error and remove the partial file.
void write_kitti_bin(const std::filesystem::path& path, const core::UnorganizedCloud& cloud);

}  // namespace ringtrack::io
