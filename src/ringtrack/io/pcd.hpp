#pragma once
/// PCD (Point Cloud Data v0.7) files as organized scans: ascii, binary and binary_compressed.

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "ringtrack/core/cloud_organizer.hpp"
#include "ringtrack/core/organized_scan.hpp"

namespace ringtrack::io {

/// How a PCD file stores its point records (the DATA line).
enum class PcdEncoding {
  kAscii,             ///< one text line per point
  kBinary,            ///< packed records, point after point
  kBinaryCompressed,  ///< LZF-compressed, field after field (all x, then all y, ...)
};

/// One field of a PCD header.
struct PcdField {
  std::string name;       ///< as in FIELDS
  char type{'F'};         ///< 'F' floating point, 'U' unsigned, 'I' signed integer
  int size{4};            ///< bytes per element: F 4|8, U/I 1|2|4|8
  int count{1};           ///< elements per point
  std::size_t offset{0};  ///< byte offset of the field within a binary point record
  /// Bytes per point (size * count).
  [[nodiscard]] std::size_t bytes() const { return static_cast<std::size_t>(size) * count; }
};

/// A parsed PCD header.
struct PcdHeader {
  std::vector<PcdField> fields;                ///< in FIELDS order
  std::size_t width{0};                        ///< columns (organized) or points (HEIGHT 1)
  std::size_t height{0};                       ///< rings; 1 = unorganized
  PcdEncoding encoding{PcdEncoding::kBinary};  ///< the DATA line
  std::size_t data_offset{0};   ///< file offset of the first byte after the DATA line
  std::size_t header_lines{0};  ///< lines up to and including DATA (for ascii line numbers)

  /// Points in the file (width * height).
  [[nodiscard]] std::size_t points() const { return width * height; }
  /// Bytes of one binary point record.
  [[nodiscard]] std::size_t point_bytes() const;
  /// The field with this name, or nullptr.
  [[nodiscard]] const PcdField* find(std::string_view name) const;
};

/// Which file row holds the bottom ring of an organized cloud.
enum class PcdRowOrder {
  kAuto,         ///< bottom first, unless the first row's points lie higher than the last row's
  kBottomFirst,  ///< row 0 = bottom ring (what write_pcd writes)
  kTopFirst,     ///< row 0 = top ring (image-like clouds of some drivers)
};

/// Options of read_pcd.
struct PcdReadOptions {
  PcdRowOrder row_order{PcdRowOrder::kAuto};  ///< which row is the bottom ring
  /// When > 0, an unorganized cloud (HEIGHT 1) with a ring field is organized by ring and azimuth
  /// into this many columns instead of being rejected.
  int organize_columns{0};
  /// Rings when organizing; 0 = largest ring value + 1.
  int organize_rings{0};
  /// Name of the ring field used when organizing ("ring" in velodyne_pointcloud clouds).
  std::string ring_field{"ring"};
};

/// An organized scan read from a PCD file, with its optional labels.
struct PcdScan {
  core::OrganizedScan scan;           ///< stamp 0, column stamps 0, azimuths from the points
  std::vector<std::uint32_t> labels;  ///< per cell (ring-major) from the `label` field, or empty
  bool rows_flipped{false};           ///< the file stored the top ring first
  std::size_t dropped_points{0};  ///< organizing only: points that lost their cell to a nearer one
};

/// Parses the header of PCD bytes; `name` (the file name) prefixes every error message.
PcdHeader parse_pcd_header(std::span<const std::uint8_t> bytes, const std::string& name);
/// Decodes PCD bytes into an organized scan; throws core::InputError naming `name` and what was
/// expected on malformed, truncated or unorganized input.
PcdScan decode_pcd(std::span<const std::uint8_t> bytes, const std::string& name,
                   const PcdReadOptions& options = {});
/// The points of PCD bytes as an unorganized cloud (x y z, intensity when present; every point of
/// every row, in file order), for clouds without rings; throws core::InputError like decode_pcd.
core::UnorganizedCloud decode_pcd_cloud(std::span<const std::uint8_t> bytes,
                                        const std::string& name);
/// True for a cloud that only core::CloudOrganizer can organize: HEIGHT 1 and no ring field.
bool pcd_needs_organizer(const PcdHeader& header, const std::string& ring_field);
/// Reads a PCD file into an organized scan (see decode_pcd).
PcdScan read_pcd(const std::filesystem::path& path, const PcdReadOptions& options = {});

/// Encodes an organized scan as PCD with fields x y z intensity (F4) and, when labels is not
/// empty, label (U4); row 0 = bottom ring, invalid cells as NaN x y z and intensity 0.
std::string encode_pcd(const core::OrganizedScan& scan, std::span<const std::uint32_t> labels,
                       PcdEncoding encoding);
/// Writes encode_pcd's bytes to a file; I/O failures throw core::Error and remove the partial file.
void write_pcd(const std::filesystem::path& path, const core::OrganizedScan& scan,
               std::span<const std::uint32_t> labels,
               PcdEncoding encoding = PcdEncoding::kBinaryCompressed);

/// The header encode_pcd_points writes for n points (ending with the DATA line); throws
/// core::Error for a comment of more than one line.
std::string pcd_points_header(std::size_t n, PcdEncoding encoding, std::string_view comment = {});

/// Encodes an unorganized cloud (WIDTH = points, HEIGHT 1) with fields x y z intensity (F4), e.g.
/// the static map; intensities empty (all 0) or one per point, else core::Error. A non-empty
/// comment (one line, e.g. the frame's origin) becomes a "# " line after the first.
std::string encode_pcd_points(std::span<const Eigen::Vector3f> points,
                              std::span<const float> intensities, PcdEncoding encoding,
                              std::string_view comment = {});
/// Writes encode_pcd_points' bytes to a file; I/O failures throw core::Error and remove the
/// partial file.
void write_pcd_points(const std::filesystem::path& path, std::span<const Eigen::Vector3f> points,
                      std::span<const float> intensities,
                      PcdEncoding encoding = PcdEncoding::kBinaryCompressed,
                      std::string_view comment = {});

/// Sets each column's azimuth to the circular mean azimuth of its valid points; columns without
/// points are interpolated from their neighbours (uniform 2*pi/columns steps when none has points).
void estimate_column_azimuths(core::OrganizedScan& scan);

/// Name of an encoding as written on the DATA line ("ascii", "binary", "binary_compressed").
std::string_view to_string(PcdEncoding encoding);

}  // namespace ringtrack::io
