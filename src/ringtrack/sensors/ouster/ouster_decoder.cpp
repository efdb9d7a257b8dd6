#include "ringtrack/sensors/ouster/ouster_decoder.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>

#include "ringtrack/core/error.hpp"

namespace ringtrack::sensors::ouster {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

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
      px.reflectivity2 = q[7];
      break;
    case OusterProfile::kRng15Rfl8Nir8:  // range 15 bits in 8 mm units, reflectivity u8, NIR u8
      px.range_mm = (le16(q) & 0x7FFFu) * 8u;
      px.reflectivity = q[2];
      break;
  }
}

// Moves the selected return of a _DUAL pixel into range_mm / reflectivity.
inline void select_return(OusterReturn selection, OusterPixel& px) {
  const bool second = selection == OusterReturn::kSecond ||
                      (selection == OusterReturn::kLast && px.range2_mm > px.range_mm);
  if (second) {
    px.range_mm = px.range2_mm;
    px.reflectivity = px.reflectivity2;
  }
}

}  // namespace

std::string to_string(OusterReturn selection) {
  switch (selection) {
    case OusterReturn::kStrongest:
      return "strongest";
    case OusterReturn::kSecond:
      return "second";
    case OusterReturn::kLast:
      return "last";
  }
  return "?";
}

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
  if (options_.return_selection != OusterReturn::kStrongest &&
      metadata_.profile != OusterProfile::kRng19Rfl8Sig16Nir16Dual) {
    throw core::InputError(metadata_.source + ": the " + to_string(options_.return_selection) +
                           " return needs the RNG19_RFL8_SIG16_NIR16_DUAL profile, but the " +
                           "sensor sends " + to_string(metadata_.profile) +
                           " (one return per pixel: the strongest)");
  }
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
  if (model_.columns() != w) {
    throw core::Error(metadata_.source + ": the sensor model has " +
                      std::to_string(model_.columns()) + " columns, the metadata " +
                      std::to_string(w));
  }
  shift_.resize(beams);
  cell0_.resize(beams);
  wrap_at_.resize(beams);
  for (std::size_t b = 0; b < beams; ++b) {
    shift_[b] = ((metadata_.pixel_shift_by_row[b] % w) + w) % w;
    cell0_[b] = static_cast<std::size_t>(ring_of_beam_[b]) * static_cast<std::size_t>(w) +
                static_cast<std::size_t>(shift_[b]);
    wrap_at_[b] = w - shift_[b];
  }
  // point() expanded. With a = cos(alt) cos(beam az), s = cos(alt) sin(beam az) and R's columns
  // r0, r1, r2, the lidar-frame direction (mm per mm of range) is
  // cos(enc) (a, s, 0) + sin(enc) (-s, a, 0) + (0, 0, sin(alt)), and the point, in metres,
  // R ((range - n) direction + (bx cos(enc), bx sin(enc), bz)) + t, which is
  // cos(enc) (range u + pu) + sin(enc) (range v + pv) + range w + pw with
  // u = a r0 + s r1, v = -s r0 + a r1, w = sin(alt) r2, pu = (bx r0 - n u) / 1000,
  // pv = (bx r1 - n v) / 1000, pw = (bz r2 + t - n w) / 1000 (range in metres).
  const Eigen::Matrix3d rot =
      Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(rotation_.data());
  const Eigen::Vector3d t_mm(translation_mm_[0], translation_mm_[1], translation_mm_[2]);
  const double n = metadata_.origin_to_beam_mm;
  bool bounded = true;
  factors_.resize(beams);
  const auto put = [&](float& x, float& y, float& z, const Eigen::Vector3d& value) {
    x = static_cast<float>(value.x());
    y = static_cast<float>(value.y());
    z = static_cast<float>(value.z());
    // Bounded factors keep every point finite (ranges are at most 524 m), so the kernel
    // needs no finiteness test per pixel; absurd metadata goes through the reference kernel.
    for (const float f : {x, y, z}) bounded = bounded && std::abs(f) <= 1e6f;
  };
  for (std::size_t b = 0; b < beams; ++b) {
    const double a = cos_alt_[b] * cos_beam_az_[b];
    const double s = cos_alt_[b] * sin_beam_az_[b];
    const Eigen::Vector3d u = a * rot.col(0) + s * rot.col(1);
    const Eigen::Vector3d v = -s * rot.col(0) + a * rot.col(1);
    const Eigen::Vector3d wv = sin_alt_[b] * rot.col(2);
    detail::OusterBeamFactors& k = factors_[b];
    put(k.ux, k.uy, k.uz, u);
    put(k.vx, k.vy, k.vz, v);
    put(k.wx, k.wy, k.wz, wv);
    put(k.pux, k.puy, k.puz, (metadata_.beam_x_mm * rot.col(0) - n * u) * 1e-3);
    put(k.pvx, k.pvy, k.pvz, (metadata_.beam_x_mm * rot.col(1) - n * v) * 1e-3);
    put(k.pwx, k.pwy, k.pwz, (metadata_.beam_z_mm * rot.col(2) + t_mm - n * wv) * 1e-3);
  }
  cos_enc_f_.assign(cos_enc_.begin(), cos_enc_.end());
  sin_enc_f_.assign(sin_enc_.begin(), sin_enc_.end());
  const auto per_packet = static_cast<std::size_t>(metadata_.columns_per_packet);
  ids_.resize(per_packet);
  pixels_.resize(per_packet);
  ce_.resize(per_packet);
  se_.resize(per_packet);
  range_rows_.resize(per_packet * beams);
  reflectivity_rows_.resize(per_packet * beams);
  // The millimetres the reference kernel takes as valid: range_mm * 1e-3f in the model's limits.
  const auto min_range = static_cast<float>(model_.min_range_m);
  const auto max_range = static_cast<float>(model_.max_range_m);
  const auto metres = [](std::int32_t mm) { return static_cast<float>(mm) * 1e-3f; };
  valid_lo_mm_ = std::max<std::int32_t>(1, static_cast<std::int32_t>(model_.min_range_m * 1e3) - 2);
  while (metres(valid_lo_mm_) < min_range) ++valid_lo_mm_;
  valid_hi_mm_ = static_cast<std::int32_t>(model_.max_range_m * 1e3) + 2;
  while (metres(valid_hi_mm_) > max_range) --valid_hi_mm_;
  if (!bounded) options_.reference_kernel = true;
  if (options_.reference_kernel) {
    // Per (measurement id, beam): the point is linear in the range, p = range * direction +
    // offset (the formula of point() with the transform folded in).
    lut_direction_.resize(static_cast<std::size_t>(w) * beams);
    lut_offset_.resize(lut_direction_.size());
    for (int m = 0; m < w; ++m) {
      for (std::size_t b = 0; b < beams; ++b) {
        const Eigen::Vector3d at0 = point(static_cast<int>(b), m, 0.0);
        const Eigen::Vector3d at1 = point(static_cast<int>(b), m, 1000.0);  // 1 m
        const std::size_t k = static_cast<std::size_t>(m) * beams + b;
        lut_direction_[k] = (at1 - at0).cast<float>();
        lut_offset_[k] = at0.cast<float>();
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
  const double bx = metadata_.beam_x_mm;
  const double x = r * c * cos_alt_[b] + bx * cos_enc_[m];
  const double y = r * s * cos_alt_[b] + bx * sin_enc_[m];
  double z = r * sin_alt_[b];
  // Only newer metadata lifts the beam origin; adding 0 could turn a -0 into +0.
  if (metadata_.beam_z_mm != 0.0) z += metadata_.beam_z_mm;
  const auto& R = rotation_;
  return Eigen::Vector3d(R[0] * x + R[1] * y + R[2] * z + translation_mm_[0],
                         R[3] * x + R[4] * y + R[5] * z + translation_mm_[1],
                         R[6] * x + R[7] * y + R[8] * z + translation_mm_[2]) *
         1e-3;
}

void OusterDecoder::start_frame(int frame_id) {
  const auto w = static_cast<std::size_t>(metadata_.columns_per_frame);
  if (spare_ && spare_->rings() == model_.rings() && spare_->columns() == model_.columns() &&
      spare_->column_azimuth_rad.size() == w && spare_->column_stamp_ns.size() == w) {
    scan_ = std::move(spare_);
    spare_.reset();
    // The fast kernel writes every cell of the frame (finish_frame those of columns not
    // received), so a recycled scan needs no reset: that would write its 2.7 MB (OS1-128) twice.
    if (options_.reference_kernel) scan_->reset();
  } else {
    scan_.emplace(model_.rings(), model_.columns());
  }
  stamps_.assign(static_cast<std::size_t>(metadata_.columns_per_frame), 0);
  seen_.assign(static_cast<std::size_t>(metadata_.columns_per_frame), 0);
  frame_id_ = frame_id;
}

namespace {

// Keeps a float's bits where keep is all ones, else puts those of fill.
inline float select_bits(float value, std::uint32_t keep, std::uint32_t fill) {
  return std::bit_cast<float>((std::bit_cast<std::uint32_t>(value) & keep) | fill);
}

// Writes n neighbouring cells of one beam's row from their ranges (mm) and reflectivities and
// the cos and sin of their columns' encoder angles: every cell, valid or not, and without a
// branch, so that the compiler vectorises it (selections as bit masks). Valid: ranges
// valid_lo_mm .. valid_hi_mm, the millimetres whose range in metres is in the model's limits.
void write_run(std::size_t n, const std::int32_t* __restrict range_mm,
               const float* __restrict reflectivity, const float* __restrict ce,
               const float* __restrict se, const detail::OusterBeamFactors& factors,
               std::int32_t valid_lo_mm, std::int32_t valid_hi_mm, float* __restrict out_range,
               float* __restrict out_intensity, float* __restrict out_x, float* __restrict out_y,
               float* __restrict out_z, core::ReturnStatus* __restrict out_status) {
  const detail::OusterBeamFactors k = factors;
  const auto nan_bits = std::bit_cast<std::uint32_t>(kNaN);
  for (std::size_t j = 0; j < n; ++j) {
    const std::int32_t mm = range_mm[j];
    const float r = static_cast<float>(mm) * 1e-3f;  // as the reference kernel rounds it
    const bool valid = (mm >= valid_lo_mm) & (mm <= valid_hi_mm);
    const core::ReturnStatus status = valid              ? core::ReturnStatus::kValid
                                      : mm == 0          ? core::ReturnStatus::kNoReturn
                                      : mm < valid_lo_mm ? core::ReturnStatus::kTooClose
                                                         : core::ReturnStatus::kTooFar;
    const float x = (r * k.ux + k.pux) * ce[j] + (r * k.vx + k.pvx) * se[j] + (r * k.wx + k.pwx);
    const float y = (r * k.uy + k.puy) * ce[j] + (r * k.vy + k.pvy) * se[j] + (r * k.wy + k.pwy);
    const float z = (r * k.uz + k.puz) * ce[j] + (r * k.vz + k.pvz) * se[j] + (r * k.wz + k.pwz);
    const std::uint32_t keep = valid ? 0xFFFFFFFFu : 0u;
    const std::uint32_t fill = nan_bits & ~keep;
    out_range[j] = select_bits(r, keep, fill);
    out_intensity[j] = select_bits(reflectivity[j], keep, 0u);
    out_x[j] = select_bits(x, keep, fill);
    out_y[j] = select_bits(y, keep, fill);
    out_z[j] = select_bits(z, keep, fill);
    out_status[j] = status;
  }
}

}  // namespace

template <OusterProfile kProfile>
void OusterDecoder::decode_columns(std::size_t count, core::OrganizedScan::Cells cells) {
  constexpr std::size_t kMaxColumns = 64;  // columns_per_packet is at most 64 (metadata)
  const auto beams = static_cast<std::size_t>(metadata_.pixels_per_column);
  const std::size_t stride = metadata_.pixel_bytes();
  const OusterReturn selection = options_.return_selection;
  // The pixels beam-major (beam * count + column), read in the packet's order.
  std::int32_t* range_rows = range_rows_.data();
  float* reflectivity_rows = reflectivity_rows_.data();
  const std::size_t column_bytes = beams * stride;
  for (std::size_t j = 0; j < count; ++j) {
    const std::uint8_t* q = pixels_[j];
    // The packet is read once, from memory: ask for the next column's lines ahead.
    if (j + 1 < count) {
      for (std::size_t at = 0; at < column_bytes; at += 64) __builtin_prefetch(pixels_[j + 1] + at);
    }
    for (std::size_t b = 0; b < beams; ++b, q += stride) {
      OusterPixel px;
      read_pixel(q, kProfile, px);
      if constexpr (kProfile == OusterProfile::kRng19Rfl8Sig16Nir16Dual) {
        select_return(selection, px);
      }
      range_rows[b * count + j] = static_cast<std::int32_t>(px.range_mm);
      reflectivity_rows[b * count + j] = static_cast<float>(px.reflectivity);
    }
  }
  const int first = ids_[0];
  bool consecutive = true;
  for (std::size_t j = 1; j < count; ++j) {
    consecutive = consecutive && ids_[j] == first + static_cast<int>(j);
  }
  // A beam's values when its cells are not one run of its row, before they are scattered.
  alignas(64) float tmp_r[kMaxColumns], tmp_f[kMaxColumns], tmp_x[kMaxColumns], tmp_y[kMaxColumns],
      tmp_z[kMaxColumns];
  alignas(64) core::ReturnStatus tmp_s[kMaxColumns];
  for (std::size_t b = 0; b < beams; ++b) {
    const detail::OusterBeamFactors& k = factors_[b];
    const std::int32_t* range_mm = range_rows + b * count;
    const float* reflectivity = reflectivity_rows + b * count;
    // Destaggered, the beam's pixels move by its shift: one run unless they wrap around.
    const int wrap = wrap_at_[b];
    if (consecutive && (first >= wrap || first + static_cast<int>(count) <= wrap)) {
      const std::size_t i = cell_of(b, first);
      write_run(count, range_mm, reflectivity, ce_.data(), se_.data(), k, valid_lo_mm_,
                valid_hi_mm_, cells.range_m + i, cells.intensity + i, cells.x + i, cells.y + i,
                cells.z + i, cells.status + i);
      continue;
    }
    write_run(count, range_mm, reflectivity, ce_.data(), se_.data(), k, valid_lo_mm_, valid_hi_mm_,
              tmp_r, tmp_f, tmp_x, tmp_y, tmp_z, tmp_s);
    for (std::size_t j = 0; j < count; ++j) {
      const std::size_t i = cell_of(b, ids_[j]);
      cells.range_m[i] = tmp_r[j];
      cells.intensity[i] = tmp_f[j];
      cells.x[i] = tmp_x[j];
      cells.y[i] = tmp_y[j];
      cells.z[i] = tmp_z[j];
      cells.status[i] = tmp_s[j];
    }
  }
}

void OusterDecoder::decode_column_reference(const std::uint8_t* q, int m,
                                            core::OrganizedScan& scan) {
  const int w = metadata_.columns_per_frame;
  const int beams = metadata_.pixels_per_column;
  const auto min_range = static_cast<float>(model_.min_range_m);
  const auto max_range = static_cast<float>(model_.max_range_m);
  const bool other_return = options_.return_selection != OusterReturn::kStrongest;
  const std::size_t stride = metadata_.pixel_bytes();
  const std::size_t lut = static_cast<std::size_t>(m) * static_cast<std::size_t>(beams);
  for (int b = 0; b < beams; ++b, q += stride) {
    OusterPixel px;
    read_pixel(q, metadata_.profile, px);
    if (other_return) select_return(options_.return_selection, px);
    if (px.range_mm == 0) continue;
    // Destaggered: the beam's pixel moves by its shift so that a column holds one direction.
    int c = m + shift_[static_cast<std::size_t>(b)];
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
    const std::size_t k = lut + static_cast<std::size_t>(b);
    scan.set_return(ring, c, range, static_cast<float>(px.reflectivity),
                    lut_direction_[k] * range + lut_offset_[k]);
  }
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
  core::OrganizedScan& scan = *scan_;
  const core::OrganizedScan::Cells cells = scan.cells();
  const int w = metadata_.columns_per_frame;
  const std::size_t pixels =
      static_cast<std::size_t>(metadata_.pixels_per_column) * metadata_.pixel_bytes();
  std::size_t count = 0;  // valid columns of the packet, for the fast kernel
  for (int col = 0; col < metadata_.columns_per_packet; ++col) {
    const std::uint8_t* block = p + column_offset(metadata_, col);
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
    seen_[static_cast<std::size_t>(m)] = 1;
    stamps_[static_cast<std::size_t>(m)] = stamp;
    const std::uint8_t* q = block + first_pixel(metadata_);
    if (options_.reference_kernel) {
      decode_column_reference(q, m, scan);
      continue;
    }
    ids_[count] = m;
    pixels_[count] = q;
    ce_[count] = cos_enc_f_[static_cast<std::size_t>(m)];
    se_[count] = sin_enc_f_[static_cast<std::size_t>(m)];
    ++count;
  }
  if (count > 0) {
    switch (metadata_.profile) {
      case OusterProfile::kLegacy:
        decode_columns<OusterProfile::kLegacy>(count, cells);
        break;
      case OusterProfile::kRng19Rfl8Sig16Nir16:
        decode_columns<OusterProfile::kRng19Rfl8Sig16Nir16>(count, cells);
        break;
      case OusterProfile::kRng19Rfl8Sig16Nir16Dual:
        decode_columns<OusterProfile::kRng19Rfl8Sig16Nir16Dual>(count, cells);
        break;
      case OusterProfile::kRng15Rfl8Nir8:
        decode_columns<OusterProfile::kRng15Rfl8Nir8>(count, cells);
        break;
    }
  }
  ++stats_.decoded_packets;
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
  if (!options_.reference_kernel) {
    // The cells of measurement ids not received still hold what the recycled scan held.
    const core::OrganizedScan::Cells cells = scan.cells();
    const auto beams = static_cast<std::size_t>(metadata_.pixels_per_column);
    for (int m = 0; m < w; ++m) {
      if (seen_[static_cast<std::size_t>(m)] != 0) continue;
      for (std::size_t b = 0; b < beams; ++b) {
        const std::size_t i = cell_of(b, m);
        cells.range_m[i] = cells.x[i] = cells.y[i] = cells.z[i] = kNaN;
        cells.intensity[i] = 0.0f;
        cells.status[i] = core::ReturnStatus::kNoReturn;
      }
    }
  }
  // Column c of the destaggered scan: the direction of measurement c - shift of beam 0 (every
  // beam's shift brings it to about that azimuth), in the sensor frame (ringtrack's azimuths
  // are counter-clockwise from +x, as Ouster's). Its stamp: that of measurement c (rows with
  // another shift were measured up to shift / columns of a revolution apart).
  const int shift0 = metadata_.pixel_shift_by_row[0];
  const double beam0_az = -kTwoPi * metadata_.beam_azimuth_deg[0] / 360.0;
  const double period_ns = 1e9 / (metadata_.scan_rate_hz * w);
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
      scan.column_stamp_ns[static_cast<std::size_t>(c)] = 0;
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
