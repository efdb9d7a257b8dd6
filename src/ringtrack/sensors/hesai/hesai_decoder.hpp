#pragma once
/// Assembles Hesai point-cloud packets into organized scans (one per revolution, one column per
/// firing block, rings from the angle-correction file) and decodes flat point lists. See
/// docs/hesai.md.

#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/sensors/hesai/hesai_calibration.hpp"
#include "ringtrack/sensors/hesai/hesai_format.hpp"

namespace ringtrack::sensors::hesai {

/// Which return of a dual-return stream fills an OrganizedScan cell.
enum class HesaiReturnSelection : std::uint8_t {
  kAuto,       ///< single-return streams: their return; dual streams: the strongest
  kStrongest,  ///< the pair's block with the higher reflectivity (ties: the second block)
  kLast,       ///< the pair's first block (last return in modes 0x39 and 0x3B)
};

/// Options of the decoder.
struct HesaiDecoderOptions {
  std::string model;  ///< "" = recognise from the packets; else a name of hesai_formats()
  HesaiCalibration calibration;  ///< required: the sensor's angle-correction file
  HesaiReturnSelection return_selection{HesaiReturnSelection::kAuto};
  double cut_azimuth_deg{0.0};  ///< scans start here (Hesai azimuth: clockwise)
  double scan_rate_hz{10.0};    ///< revolutions per second; sets the grid's columns
  bool keep_partial_scans{false};
  double min_range_m{-1.0};  ///< < 0: the format's default
  double max_range_m{-1.0};  ///< < 0: the format's default
};

/// Counters; every skipped packet and missing column is counted here.
struct HesaiDecoderStats {
  std::uint64_t packets{0};
  std::uint64_t decoded_packets{0};
  std::uint64_t wrong_size{0};
  std::uint64_t bad_header{0};
  std::uint64_t bad_azimuth{0};
  std::uint64_t unknown_return_mode{0};
  std::uint64_t mode_changed{0};     ///< return mode differs from the stream's first packet
  std::uint64_t repeated_blocks{0};  ///< blocks at or behind the previous azimuth, dropped
  std::uint64_t lost_blocks{0};      ///< firing blocks missing between received ones
  std::uint64_t overflow_blocks{0};  ///< blocks past the grid's last column, dropped
  std::uint64_t scans{0};
  std::uint64_t partial_scans_dropped{0};
  std::uint64_t invalid_columns{0};
  /// Packets skipped for any reason.
  [[nodiscard]] std::uint64_t skipped_packets() const {
    return wrong_size + bad_header + bad_azimuth + unknown_return_mode + mode_changed;
  }
};

/// One decoded return in packet order, for flat point lists and validation.
struct HesaiPoint {
  int channel{0};              ///< 0-based channel (record order; calibration row channel - 1)
  int block{0};                ///< block of the packet
  bool second_of_pair{false};  ///< dual: read from the pair's second block
  double azimuth_deg{0};       ///< block azimuth + the channel's azimuth offset (clockwise)
  double elevation_deg{0};     ///< the channel's elevation
  double distance_m{0};
  std::uint8_t reflectivity{0};
  /// Sensor-frame point in ringtrack's convention (+x at azimuth 0, counter-clockwise).
  [[nodiscard]] Eigen::Vector3d xyz() const;
};

/// Appends every return of a parsed packet in data order (block, channel). Zero distances are
/// skipped; in dual mode a second-block return whose distance equals the first block's is the
/// same echo reported twice and is skipped.
void append_hesai_points(const HesaiParsedPacket& packet, const HesaiCalibration& calibration,
                         std::vector<HesaiPoint>& out);

/// Turns a stream of Hesai packets into OrganizedScans.
class HesaiDecoder {
 public:
  /// Throws core::ConfigError on bad options (unknown model, rates, empty calibration).
  explicit HesaiDecoder(HesaiDecoderOptions options);

  /// Decodes one UDP payload received at host_stamp_ns. Malformed packets are counted and
  /// skipped. Throws core::InputError when the packets are of another model than the named one
  /// or than the calibration's channel count, or when the requested return is absent.
  HesaiPacketStatus add_packet(std::span<const std::uint8_t> payload, std::int64_t host_stamp_ns);
  /// The oldest completed scan, if any.
  std::optional<core::OrganizedScan> pop_scan();
  /// Hands a scan back for reuse: the next scan is built in its memory when its size fits
  /// (saves allocating and page-faulting a fresh scan per revolution).
  void recycle(core::OrganizedScan&& used) { spare_ = std::move(used); }
  /// Ends the stream (emits the scan in progress when complete, or with keep_partial_scans).
  void finish();

  /// True once the model is known.
  [[nodiscard]] bool has_model() const { return model_.has_value(); }
  /// The sensor model; throws core::Error before has_model().
  [[nodiscard]] const core::SensorModel& model() const;
  /// The packet format in use (nullptr before the first packet when not named).
  [[nodiscard]] const HesaiFormat* format() const { return format_; }
  /// Counters.
  [[nodiscard]] const HesaiDecoderStats& stats() const { return stats_; }

 private:
  void set_format(const HesaiFormat& format);
  // The steps of add_packet: a packet that fails to parse as the stream's format but is another
  // model's is an error; a rejected parse is counted (true); the first packet fixes the format
  // and the return taken (choose_return), and a later change of return mode is counted (false).
  void check_same_format(std::span<const std::uint8_t> payload) const;
  bool count_rejected(HesaiPacketStatus status);
  void choose_return(std::uint8_t mode, bool dual);
  bool stream_matches(const HesaiFormat& format);
  void add_firing(int block, std::int64_t stamp_ns);
  void start_scan(double rel_deg, int block, std::int64_t stamp_ns);
  void fill_column(int column, int block, std::int64_t stamp_ns);
  void finish_scan(bool complete);

  HesaiDecoderOptions options_;
  const HesaiFormat* format_{nullptr};
  std::optional<core::SensorModel> model_;
  bool stream_known_{false};
  std::uint8_t return_mode_{0};
  bool use_last_{false};
  double step_deg_{0};
  double spacing_deg_{0};  // measured azimuth advance per firing (running average)
  double firing_us_{0};
  float min_range_{0};
  float max_range_{0};
  std::vector<float> cos_el_, sin_el_;
  std::vector<double> cos_offset_, sin_offset_;  // of each channel's azimuth offset
  std::vector<int> ring_of_channel_;

  std::optional<core::OrganizedScan> scan_;
  std::optional<core::OrganizedScan> spare_;
  std::vector<std::uint8_t> filled_;
  bool scan_is_first_{true};
  int first_column_{0};
  bool have_prev_{false};
  int prev_column_{0};
  double prev_azimuth_deg_{0};
  double prev_rel_deg_{0};
  std::deque<core::OrganizedScan> ready_;
  HesaiDecoderStats stats_;
  HesaiParsedPacket parsed_;
};

/// Parses auto, strongest or last; throws core::ConfigError.
HesaiReturnSelection parse_hesai_return_selection(const std::string& name);

}  // namespace ringtrack::sensors::hesai
