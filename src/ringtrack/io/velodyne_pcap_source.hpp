#pragma once
/// Organized scans from a Velodyne capture (.pcap / .pcapng).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/io/pcap_reader.hpp"
#include "ringtrack/io/velodyne_decoder.hpp"

namespace ringtrack::io {

/// Which datagrams of a capture are Velodyne packets.
struct VelodynePcapOptions {
  std::uint16_t data_port{2368};      ///< UDP destination port of data packets
  std::uint16_t position_port{8308};  ///< UDP destination port of position packets (ignored)
  bool allow_truncated{true};         ///< a file ending inside a record ends the stream (counted)
};

/// Counters of the datagrams a source did not decode (the decoder counts bad data packets).
struct VelodynePcapStats {
  std::uint64_t data_datagrams{0};      ///< datagrams to the data port (handed to the decoder)
  std::uint64_t position_datagrams{0};  ///< datagrams to the position port, ignored
  std::uint64_t other_datagrams{0};     ///< UDP to other ports, ignored
};

/// Reads a capture and yields one OrganizedScan per revolution.
class VelodynePcapSource {
 public:
  /// Opens the capture; throws core::InputError (file) or core::ConfigError (options).
  VelodynePcapSource(const std::filesystem::path& path, VelodynePcapOptions pcap_options = {},
                     VelodyneDecoderOptions decoder_options = {});

  /// The next scan, or nullopt at the end. Throws core::InputError naming the file and frame
  /// when the stream contradicts the options, or when the file holds no Velodyne data packets.
  std::optional<core::OrganizedScan> next();

  /// The decoder (model, return mode and its counters).
  [[nodiscard]] const VelodyneDecoder& decoder() const { return decoder_; }
  /// The capture reader (its counters and truncation state).
  [[nodiscard]] const PcapReader& reader() const { return reader_; }
  /// Datagram counters.
  [[nodiscard]] const VelodynePcapStats& stats() const { return stats_; }
  /// One line summarizing what was read and skipped, for logs.
  [[nodiscard]] std::string summary() const;

 private:
  PcapReader reader_;
  VelodynePcapOptions options_;
  VelodyneDecoder decoder_;
  VelodynePcapStats stats_;
  bool finished_{false};
};

}  // namespace ringtrack::io
