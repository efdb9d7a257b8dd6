#pragma once
/// Assembles Ouster lidar packets into organized, destaggered scans (one per frame) with the
/// XYZ of Ouster's manual (beam origin offset, lidar-to-sensor transform). See docs/ouster.md.

#include <array>
#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/sensors/ouster/ouster_metadata.hpp"

namespace ringtrack::sensors::ouster {

/// Which return of a pixel fills its cell. The _DUAL profile reports two returns per pixel,
/// return 1 the strongest and return 2 the second strongest (Ouster's manual); the other
/// profiles report the strongest only.
enum class OusterReturn : std::uint8_t {
  kStrongest,  ///< return 1 (every profile)
  kSecond,     ///< return 2, the second strongest (_DUAL only; empty where there is none)
  kLast,       ///< the farther of returns 1 and 2 (_DUAL only; return 1 where 2 is empty)
};

/// Name of a return selection: strongest, second, last.
std::string to_string(OusterReturn selection);

/// Options of the decoder.
struct OusterDecoderOptions {
  bool keep_partial_scans{false};  ///< emit frames with columns of the window missing
  OusterReturn return_selection{OusterReturn::kStrongest};  ///< which return fills a cell
  /// Decode pixel by pixel through OrganizedScan::set_return and a per (measurement id, beam)
  /// point table: the naive reference the fast kernel is tested against (docs/ouster.md).
  bool reference_kernel{false};
};

namespace detail {
/// The fast kernel's point of one beam as a function of the range r (m) and the encoder angle:
/// p = cos(enc) (r u + pu) + sin(enc) (r v + pv) + r w + pw (OusterDecoder's constructor).
struct OusterBeamFactors {
  float ux, uy, uz, vx, vy, vz, wx, wy, wz, pux, puy, puz, pvx, pvy, pvz, pwx, pwy, pwz;
};
}  // namespace detail

/// Counters; every skipped packet and missing column is counted here.
struct OusterDecoderStats {
  std::uint64_t packets{0};
  std::uint64_t decoded_packets{0};
  std::uint64_t wrong_size{0};          ///< packets of another size than the metadata's format
  std::uint64_t invalid_columns{0};     ///< columns flagged invalid by the sensor
  std::uint64_t bad_measurement_id{0};  ///< measurement ids >= columns per frame
  std::uint64_t lost_columns{0};        ///< columns of the window missing from emitted scans
  std::uint64_t scans{0};
  std::uint64_t partial_scans_dropped{0};
};

/// One decoded pixel (for tests and flat point lists).
struct OusterPixel {
  std::uint32_t range_mm{0};   ///< first return (0 = none)
  std::uint32_t range2_mm{0};  ///< second return of the _DUAL profile
  std::uint16_t reflectivity{0};
  std::uint16_t reflectivity2{0};  ///< second return's reflectivity (_DUAL)
};

/// Reads pixel `beam` of column `column` of a packet of the metadata's format (no checks).
OusterPixel ouster_pixel(std::span<const std::uint8_t> packet, const OusterMetadata& metadata,
                         int column, int beam);

/// Turns a stream of Ouster lidar packets into OrganizedScans.
class OusterDecoder {
 public:
  /// Throws core::InputError when the metadata is unusable or its profile cannot give the
  /// selected return (a single-return profile and the second or last return).
  OusterDecoder(OusterMetadata metadata, OusterDecoderOptions options = {});

  /// Decodes one lidar packet (UDP payload, port 7502) received at host_stamp_ns (unused: the
  /// packets carry the sensor's own column time stamps). The first packet must have the
  /// metadata's size, else core::InputError (packets of another sensor or profile); later
  /// packets of another size are counted and skipped.
  void add_packet(std::span<const std::uint8_t> payload, std::int64_t host_stamp_ns);
  /// The oldest completed scan, if any.
  std::optional<core::OrganizedScan> pop_scan();
  /// Hands a scan back for reuse: the next frame is built in its memory (saves allocating and
  /// page-faulting a fresh scan per frame).
  void recycle(core::OrganizedScan&& used) { spare_ = std::move(used); }
  /// Ends the stream: emits the frame in progress when complete (or with keep_partial_scans).
  void finish();

