#include "ringtrack/sensors/ouster/ouster_decoder.hpp"

#include <cmath>
#include <limits>
#include <numbers>

#include "ringtrack/core/error.hpp"

namespace ringtrack::sensors::ouster {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

std::uint16_t le16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}

std::uint32_t le32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}

std::uint64_t le64(const std::uint8_t* p) {
  return static_cast<std::uint64_t>(le32(p)) | (static_cast<std::uint64_t>(le32(p + 4)) << 32);
}

// Offset of a column's block within a packet, and of its first pixel.
std::size_t column_offset(const OusterMetadata& m, int column) {
  const std::size_t pixels = static_cast<std::size_t>(m.pixels_per_column) * m.pixel_bytes();
  if (m.profile == OusterProfile::kLegacy)
    return static_cast<std::size_t>(column) * (16 + pixels + 4);
  return 32 + static_cast<std::size_t>(column) * (12 + pixels);
}

std::size_t first_pixel(const OusterMetadata& m) {
  return m.profile == OusterProfile::kLegacy ? 16 : 12;
}

// Reads one pixel of the profile at q.
inline void read_pixel(const std::uint8_t* q, OusterProfile profile, OusterPixel& px) {
  switch (profile) {
    case OusterProfile::kLegacy:  // range 20 bits (mm), reflectivity u16, signal, NIR, unused
      px.range_mm = le32(q) & 0xFFFFFu;
      px.reflectivity = le16(q + 4);
      break;
    case OusterProfile::kRng19Rfl8Sig16Nir16:  // range 19 bits, reflectivity u8, signal, NIR
      px.range_mm = le32(q) & 0x7FFFFu;
      px.reflectivity = q[4];
      break;
    case OusterProfile::kRng19Rfl8Sig16Nir16Dual:  // (range 19 bits, reflectivity in bits 24..31)
                                                   // x 2, signal x 2, NIR
      px.range_mm = le32(q) & 0x7FFFFu;
      px.reflectivity = q[3];
      px.range2_mm = le32(q + 4) & 0x7FFFFu;
      break;
    case OusterProfile::kRng15Rfl8Nir8:  // range 15 bits in 8 mm units, reflectivity u8, NIR u8
      px.range_mm = (le16(q) & 0x7FFFu) * 8u;
      px.reflectivity = q[2];
      break;
  }
}

}  // namespace

OusterPixel ouster_pixel(std::span<const std::uint8_t> packet, const OusterMetadata& metadata,
                         int column, int beam) {
  const std::uint8_t* p = packet.data() + column_offset(metadata, column) + first_pixel(metadata) +
                          static_cast<std::size_t>(beam) * metadata.pixel_bytes();
  OusterPixel px;
  read_pixel(p, metadata.profile, px);
  return px;
}

OusterDecoder::OusterDecoder(OusterMetadata metadata, OusterDecoderOptions options)
    : metadata_(std::move(metadata)), options_(options), model_(ouster_sensor_model(metadata_)) {
  const auto beams = static_cast<std::size_t>(metadata_.pixels_per_column);
  ring_of_beam_.resize(beams);
  cos_alt_.resize(beams);
  sin_alt_.resize(beams);
  cos_beam_az_.resize(beams);
  sin_beam_az_.resize(beams);
  for (std::size_t b = 0; b < beams; ++b) {
    ring_of_beam_[b] = model_.ring_of_laser(static_cast<int>(b));
    const double alt = kTwoPi * metadata_.beam_altitude_deg[b] / 360.0;
    const double az = -kTwoPi * metadata_.beam_azimuth_deg[b] / 360.0;
    cos_alt_[b] = std::cos(alt);
    sin_alt_[b] = std::sin(alt);
    cos_beam_az_[b] = std::cos(az);
    sin_beam_az_[b] = std::sin(az);
  }
  const int w = metadata_.columns_per_frame;
  cos_enc_.resize(static_cast<std::size_t>(w));
  sin_enc_.resize(static_cast<std::size_t>(w));
  for (int m = 0; m < w; ++m) {
    const double enc = kTwoPi * (1.0 - static_cast<double>(m) / w);
    cos_enc_[static_cast<std::size_t>(m)] = std::cos(enc);
    sin_enc_[static_cast<std::size_t>(m)] = std::sin(enc);
  }
  const auto& t = metadata_.lidar_to_sensor;
  rotation_ = {t[0], t[1], t[2], t[4], t[5], t[6], t[8], t[9], t[10]};
  translation_mm_ = {t[3], t[7], t[11]};
  yaw_rad_ = std::atan2(t[4], t[0]);
  build_point_table();
  const auto pixels = static_cast<std::size_t>(metadata_.columns_per_packet) * beams;
  pixel_range_mm_.resize(pixels);
  pixel_reflectivity_.resize(pixels);
  packet_columns_.reserve(static_cast<std::size_t>(metadata_.columns_per_packet));
}

