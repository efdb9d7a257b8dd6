// The options every command that reads a recording shares, and what each command that writes a
// folder records about itself (run.json).

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <string>

#include "commands.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/version.hpp"

namespace ringtrack::cli {
namespace {

std::vector<std::string>& stored_command_line() {
  static std::vector<std::string> line;
  return line;
}

}  // namespace

void InputOptions::add_to(CLI::App& command) {
  command.add_option("--format", format,
                     "input format: auto (from the name and contents) | pcap | udp | bag (ROS 1) "
                     "| rosbag2 (sqlite3 or mcap) | folder (PCD or KITTI-style .bin files)");
  command.add_option("--topic", topic,
                     "bag topic: velodyne_msgs/VelodyneScan, pandar_msgs/PandarScan or "
                     "sensor_msgs/PointCloud2 (default: the first one with messages)");
  command.add_option("--model,--sensor", model,
                     "vlp16 | vlp32c | hdl32e | hdl64e | Pandar40P | Pandar64 | PandarQT64 | "
                     "PandarXT16 | PandarXT32 (default: from the packets' product byte or Hesai "
                     "header; point clouds: vlp16 up to 16 rings; ringtrack sensors)");
  command.add_option("--calibration", calibration,
                     "Hesai: the sensor's angle-correction CSV (channel, elevation, azimuth)");
  command.add_option("--metadata", metadata,
                     "Ouster: the sensor's metadata JSON (beam angles, data format)");
  command.add_option("--return", return_selection,
                     "which return fills a cell: auto | strongest | last | second (Ouster _DUAL; "
                     "docs/ouster.md)");
  command.add_option("--cut-azimuth", cut_azimuth_deg,
                     "azimuth where scans start, degrees clockwise from the sensor's +x "
                     "(Velodyne convention)");
  command.add_option("--scan-rate", scan_rate_hz, "revolutions per second (rpm / 60)");
  command.add_option("--time-source", time_source, "host | sensor (GPS-synchronised)");
  command.add_option("--port", port, "UDP port of data packets in a pcap");
  command.add_option("--ring-field", ring_field,
                     "PointCloud2 topics: the field holding each point's ring (0 = bottom)");
  command.add_flag("--keep-partial", keep_partial,
                   "keep the first and last scans even when they cover less than a revolution");
}

io::ScanSourceOptions InputOptions::source_options() const {
  if (port < 1 || port > 65535) throw core::ConfigError("--port must be 1..65535");
  io::ScanSourceOptions options;
  options.format = io::parse_scan_input_format(format);
  options.topic = topic;
  options.ring_field = ring_field;
  options.calibration = calibration;
  options.metadata = metadata;
  io::VelodyneDecoderOptions& decoder = options.velodyne.decoder;
  decoder.model = model;
  decoder.return_selection = io::parse_velodyne_return_selection(return_selection);
  decoder.time_source = io::parse_velodyne_time_source(time_source);
  decoder.cut_azimuth_deg = cut_azimuth_deg;
  decoder.scan_rate_hz = scan_rate_hz;
  decoder.keep_partial_scans = keep_partial;
  options.velodyne.pcap.data_port = static_cast<std::uint16_t>(port);
  return options;
}

void set_command_line(int argc, char** argv) {
  auto& line = stored_command_line();
  line.assign(argv, argv + argc);
}

io::RunStatus new_run_status(const std::string& command, const std::string& input) {
  io::RunStatus status;
  status.command = command;
  status.arguments = stored_command_line();
  status.version = kVersion;
  status.input = input;
  return status;
}

void check_stdout() {
  // Both the C and the C++ streams (std::cout writes through stdout): commands print through
  // either. The last flush's errno names the cause; an earlier failed write leaves only the
  // stream's error flag.
  errno = 0;
  const bool flush_failed = std::fflush(stdout) != 0;
  const int flush_errno = errno;
  std::cout.flush();
  if (flush_failed || std::ferror(stdout) != 0 || !std::cout) {
    std::string message = "cannot write to standard output";
    if (flush_failed && flush_errno != 0) message += std::string(": ") + std::strerror(flush_errno);
    throw core::Error(message);
  }
}

}  // namespace ringtrack::cli