  /// The sensor model.
  [[nodiscard]] const core::SensorModel& model() const { return model_; }
  /// The metadata.
  [[nodiscard]] const OusterMetadata& metadata() const { return metadata_; }
  /// Counters.
  [[nodiscard]] const OusterDecoderStats& stats() const { return stats_; }

  /// Sensor-frame point (metres) of range_mm at measurement id m of beam (the manual's formula).
  [[nodiscard]] Eigen::Vector3d point(int beam, int measurement_id, double range_mm) const;

 private:
  void start_frame(int frame_id);
  void finish_frame();
  // The fast kernel: the packet's valid columns (ids_, pixels_, ce_, se_ hold count of them)
  // written beam by beam, each beam's pixels a run of neighbouring cells of its ring's row.
  template <OusterProfile kProfile>
  void decode_columns(std::size_t count, core::OrganizedScan::Cells cells);
  // The reference kernel: one column's pixels through set_return / set_invalid.
  void decode_column_reference(const std::uint8_t* pixels, int measurement_id,
                               core::OrganizedScan& scan);
  // Fast kernel: the scan index of beam b's pixel of measurement id m, destaggered.
  [[nodiscard]] std::size_t cell_of(std::size_t b, int m) const {
    return cell0_[b] + static_cast<std::size_t>(m) -
           (m >= wrap_at_[b] ? static_cast<std::size_t>(metadata_.columns_per_frame) : 0);
  }

  OusterMetadata metadata_;
  OusterDecoderOptions options_;
  core::SensorModel model_;
  std::vector<int> ring_of_beam_;
  std::vector<double> cos_alt_, sin_alt_, cos_beam_az_, sin_beam_az_;
  std::vector<double> cos_enc_, sin_enc_;  // per measurement id
  std::array<double, 9> rotation_{};
  std::array<double, 3> translation_mm_{};
  double yaw_rad_{0};
  std::vector<int> shift_;  // pixel_shift_by_row brought into [0, columns)
  // Reference kernel: the point per (measurement id, beam), p = range * direction + offset.
  std::vector<Eigen::Vector3f> lut_direction_, lut_offset_;
  // Fast kernel. Per beam: cell index of measurement id 0 and the id from which the destaggered
  // column wraps around; the point's factors, p = cos(enc) * (range * u + pu) +
  // sin(enc) * (range * v + pv) + range * w + pw (the formula of point() expanded, metres).
  std::vector<std::size_t> cell0_;
  std::vector<int> wrap_at_;
  std::vector<detail::OusterBeamFactors> factors_;
  std::vector<float> cos_enc_f_, sin_enc_f_;  // per measurement id
  // The packet in progress, per valid column: measurement id, first pixel, cos and sin of the
  // encoder angle.
  std::vector<int> ids_;
  std::vector<const std::uint8_t*> pixels_;
  std::vector<float> ce_, se_;
  // Its pixels beam-major (beam * columns + column): range (mm), reflectivity.
  std::vector<std::int32_t> range_rows_;
  std::vector<float> reflectivity_rows_;
  std::int32_t valid_lo_mm_{1}, valid_hi_mm_{0};  // the ranges of valid cells

  std::optional<core::OrganizedScan> scan_;
  std::optional<core::OrganizedScan> spare_;
  std::vector<std::int64_t> stamps_;  // per measurement id of the frame in progress
  std::vector<std::uint8_t> seen_;    // per measurement id
  int frame_id_{-1};
  std::deque<core::OrganizedScan> ready_;
  OusterDecoderStats stats_;
};

}  // namespace ringtrack::sensors::ouster