void OusterDecoder::build_point_table() {
  // The point is linear in the range: p = range * direction + offset (the formula of point()
  // with the transform folded in), so decoding a pixel is 3 multiply-adds instead of the
  // formula's trigonometry and rotation.
  const int w = metadata_.columns_per_frame;
  const int beams = metadata_.pixels_per_column;
  point_table_.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(beams));
  for (int b = 0; b < beams; ++b) {
    for (int m = 0; m < w; ++m) {
      const Eigen::Vector3d at0 = point(b, m, 0.0);
      const Eigen::Vector3d at1 = point(b, m, 1000.0);  // 1 m
      auto& k = point_table_[static_cast<std::size_t>(b) * static_cast<std::size_t>(w) +
                             static_cast<std::size_t>(m)];
      k.direction = (at1 - at0).cast<float>();
      k.offset = at0.cast<float>();
      // The fast kernel writes points without set_return's finiteness test; a metadata value
      // that overflows a float would otherwise put an infinite point into a valid cell.
      if (!k.direction.allFinite() || !k.offset.allFinite()) {
        throw core::InputError(metadata_.source + ": beam " + std::to_string(b) +
                               " gives a non-finite point direction (beam angles, origin offset "
                               "or lidar_to_sensor_transform out of range)");
      }
    }
  }
}

Eigen::Vector3d OusterDecoder::point(int beam, int measurement_id, double range_mm) const {
  const auto b = static_cast<std::size_t>(beam);
  const auto m = static_cast<std::size_t>(measurement_id);
  const double n = metadata_.origin_to_beam_mm;
  const double r = range_mm - n;
  // cos/sin(encoder + beam azimuth) by the angle-addition formulas.
  const double c = cos_enc_[m] * cos_beam_az_[b] - sin_enc_[m] * sin_beam_az_[b];
  const double s = sin_enc_[m] * cos_beam_az_[b] + cos_enc_[m] * sin_beam_az_[b];
  const double x = r * c * cos_alt_[b] + n * cos_enc_[m];
  const double y = r * s * cos_alt_[b] + n * sin_enc_[m];
  const double z = r * sin_alt_[b];
  const auto& R = rotation_;
  return Eigen::Vector3d(R[0] * x + R[1] * y + R[2] * z + translation_mm_[0],
                         R[3] * x + R[4] * y + R[5] * z + translation_mm_[1],
                         R[6] * x + R[7] * y + R[8] * z + translation_mm_[2]) *
         1e-3;
}

void OusterDecoder::start_frame(int frame_id) {
  if (spare_ && spare_->rings() == model_.rings() && spare_->columns() == model_.columns()) {
    scan_ = std::move(spare_);
    spare_.reset();
    // The fast kernel writes every cell of the frame once (write_row, clear_unseen_columns), so
    // the 2.7 MB of an OS1-128 scan are not written twice; the naive kernel needs a clean scan.
    if (options_.reference_kernel) scan_->reset();
  } else {
    scan_.emplace(model_.rings(), model_.columns());
  }
  stamps_.assign(static_cast<std::size_t>(metadata_.columns_per_frame), 0);
  seen_.assign(static_cast<std::size_t>(metadata_.columns_per_frame), 0);
  frame_id_ = frame_id;
}

