#pragma once
/// Organized scans from a capture (.pcap / .pcapng) of Ouster lidar packets with the sensor's
/// metadata JSON; the decoding itself is sensors/ouster. See docs/ouster.md.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/io/pcap_reader.hpp"
#include "ringtrack/io/source.hpp"
#include "ringtrack/sensors/ouster/ouster_decoder.hpp"

namespace ringtrack::io {

/// Reads a capture: lidar packets to `lidar_port` (7502) are decoded, IMU packets (7503) and
/// other traffic counted and ignored.
class OusterPcapSource final : public ScanSource {
 public:
  /// Opens the capture; throws core::InputError.
  OusterPcapSource(const std::filesystem::path& path, sensors::ouster::OusterMetadata metadata,
                   sensors::ouster::OusterDecoderOptions options = {},
                   std::uint16_t lidar_port = 7502);
  /// The next scan, or nullopt at the end; throws core::InputError naming the file and frame.
  std::optional<core::OrganizedScan> next() override;
  /// The sensor model.
  [[nodiscard]] const core::SensorModel& model() const override { return decoder_.model(); }
  /// The capture's name and kind.
  [[nodiscard]] std::string description() const override {
    return reader_.path() + " (Ouster pcap)";
  }
  /// One line of counters.
  [[nodiscard]] std::string summary() const override;
  /// The decoder.
  [[nodiscard]] const sensors::ouster::OusterDecoder& decoder() const { return decoder_; }

 private:
  PcapReader reader_;
  sensors::ouster::OusterDecoder decoder_;
  std::uint16_t port_;
  std::uint64_t imu_datagrams_{0};
  std::uint64_t other_datagrams_{0};
  bool finished_{false};
};

/// True when the capture's first UDP datagrams include one to the Ouster lidar port 7502 and
/// none to the Velodyne/Hesai port 2368.
bool pcap_holds_ouster(const std::filesystem::path& path);

}  // namespace ringtrack::io
