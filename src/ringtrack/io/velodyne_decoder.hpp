#pragma once
/// Assembles Velodyne data packets into organized scans, one per revolution.

#include <cstdint>
#include <deque>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/velodyne_packet.hpp"

namespace ringtrack::io {

/// Which return fills an OrganizedScan cell (a cell holds one return).
enum class VelodyneReturnSelection : std::uint8_t {
  kAuto,       ///< single-return streams: their return; dual streams: the strongest
  kStrongest,  ///< the strongest return (from a strongest or a dual stream)
  kLast,       ///< the last return (from a last or a dual stream)
  kSecond,     ///< the second strongest return: Ouster's _DUAL profile only (docs/ouster.md)
};

/// Where scan and column time stamps come from.
enum class VelodyneTimeSource : std::uint8_t {
  kHost,    ///< the receive (capture) time of each packet, taken as the end of its last firing
  kSensor,  ///< the packet's microseconds past the hour, with the hour from the receive time
            ///< (for GPS-synchronised sensors)
};

/// Options of the packet-to-scan decoder.
struct VelodyneDecoderOptions {
  std::string model;  ///< "" = detect from the product byte; else vlp16, vlp32c or hdl32e
  VelodyneReturnSelection return_selection{VelodyneReturnSelection::kAuto};
  double cut_azimuth_deg{0.0};  ///< scans start here (Velodyne azimuth: clockwise, 0 = +x)
  double scan_rate_hz{10.0};    ///< nominal revolutions per second; sets the grid's columns
  VelodyneTimeSource time_source{VelodyneTimeSource::kHost};
  bool keep_partial_scans{false};   ///< emit the stream's first and last scans even when they do
                                    ///< not cover a whole revolution
  double max_rate_deviation{0.05};  ///< measured spin rate may differ this much from scan_rate_hz
};

/// Counters of the decoder; every skipped packet and missing column is counted here.
struct VelodyneDecoderStats {
  std::uint64_t packets{0};                ///< data packets offered
  std::uint64_t decoded_packets{0};        ///< packets that went into scans
  std::uint64_t wrong_size{0};             ///< payload not 1206 bytes
  std::uint64_t bad_block_flag{0};         ///< a block without 0xFFEE
  std::uint64_t bad_azimuth{0};            ///< block azimuth >= 360 deg or dual pair mismatch
  std::uint64_t unknown_return_mode{0};    ///< return-mode byte not 0x00/0x37/0x38/0x39
  std::uint64_t product_changed{0};        ///< product or return-mode byte changed mid-stream
  std::uint64_t out_of_order{0};           ///< packets older than their predecessor
  std::uint64_t sequences{0};              ///< firing sequences placed into scans
  std::uint64_t lost_sequences{0};         ///< firing sequences missing between received ones
  std::uint64_t overflow_sequences{0};     ///< sequences past the grid's last column (spin slower
                                           ///< than scan_rate_hz), dropped
  std::uint64_t clock_mismatches{0};       ///< packet time stamps disagreeing with the azimuths
                                           ///< (gap sizes then come from the azimuth)
  std::uint64_t stream_breaks{0};          ///< sensor-time gaps over a second (paused capture):
                                           ///< the scan in progress ends, a new one starts
  std::uint64_t scans{0};                  ///< scans emitted
  std::uint64_t partial_scans_dropped{0};  ///< first/last scans not covering a revolution
  std::uint64_t invalid_columns{0};        ///< columns of emitted scans that no sequence filled
  /// Packets skipped for any reason.
  [[nodiscard]] std::uint64_t skipped_packets() const {
    return wrong_size + bad_block_flag + bad_azimuth + unknown_return_mode + product_changed +
           out_of_order;
  }
};

/// Turns a stream of Velodyne data packets into OrganizedScans. Scans start at the cut azimuth;
/// each firing sequence fills one column, the column being the count of sequences since the cut
/// (gaps from lost packets are measured and skipped, never closed up). See docs/vlp16.md.
class VelodyneDecoder {
 public:
  /// Throws core::ConfigError on a bad option (unknown model name, rates, return selection).
  explicit VelodyneDecoder(VelodyneDecoderOptions options = {});