void OusterDecoder::add_packet(std::span<const std::uint8_t> payload, std::int64_t) {
  ++stats_.packets;
  if (payload.size() != metadata_.packet_bytes()) {
    if (stats_.decoded_packets == 0) {
      throw core::InputError("ouster packet " + std::to_string(stats_.packets) + ": " +
                             std::to_string(payload.size()) + " bytes, but the metadata (" +
                             metadata_.source + ") describes " + to_string(metadata_.profile) +
                             " packets of " + std::to_string(metadata_.columns_per_packet) +
                             " columns x " + std::to_string(metadata_.pixels_per_column) +
                             " pixels = " + std::to_string(metadata_.packet_bytes()) +
                             " bytes (metadata of another sensor?)");
    }
    ++stats_.wrong_size;
    return;
  }
  const std::uint8_t* p = payload.data();
  const bool legacy = metadata_.profile == OusterProfile::kLegacy;
  const int frame_id = legacy ? le16(p + 10) : le16(p + 2);
  if (scan_ && frame_id != frame_id_) finish_frame();
  if (!scan_) start_frame(frame_id);
  // The column headers first (stamps, validity), then the pixels row by row: a beam's pixels of
  // the packet's columns go to neighbouring cells of one ring, where a column at a time would
  // write each pixel to another ring's row (128 scattered cache lines per column).
  const int w = metadata_.columns_per_frame;
  const std::size_t pixels =
      static_cast<std::size_t>(metadata_.pixels_per_column) * metadata_.pixel_bytes();
  packet_columns_.clear();
  for (int col = 0; col < metadata_.columns_per_packet; ++col) {
    const std::size_t offset = column_offset(metadata_, col);
    const std::uint8_t* block = p + offset;
    const auto stamp = static_cast<std::int64_t>(le64(block));
    const int m = le16(block + 8);
    const bool valid =
        legacy ? le32(block + 16 + pixels) == 0xFFFFFFFFu : (le16(block + 10) & 1) != 0;
    if (!valid) {
      ++stats_.invalid_columns;
      continue;
    }
    if (m >= w) {
      ++stats_.bad_measurement_id;
      continue;
    }
    const bool first = seen_[static_cast<std::size_t>(m)] == 0;
    seen_[static_cast<std::size_t>(m)] = 1;
    stamps_[static_cast<std::size_t>(m)] = stamp;
    packet_columns_.push_back({offset, m, first});
  }
  decode_pixels(p);
  ++stats_.decoded_packets;
}

void OusterDecoder::decode_pixels(const std::uint8_t* packet) {
  const std::span<const PacketColumn> columns(packet_columns_);
  if (options_.reference_kernel) {
    decode_reference(packet, columns);
    return;
  }
  switch (metadata_.profile) {  // one loop per profile: the pixel layout known at compile time
    case OusterProfile::kLegacy:
      decode_rows<OusterProfile::kLegacy>(packet, columns);
      break;
    case OusterProfile::kRng19Rfl8Sig16Nir16:
      decode_rows<OusterProfile::kRng19Rfl8Sig16Nir16>(packet, columns);
      break;
    case OusterProfile::kRng19Rfl8Sig16Nir16Dual:
      decode_rows<OusterProfile::kRng19Rfl8Sig16Nir16Dual>(packet, columns);
      break;
    case OusterProfile::kRng15Rfl8Nir8:
      decode_rows<OusterProfile::kRng15Rfl8Nir8>(packet, columns);
      break;
  }
}

// The naive kernel: pixel by pixel, column by column, through set_return / set_invalid.
void OusterDecoder::decode_reference(const std::uint8_t* packet,
                                     std::span<const PacketColumn> columns) {
  core::OrganizedScan& scan = *scan_;
  const int w = metadata_.columns_per_frame;
  const int beams = metadata_.pixels_per_column;
  const auto min_range = static_cast<float>(model_.min_range_m);
  const auto max_range = static_cast<float>(model_.max_range_m);
  const std::size_t stride = metadata_.pixel_bytes();
  for (const PacketColumn& column : columns) {
    const std::uint8_t* q = packet + column.offset + first_pixel(metadata_);
    for (int b = 0; b < beams; ++b, q += stride) {
      OusterPixel px;
      read_pixel(q, metadata_.profile, px);
      if (px.range_mm == 0) continue;
      // Destaggered: the beam's pixel moves by its shift so that a column holds one direction.
      int c = column.m + metadata_.pixel_shift_by_row[static_cast<std::size_t>(b)];
      if (c >= w) c -= w;
      const int ring = ring_of_beam_[static_cast<std::size_t>(b)];
      const float range = static_cast<float>(px.range_mm) * 1e-3f;
      if (range < min_range) {
        scan.set_invalid(ring, c, core::ReturnStatus::kTooClose);
        continue;
      }
      if (range > max_range) {
        scan.set_invalid(ring, c, core::ReturnStatus::kTooFar);
        continue;
      }
      const auto& k = point_table_[static_cast<std::size_t>(b) * static_cast<std::size_t>(w) +
                                   static_cast<std::size_t>(column.m)];
      scan.set_return(ring, c, range, static_cast<float>(px.reflectivity),
                      k.direction * range + k.offset);
    }
  }
}

