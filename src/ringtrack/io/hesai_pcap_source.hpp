#pragma once
/// Organized scans from a capture (.pcap / .pcapng) of Hesai point-cloud packets; the decoding
/// itself is sensors/hesai. See docs/hesai.md.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/io/pcap_reader.hpp"
#include "ringtrack/io/source.hpp"
#include "ringtrack/sensors/hesai/hesai_decoder.hpp"

namespace ringtrack::io {

/// Reads a capture and yields one OrganizedScan per revolution.
class HesaiPcapSource final : public ScanSource {
 public:
  /// Opens the capture; throws core::InputError (file) or core::ConfigError (options).
  HesaiPcapSource(const std::filesystem::path& path, std::uint16_t data_port,
                  const sensors::hesai::HesaiDecoderOptions& options, bool allow_truncated = true);
  /// The next scan, or nullopt at the end; throws core::InputError naming the file and frame.
  std::optional<core::OrganizedScan> next() override;
  /// The sensor model (known after the first packet).
  [[nodiscard]] const core::SensorModel& model() const override { return decoder_.model(); }
  /// The capture's name and kind.
  [[nodiscard]] std::string description() const override {
    return reader_.path() + " (Hesai pcap)";
  }
  /// One line of counters.
  [[nodiscard]] std::string summary() const override;
  /// The decoder.
  [[nodiscard]] const sensors::hesai::HesaiDecoder& decoder() const { return decoder_; }

 private:
  PcapReader reader_;
  std::uint16_t port_;
  sensors::hesai::HesaiDecoder decoder_;
  std::uint64_t other_datagrams_{0};
  bool finished_{false};
};

/// The Hesai decoder's non-zero problem counters as the summaries list them (", 3 wrong-size"
/// each), for the capture's and the live source's summary lines.
std::string hesai_problem_counts(const sensors::hesai::HesaiDecoderStats& d);

/// True when the first UDP payload to `port` among the capture's first frames is a Hesai packet
/// (sensors/hesai/hesai_format.hpp); false for Velodyne or when there is none.
bool pcap_holds_hesai(const std::filesystem::path& path, std::uint16_t port);

}  // namespace ringtrack::io