  /// Decodes one UDP payload received at host_stamp_ns (ns since the epoch). Malformed packets
  /// are counted and skipped (the status says why). Throws core::InputError when the product
  /// byte contradicts the named model, when no model is named and the product is unknown, when
  /// the requested return is absent from the stream, or when the sensor spins at a rate far from
  /// scan_rate_hz.
  VelodynePacketStatus add_packet(std::span<const std::uint8_t> payload,
                                  std::int64_t host_stamp_ns);
  /// The oldest completed scan, if any.
  std::optional<core::OrganizedScan> pop_scan();
  /// Ends the stream: completes the scan in progress (emitted when it reached the end of the
  /// revolution, or with keep_partial_scans).
  void finish();

  /// True once the model is known (named, or detected from the first good packet).
  [[nodiscard]] bool has_model() const { return model_.has_value(); }
  /// The sensor model in use; throws core::Error before has_model().
  [[nodiscard]] const core::SensorModel& model() const;
  /// Raw return-mode byte of the stream (0 before the first good packet).
  [[nodiscard]] std::uint8_t return_mode() const { return return_mode_; }
  /// Counters.
  [[nodiscard]] const VelodyneDecoderStats& stats() const { return stats_; }
  /// Options in effect.
  [[nodiscard]] const VelodyneDecoderOptions& options() const { return options_; }

 private:
  void set_model(core::SensorModel model);
  void check_stream(std::uint8_t product, std::uint8_t return_mode);
  // The steps of add_packet on the packet in parsed_: counts a rejected parse (true when
  // rejected); checks the product and return mode against the stream's (false on a change);
  // whether it goes back in time and azimuth; the running azimuth advance (throws on a wrong
  // rotation rate); its first firing's time in ns.
  bool count_rejected(VelodynePacketStatus status);
  bool stream_matches(std::span<const std::uint8_t> payload);
  [[nodiscard]] bool goes_back(double packet_start_us) const;
  void update_spacing();
  [[nodiscard]] std::int64_t packet_start_ns(std::int64_t host_stamp_ns) const;
  void add_sequence(const VelodyneSequence& seq, double sensor_us, std::int64_t stamp_ns);
  void start_scan(double rel_deg, const VelodyneSequence& seq, std::int64_t stamp_ns);
  void fill_column(int column, const VelodyneSequence& seq, std::int64_t stamp_ns);
  void finish_scan(bool complete);

  VelodyneDecoderOptions options_;
  std::optional<core::SensorModel> model_;
  VelodyneLayout layout_;
  bool stream_known_{false};  // product and return mode taken from the first good packet
  std::uint8_t product_{0};
  std::uint8_t return_mode_{0};
  bool dual_{false};
  bool use_last_{false};  // from a dual stream: last (true) or strongest (false)
  double nominal_advance_deg_{0};
  double step_deg_{0};
  double spacing_deg_{0};  // measured azimuth advance per sequence (running average)
  std::uint64_t spacing_samples_{0};
  // Per-ring lookup tables (by laser id).
  std::vector<int> ring_of_laser_;
  std::vector<float> cos_el_, sin_el_, z_offset_;
  std::vector<double> laser_delta_rad_;  // azimuth offset per laser (ringtrack convention)
  std::vector<double> laser_fraction_;   // firing time / sequence time per laser

  // Scan in progress.
  std::optional<core::OrganizedScan> scan_;
  std::vector<std::uint8_t> filled_;
  bool scan_is_first_{true};
  int first_column_{-1};
  // The previous sequence.
  bool have_prev_{false};
  int prev_column_{0};
  double prev_azimuth_deg_{0};
  double prev_rel_deg_{0};
  double prev_sensor_us_{0};
  std::deque<core::OrganizedScan> ready_;
  VelodyneDecoderStats stats_;
  VelodyneParsedPacket parsed_;
};

/// Parses a return-selection name: auto, strongest, last. Throws core::ConfigError.
VelodyneReturnSelection parse_velodyne_return_selection(const std::string& name);
/// Parses a time-source name: host, sensor. Throws core::ConfigError.
VelodyneTimeSource parse_velodyne_time_source(const std::string& name);

}  // namespace ringtrack::io