// The fast kernel, in two passes. First the packet is read in its own order, column by column
// (a sequential stream the prefetcher follows), into a small beam-major buffer of ranges and
// reflectivities; then each beam's pixels go to neighbouring cells of its ring's row, where a
// column at a time would write every pixel to another ring's row (scattered cache lines), and
// reading the packet beam by beam would jump a column's size per pixel. Same arithmetic as
// decode_reference, so the same bits (test OusterKernels.FastKernelMatchesTheReferenceBitForBit);
// set_return's finiteness test is left out because the point table is checked finite and
// ranges are integers x 1e-3.
template <OusterProfile kProfile>
void OusterDecoder::decode_rows(const std::uint8_t* packet, std::span<const PacketColumn> columns) {
  const std::size_t n = columns.size();
  const int beams = metadata_.pixels_per_column;
  const std::size_t stride = metadata_.pixel_bytes();
  for (std::size_t j = 0; j < n; ++j) {
    const std::uint8_t* q = packet + columns[j].offset + first_pixel(metadata_);
    for (int b = 0; b < beams; ++b, q += stride) {
      OusterPixel px;
      read_pixel(q, kProfile, px);
      const std::size_t k = static_cast<std::size_t>(b) * n + j;
      pixel_range_mm_[k] = px.range_mm;
      pixel_reflectivity_[k] = px.reflectivity;
    }
  }
  for (int b = 0; b < beams; ++b) write_row(b, columns);
}

// Second pass of decode_rows: beam b's pixels of the packet's columns into its ring's row.
void OusterDecoder::write_row(int b, std::span<const PacketColumn> columns) {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  const core::OrganizedScan::CellArrays cells = scan_->cell_arrays();
  const int w = metadata_.columns_per_frame;
  const auto min_range = static_cast<float>(model_.min_range_m);
  const auto max_range = static_cast<float>(model_.max_range_m);
  const auto ub = static_cast<std::size_t>(b);
  const std::size_t row = static_cast<std::size_t>(ring_of_beam_[ub]) * static_cast<std::size_t>(w);
  const int shift = metadata_.pixel_shift_by_row[ub];
  const PointCoefficients* table = point_table_.data() + ub * static_cast<std::size_t>(w);
  const std::uint32_t* range_mm = pixel_range_mm_.data() + ub * columns.size();
  const std::uint16_t* reflectivity = pixel_reflectivity_.data() + ub * columns.size();
  const auto set_invalid = [&cells](std::size_t i, core::ReturnStatus why) {
    cells.range_m[i] = kNaN;
    cells.intensity[i] = 0.0f;
    cells.x[i] = cells.y[i] = cells.z[i] = kNaN;
    cells.status[i] = why;
  };
  for (std::size_t j = 0; j < columns.size(); ++j) {
    const int m = columns[j].m;
    int c = m + shift;
    if (c >= w) c -= w;
    const std::size_t i = row + static_cast<std::size_t>(c);
    if (range_mm[j] == 0) {
      // No echo: the scan was not reset, so the measurement id's first column clears the cell;
      // a repeated one keeps what came before, as the naive kernel does.
      if (columns[j].first) set_invalid(i, core::ReturnStatus::kNoReturn);
      continue;
    }
    const float range = static_cast<float>(range_mm[j]) * 1e-3f;
    if (range < min_range || range > max_range) {
      set_invalid(i,
                  range < min_range ? core::ReturnStatus::kTooClose : core::ReturnStatus::kTooFar);
      continue;
    }
    const PointCoefficients& k = table[m];
    const Eigen::Vector3f xyz = k.direction * range + k.offset;
    cells.range_m[i] = range;
    cells.intensity[i] = static_cast<float>(reflectivity[j]);
    cells.x[i] = xyz.x();
    cells.y[i] = xyz.y();
    cells.z[i] = xyz.z();
    cells.status[i] = core::ReturnStatus::kValid;
  }
}

