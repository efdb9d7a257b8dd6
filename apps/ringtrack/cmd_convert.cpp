// `ringtrack convert`: decodes an input (Velodyne pcap/pcapng, live UDP, ROS 1 or ROS 2 bag) into
// a sequence folder of organized PCD scans (docs/inputs.md, docs/formats.md, docs/vlp16.md).

#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include "commands.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/bad_scans.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/io/sequence.hpp"
#include "ringtrack/io/text.hpp"
#include "stop_signals.hpp"

namespace ringtrack::cli {
namespace {

struct ConvertOptions {
  std::string input;
  std::string out;
  InputOptions source;  // --format, --topic, the decoder's options (shared with run)
  std::string on_bad_scan{"skip"};
  std::string encoding{"binary_compressed"};
  std::size_t max_scans{0};
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

// A warning about a skipped scan: the first few on stderr, the rest counted (run.json).
void warn_skipped(const std::string& input, std::uint64_t index, const std::string& reason,
                  std::uint64_t count) {
  constexpr std::uint64_t kShown = 20;
  if (count <= kShown) {
    std::cerr << "ringtrack: warning: " << input << ": scan " << index << ": " << reason << "\n";
  } else if (count == kShown + 1) {
    std::cerr << "ringtrack: warning: " << input
              << ": more scans skipped; they are counted in run.json\n";
  }
}

void run_convert(const ConvertOptions& o) {
  if (o.out.empty()) throw core::ConfigError("convert: --out DIR is required");
  io::ScanSourceOptions options = o.source.source_options();
  options.velodyne.interrupt = &StopSignals::stop_flag();
  io::SequenceWriteOptions write_options;
  write_options.encoding = parse_encoding(o.encoding);
  write_options.ground_truth = false;
  write_options.overwrite = o.overwrite;

  // For the whole command: a signal while the last files are written still lets them finish.
  const StopSignals stop_signals;
  auto source = io::open_source(o.input, options);
  if (source->live() && !o.quiet) {
    std::cerr << "ringtrack convert: recording " << o.input << ", Ctrl-C to stop\n";
  }
  // run.json is written once the sequence writer has claimed the folder (it refuses one that
  // holds another sequence, whose run.json must stay as it is).
  std::optional<io::RunStatusFile> status_file;
  io::RunStatus pending = new_run_status("convert", o.input);
  io::RunStatus* status = &pending;
  std::uint64_t skipped_count = 0;
  io::ScanReader reader(*source, io::parse_bad_scan_policy(o.on_bad_scan),
                        [&](std::uint64_t index, const std::string& error) {
                          ++status->scans_skipped_unreadable;
                          status->add_skipped(index, "unreadable: " + error);
                          warn_skipped(o.input, index, "unreadable, skipped: " + error,
                                       ++skipped_count);
                        });
  std::unique_ptr<io::SequenceWriter> writer;
  std::optional<std::int64_t> last_stamp_ns;
  try {
    while (o.max_scans == 0 || writer == nullptr || writer->size() < o.max_scans) {
      // Files stop at Ctrl-C or SIGTERM too; live inputs stop by themselves and return what is
      // left.
      if (!source->live() && StopSignals::requested()) break;
      std::uint64_t index = 0;
      std::optional<core::OrganizedScan> scan;
      try {
        scan = reader.next(index);
      } catch (...) {
        status->scans_read = reader.read();
        status->scans_failed = 1;
        throw;
      }
      status->scans_read = reader.read();
      if (!scan) break;
      if (last_stamp_ns && scan->stamp_ns <= *last_stamp_ns) {
        // A sequence's stamps increase; a scan that does not move time forward (a clock step, a
        // corrupt stamp, a repeated message) is left out, as `run` would skip it.
        const std::string reason =
            "stamp " + io::format_stamp(scan->stamp_ns) + " s is not after the previous scan's " +
            io::format_stamp(*last_stamp_ns) + " s (a clock step or a corrupt stamp); skipped";
        ++status->scans_skipped_stamp;
        status->add_skipped(index, reason);
        warn_skipped(o.input, index, reason, ++skipped_count);
        continue;
      }
      if (!writer) {
        writer = std::make_unique<io::SequenceWriter>(
            o.out, io::SequenceMeta::for_sensor(source->model(), scan->columns()), write_options);
        status_file.emplace(std::filesystem::path(o.out) / "run.json", pending);
        status = &status_file->status();
        status_file->start();
      }
      writer->add_scan(*scan, {});
      last_stamp_ns = scan->stamp_ns;
      ++status->scans_processed;
      if (!o.quiet && source->live()) std::cerr << "\rscans: " << writer->size() << std::flush;
    }
    if (!writer) {
      throw core::InputError(o.input + ": no complete revolution to convert (" + source->summary() +
                             "); --keep-partial keeps partial scans");
    }
    writer->finish();
  } catch (const std::exception& e) {
    if (status_file) status_file->fail(e.what());
    throw;
  }
  status_file->finish(StopSignals::signal_name());
  // Always shown, even with --quiet: the output lacks what the input lost.
  if (const auto warning = source->warning(); !warning.empty()) {
    std::cerr << "ringtrack: warning: " << warning << "\n";
  }
  if (!o.quiet) {
    if (source->live()) std::cerr << "\n";
    std::cerr << "ringtrack convert: wrote " << writer->size() << " scans to " << o.out << " ("
              << source->summary() << ")";
    if (const std::uint64_t skipped =
            status->scans_skipped_unreadable + status->scans_skipped_stamp;
        skipped > 0) {
      std::cerr << "; " << skipped << " scans skipped (run.json)";
    }
    if (const auto signal = StopSignals::signal_name(); !signal.empty()) {
      std::cerr << "; stopped by " << signal;
    }
    std::cerr << "\n";
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
         "pcap/pcapng file, udp://HOST:PORT, ROS 1 .bag file, rosbag2 folder, .db3 or .mcap")
      ->required();
  cmd->add_option("--out", options->out, "sequence folder to write")->required();
  options->source.add_to(*cmd);
  cmd->add_option("--on-bad-scan", options->on_bad_scan,
                  "a bag message that cannot be decoded: skip it (counted in run.json) or stop "
                  "with an error")
      ->check(CLI::IsMember({"skip", "stop"}))
      ->capture_default_str();
  cmd->add_option("--encoding", options->encoding, "binary_compressed | binary | ascii");
  cmd->add_option("--max-scans", options->max_scans, "stop after this many scans (0: all)");
  cmd->add_flag("--overwrite", options->overwrite, "replace a sequence already in --out");
  cmd->add_flag("--quiet", options->quiet, "no messages on stderr");
  cmd->callback([options] { run_convert(*options); });
}

}  // namespace ringtrack::cli
