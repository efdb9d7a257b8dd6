// `ringtrack convert`: decodes an input (Velodyne pcap/pcapng, live UDP, ROS 1 or ROS 2 bag) into
// a sequence folder of organized PCD scans (docs/inputs.md, docs/formats.md, docs/vlp16.md).

#include <atomic>
#include <csignal>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/io/sequence.hpp"

namespace ringtrack::cli {
namespace {

std::atomic<bool> g_interrupted{false};

extern "C" void on_convert_interrupt(int) {
  g_interrupted.store(true);
}

struct ConvertOptions {
  std::string input;
  std::string out;
  std::string format{"auto"};
  std::string model;
  std::string calibration;
  std::string metadata;
  std::string return_selection{"auto"};
  std::string time_source{"host"};
  std::string encoding{"binary_compressed"};
  std::string topic;
  std::string ring_field{"ring"};
  double cut_azimuth_deg{0.0};
  double scan_rate_hz{10.0};
  int port{2368};
  std::size_t max_scans{0};
  bool keep_partial{false};
  bool overwrite{false};
  bool quiet{false};
};

io::PcdEncoding parse_encoding(const std::string& name) {
  if (name == "binary_compressed") return io::PcdEncoding::kBinaryCompressed;
  if (name == "binary") return io::PcdEncoding::kBinary;
  if (name == "ascii") return io::PcdEncoding::kAscii;
  throw core::ConfigError("convert: --encoding '" + name +
                          "': expected binary_compressed, binary or ascii");
}

void run_convert(const ConvertOptions& o) {
  if (o.out.empty()) throw core::ConfigError("convert: --out DIR is required");
  if (o.port < 1 || o.port > 65535) throw core::ConfigError("convert: --port must be 1..65535");
  io::ScanSourceOptions options;
  options.format = io::parse_scan_input_format(o.format);
  options.topic = o.topic;
  options.ring_field = o.ring_field;
  options.calibration = o.calibration;
  options.metadata = o.metadata;
  io::VelodyneSourceOptions& velodyne = options.velodyne;
  velodyne.decoder.model = o.model;
  velodyne.decoder.return_selection = io::parse_velodyne_return_selection(o.return_selection);
  velodyne.decoder.time_source = io::parse_velodyne_time_source(o.time_source);
  velodyne.decoder.cut_azimuth_deg = o.cut_azimuth_deg;
  velodyne.decoder.scan_rate_hz = o.scan_rate_hz;
  velodyne.decoder.keep_partial_scans = o.keep_partial;
  velodyne.pcap.data_port = static_cast<std::uint16_t>(o.port);
  velodyne.interrupt = &g_interrupted;
  io::SequenceWriteOptions write_options;
  write_options.encoding = parse_encoding(o.encoding);
  write_options.ground_truth = false;
  write_options.overwrite = o.overwrite;

  auto source = io::open_scan_source(o.input, options);
  g_interrupted.store(false);
  const auto previous = std::signal(SIGINT, on_convert_interrupt);
  if (source->live() && !o.quiet) {
    std::cerr << "ringtrack convert: recording " << o.input << ", Ctrl-C to stop\n";
  }
  std::unique_ptr<io::SequenceWriter> writer;
  try {
    while (o.max_scans == 0 || writer == nullptr || writer->size() < o.max_scans) {
      // Files stop at Ctrl-C too; live inputs stop by themselves and return what is left.
      if (!source->live() && g_interrupted.load()) break;
      auto scan = source->next();
      if (!scan) break;
      if (!writer) {
        writer = std::make_unique<io::SequenceWriter>(
            o.out, io::SequenceMeta::for_sensor(source->model(), scan->columns()), write_options);
      }
      writer->add_scan(*scan, {});
      if (!o.quiet && source->live()) std::cerr << "\rscans: " << writer->size() << std::flush;
    }
  } catch (...) {
    std::signal(SIGINT, previous);
    throw;
  }
  std::signal(SIGINT, previous);
  if (!writer) {
    throw core::InputError(o.input + ": no complete revolution to convert (" + source->summary() +
                           "); --keep-partial keeps partial scans");
  }
  writer->finish();
  // Always shown, even with --quiet: the output lacks what the input lost.
  if (const auto warning = source->warning(); !warning.empty()) {
    std::cerr << "ringtrack: warning: " << warning << "\n";
  }
  if (!o.quiet) {
    if (source->live()) std::cerr << "\n";
    std::cerr << "ringtrack convert: wrote " << writer->size() << " scans to " << o.out << " ("
              << source->summary() << ")\n";
  }
}

}  // namespace

void register_convert(CLI::App& app) {
  auto options = std::make_shared<ConvertOptions>();
  CLI::App* cmd = app.add_subcommand(
      "convert",
      "Decode a recording or live sensor (Velodyne pcap/pcapng, udp://HOST:PORT, "
      "ROS 1 .bag, ROS 2 bag in sqlite3 or MCAP) into a sequence folder of organized PCD scans");
  cmd->add_option(
         "input", options->input,
         "pcap/pcapng file, udp://HOST:PORT, ROS 1 .bag file, rosbag2 folder, .db3 or .mcap, "
         "folder of PCD or KITTI-style .bin files")
      ->required();
  cmd->add_option("--out", options->out, "sequence folder to write")->required();
  cmd->add_option("--format", options->format,
                  "auto | pcap | udp | bag (ROS 1) | rosbag2 | folder (PCD or .bin files)");
  cmd->add_option("--model,--sensor", options->model,
                  "vlp16 | vlp32c | hdl32e | Pandar40P | Pandar64 | PandarQT64 | PandarXT16 | "
                  "PandarXT32 (default: from the packets' product byte or Hesai header; point "
                  "clouds: vlp16 up to 16 rings)");
  cmd->add_option("--calibration", options->calibration,
                  "Hesai: the sensor's angle-correction CSV (channel, elevation, azimuth)");
  cmd->add_option("--metadata", options->metadata,
                  "Ouster: the sensor's metadata JSON (beam angles, data format)");
  cmd->add_option("--return", options->return_selection,
                  "which return fills a cell: auto | strongest | last");
  cmd->add_option("--cut-azimuth", options->cut_azimuth_deg,
                  "azimuth where scans start, degrees clockwise from the sensor's +x (Velodyne "
                  "convention)");
  cmd->add_option("--scan-rate", options->scan_rate_hz, "revolutions per second (rpm / 60)");
  cmd->add_option("--time-source", options->time_source, "host | sensor (GPS-synchronised)");
  cmd->add_option("--port", options->port, "UDP port of data packets in a pcap");
  cmd->add_option("--topic", options->topic,
                  "bag topic, velodyne_msgs/VelodyneScan or sensor_msgs/PointCloud2 (default: the "
                  "first one with messages)");
  cmd->add_option("--ring-field", options->ring_field,
                  "PointCloud2 topics: the field holding each point's ring (0 = bottom)");
  cmd->add_option("--encoding", options->encoding, "binary_compressed | binary | ascii");
  cmd->add_option("--max-scans", options->max_scans, "stop after this many scans (0: all)");
  cmd->add_flag("--keep-partial", options->keep_partial,
                "keep the first and last scans even when they cover less than a revolution");
  cmd->add_flag("--overwrite", options->overwrite, "replace a sequence already in --out");
  cmd->add_flag("--quiet", options->quiet, "no messages on stderr");
  cmd->callback([options] { run_convert(*options); });
}

}  // namespace ringtrack::cli