// The fast kernel's scans are not reset: the cells of measurement ids that no packet of the
// frame brought (lost packets, the column window) become kNoReturn here.
void OusterDecoder::clear_unseen_columns() {
  constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
  const core::OrganizedScan::CellArrays cells = scan_->cell_arrays();
  const int w = metadata_.columns_per_frame;
  for (int m = 0; m < w; ++m) {
    if (seen_[static_cast<std::size_t>(m)] != 0) continue;
    for (int b = 0; b < metadata_.pixels_per_column; ++b) {
      const auto ub = static_cast<std::size_t>(b);
      int c = m + metadata_.pixel_shift_by_row[ub];
      if (c >= w) c -= w;
      const std::size_t i =
          static_cast<std::size_t>(ring_of_beam_[ub]) * static_cast<std::size_t>(w) +
          static_cast<std::size_t>(c);
      cells.range_m[i] = kNaN;
      cells.intensity[i] = 0.0f;
      cells.x[i] = cells.y[i] = cells.z[i] = kNaN;
      cells.status[i] = core::ReturnStatus::kNoReturn;
    }
  }
}

void OusterDecoder::finish_frame() {
  if (!scan_) return;
  const int w = metadata_.columns_per_frame;
  std::uint64_t missing = 0;
  for (int m = 0; m < w; ++m) {
    if (metadata_.in_window(m) && seen_[static_cast<std::size_t>(m)] == 0) ++missing;
  }
  if (missing > 0 && !options_.keep_partial_scans) {
    ++stats_.partial_scans_dropped;
    spare_ = std::move(scan_);  // its memory serves the next frame
    scan_.reset();
    return;
  }
  stats_.lost_columns += missing;
  core::OrganizedScan& scan = *scan_;
  // Column c of the destaggered scan: the direction of measurement c - shift of beam 0 (every
  // beam's shift brings it to about that azimuth), in the sensor frame (ringtrack's azimuths
  // are counter-clockwise from +x, as Ouster's). Its stamp: that of measurement c (rows with
  // another shift were measured up to shift / columns of a revolution apart).
  const int shift0 = metadata_.pixel_shift_by_row[0];
  const double beam0_az = -kTwoPi * metadata_.beam_azimuth_deg[0] / 360.0;
  const double period_ns = 1e9 / (metadata_.scan_rate_hz * w);
  if (!options_.reference_kernel) clear_unseen_columns();
  // A stamp for columns that were not received: continued from the nearest received one.
  int anchor = -1;
  for (int m = 0; m < w; ++m) {
    if (seen_[static_cast<std::size_t>(m)] != 0) {
      anchor = m;
      break;
    }
  }
  for (int c = 0; c < w; ++c) {
    const int m = ((c - shift0) % w + w) % w;
    double az = kTwoPi * (1.0 - static_cast<double>(m) / w) + beam0_az + yaw_rad_;
    az = std::fmod(az, kTwoPi);
    if (az < 0) az += kTwoPi;
    scan.column_azimuth_rad[static_cast<std::size_t>(c)] = az;
    if (seen_[static_cast<std::size_t>(c)] != 0) {
      scan.column_stamp_ns[static_cast<std::size_t>(c)] = stamps_[static_cast<std::size_t>(c)];
    } else if (anchor >= 0) {
      scan.column_stamp_ns[static_cast<std::size_t>(c)] =
          stamps_[static_cast<std::size_t>(anchor)] + std::llround((c - anchor) * period_ns);
    } else {
      scan.column_stamp_ns[static_cast<std::size_t>(c)] = 0;  // a recycled scan is not reset
    }
  }
  scan.stamp_ns = scan.column_stamp_ns[0];
  ready_.push_back(std::move(scan));
  ++stats_.scans;
  scan_.reset();
}

void OusterDecoder::finish() {
  finish_frame();
}

std::optional<core::OrganizedScan> OusterDecoder::pop_scan() {
  if (ready_.empty()) return std::nullopt;
  core::OrganizedScan scan = std::move(ready_.front());
  ready_.pop_front();
  return scan;
}

}  // namespace ringtrack::sensors::ouster
