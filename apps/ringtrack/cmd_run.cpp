// `ringtrack run INPUT --out DIR`: the command line of runner::Run (ringtrack/runner/run.hpp) and
// the printing around it: progress, warnings and the summary.

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "plots.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/eval/statistics.hpp"
#include "ringtrack/io/bad_scans.hpp"
#include "ringtrack/runner/run.hpp"
#include "ringtrack/runner/run_input.hpp"
#include "ringtrack/version.hpp"
#include "stop_signals.hpp"

namespace ringtrack::cli {
namespace {

namespace fs = std::filesystem;

struct RunOptions {
  std::string input;
  std::string out;
  InputOptions source;  // --format, --topic, the decoder's options (shared with convert)
  std::string on_bad_scan{"skip"};
  std::string poses;
  std::string poses_format{"tum"};
  std::string mcap;
  std::string mcap_compression{"zstd"};
  std::uint32_t mcap_map_every{0};
  bool filtered_scans{false};
  bool no_deskew{false};
  std::string odometry{"auto"};
  std::string odometry_start;
  bool quiet{false};
  bool no_plots{false};
  ConfigOptions config;
};

// One status line on stderr: scans done, rate and, when the total is known, the time left.
void print_progress(std::size_t done, std::size_t total,
                    std::chrono::steady_clock::time_point start) {
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double rate = s > 0 ? static_cast<double>(done) / s : 0.0;
  if (total > 0) {
    const double eta = rate > 0 ? static_cast<double>(total - done) / rate : 0.0;
    std::fprintf(stderr, "\rscan %zu / %zu  %.0f scans/s  ETA %.0f s   ", done, total, rate, eta);
  } else {
    std::fprintf(stderr, "\rscan %zu  %.0f scans/s   ", done, rate);
  }
}

// The run's input (runner::RunInput) from the command line: the input options, --poses,
// --no-deskew and --on-bad-scan; Ctrl-C stops a live input.
runner::RunInputOptions run_input_options(const RunOptions& o) {
  runner::RunInputOptions options;
  options.source = o.source.source_options();
  options.source.velodyne.interrupt = &StopSignals::stop_flag();
  options.poses = o.poses;
  options.poses_format = o.poses_format;
  options.no_deskew = o.no_deskew;
  options.on_bad_scan = io::parse_bad_scan_policy(o.on_bad_scan);
  return options;
}

// The odometry's lines of the run summary, and a warning when some poses are unreliable.
void print_odometry_summary(const runner::RunSummary& s) {
  std::printf(
      "odometry         %zu of %zu scans flagged unreliable (too little geometry or not "
      "registered), %zu weak (may slide); ms per scan median %.3f, p95 %.3f\n",
      s.odometry_degenerate, s.odometry_scans, s.odometry_weak, eval::quantile(s.odometry_ms, 0.5),
      eval::quantile(s.odometry_ms, 0.95));
  if (s.odometry_degenerate > 0) {
    std::fprintf(stderr,
                 "ringtrack: warning: odometry: %zu of %zu scans had too little geometry to fix "
                 "the pose (e.g. ground only): the estimated poses are unreliable there "
                 "(odometry.csv, column degenerate)\n",
                 s.odometry_degenerate, s.odometry_scans);
  }
  if (s.odometry_weak > 0) {
    std::fprintf(stderr,
                 "ringtrack: warning: odometry: %zu of %zu scans had weak geometry in one "
                 "direction (weakest_share below odometry.weak_share_threshold): the estimated "
                 "poses may slide along it there; check them against another source "
                 "(odometry.csv, column weak)\n",
                 s.odometry_weak, s.odometry_scans);
  }
}

// Warnings about skipped scans on stderr: the first few, then one line saying the rest are only
// counted (run.json lists them), so a recording full of bad scans does not flood the terminal.
class SkipWarnings {
 public:
  explicit SkipWarnings(std::string input) : input_(std::move(input)) {}
  void warn(std::uint64_t index, const std::string& reason) {
    ++count_;
    if (count_ <= kShown) {
      std::fprintf(stderr, "ringtrack: warning: %s: scan %llu: %s\n", input_.c_str(),
                   static_cast<unsigned long long>(index), reason.c_str());
    } else if (count_ == kShown + 1) {
      std::fprintf(stderr,
                   "ringtrack: warning: %s: more scans skipped; they are counted in the summary "
                   "and listed in run.json\n",
                   input_.c_str());
    }
  }

 private:
  static constexpr std::uint64_t kShown = 20;
  std::string input_;
  std::uint64_t count_{0};
};

// The "scans" line's note on skipped scans, "" when none.
std::string skipped_note(const io::RunStatus& s) {
  const std::uint64_t skipped = s.scans_skipped_unreadable + s.scans_skipped_stamp;
  if (skipped == 0) return "";
  std::string note = " (" + std::to_string(skipped) + " more skipped: ";
  if (s.scans_skipped_unreadable > 0 && s.scans_skipped_stamp > 0) {
    note += std::to_string(s.scans_skipped_unreadable) + " unreadable, " +
            std::to_string(s.scans_skipped_stamp) + " with a stamp not after the scan before";
  } else if (s.scans_skipped_unreadable > 0) {
    note += "unreadable";
  } else {
    note += "stamp not after the scan before";
  }
  return note + ")";
}

// A warning when the altitude test rejected clusters and nothing was detected: the heights of
// the poses' frame may not be what detection.sensor_height_m says (docs/detection.md).
void warn_about_heights(const core::Config& config, std::uint64_t too_high,
                        std::uint64_t detections) {
  if (too_high == 0 || detections > 0) return;
  std::fprintf(stderr,
               "ringtrack: warning: no detections, and %llu clusters had their lowest point "
               "more than detection.max_altitude_m = %g m above the ground, which is taken as "
               "detection.sensor_height_m = %g m below the first scan's sensor: check "
               "sensor_height_m (docs/detection.md)\n",
               static_cast<unsigned long long>(too_high), config.detection.max_altitude_m,
               config.detection.sensor_height_m);
}

// The runner's options from the command line: the outputs, the MCAP's metadata (what wrote it,
// from what), Ctrl-C and SIGTERM as the stop request, the skip warnings and the progress line.
runner::RunOptions runner_options(const RunOptions& o, bool odometry, SkipWarnings& warnings) {
  runner::RunOptions options;
  options.out = o.out;
  options.odometry = odometry;
  options.odometry_start = o.odometry_start;
  options.filtered_scans = o.filtered_scans;
  options.raw_map = !o.no_plots;
  options.mcap = o.mcap;
  options.mcap_compression = o.mcap_compression;
  options.mcap_map_every = o.mcap_map_every;
  options.mcap_metadata = {{"version", kVersion}, {"command", "run"},
                           {"input", o.input},    {"format", o.source.format},
                           {"poses", o.poses},    {"deskew", o.no_deskew ? "off" : "auto"}};
  options.stop = &StopSignals::stop_flag();
  options.on_skipped = [&warnings](std::uint64_t index, const std::string& reason) {
    warnings.warn(index, reason);
  };
  return options;
}

// The summary's lines from "tracks" on, with the warnings on what the figures suggest.
void print_results(const RunOptions& o, const core::Config& config, bool odometry,
                   const runner::RunSummary& s, bool plotted) {
  std::printf("tracks           %zu (%zu ever dynamic)\n", s.tracks, s.dynamic_tracks);
  if (s.bounded_map) {
    std::printf(
        "static map       %zu voxels (%llu written out during the run, beyond "
        "mapping.map_radius_m %g m of the sensor; no raw_map.ply or maps.png)\n",
        s.map_voxels, static_cast<unsigned long long>(s.spilled_voxels),
        config.mapping.map_radius_m);
  } else {
    std::printf("static map       %zu voxels\n", s.map_voxels);
  }
  warn_about_heights(config, s.too_high, s.detections);
  if (s.dropped_points > 0) {
    std::fprintf(stderr,
                 "ringtrack: warning: static map: %zu points lay outside its voxel index "
                 "(+-2^20 voxels of mapping.voxel_size_m about the local origin) and are not in "
                 "it\n",
                 s.dropped_points);
  }
  std::printf("ms per scan      median %.3f, p95 %.3f, max %.3f\n", eval::quantile(s.total_ms, 0.5),
              eval::quantile(s.total_ms, 0.95),
              *std::max_element(s.total_ms.begin(), s.total_ms.end()));
  std::printf(
      "outputs          "
      "%s/"
      "{tracks.csv,timing.csv,static_map.ply,static_map.pcd,poses.txt,config.yaml,run.json%s%s%s%s}"
      "\n",
      o.out.c_str(), odometry ? ",odometry.csv" : "", s.raw_map ? ",raw_map.ply" : "",
      plotted ? ",maps.png" : "", o.filtered_scans ? ",filtered/" : "");
  if (s.mcap) {
    std::printf("mcap             %s (%llu messages, %u chunks, %.1f MB)\n", o.mcap.c_str(),
                static_cast<unsigned long long>(s.mcap->messages), s.mcap->chunks,
                static_cast<double>(s.mcap->file_bytes) / 1e6);
  }
}

// The run's summary on stdout (and its warnings on stderr).
void print_summary(const RunOptions& o, const core::Config& config, bool odometry,
                   const runner::RunInput& input, const io::RunStatus& status,
                   const runner::RunSummary& s, bool plotted) {
  const std::string signal = StopSignals::signal_name();
  if (const auto summary = input.summary(); !summary.empty())
    std::printf("input            %s\n", summary.c_str());
  std::printf(
      "scans            %zu%s%s\n", s.scans, skipped_note(status).c_str(),
      signal.empty()
          ? ""
          : (" (interrupted by " + signal + ": the outputs cover these scans only)").c_str());
  std::printf("poses            %s\n", input.pose_summary(o.odometry).c_str());
  if (!s.origin.isZero()) {
    std::printf(
        "frame            tracks.csv and poses.txt in the poses' frame; maps%s in the local frame "
        "at origin (%.3f, %.3f, %.3f) m (docs/inputs.md, \"Frames\")\n",
        s.mcap ? " and MCAP" : "", s.origin.x(), s.origin.y(), s.origin.z());
  }
  if (odometry) print_odometry_summary(s);
  std::printf("deskew           %s\n", input.deskew_summary().c_str());
  print_results(o, config, odometry, s, plotted);
}

// The run proper, once the output folder and its run.json exist; keeps `status` up to date.
void run_into(const RunOptions& o, const core::Config& config, bool odometry, io::RunStatus& status,
              SkipWarnings& warnings, runner::RunInput& input) {
  const bool progress = !o.quiet && isatty(STDERR_FILENO);
  const auto start = std::chrono::steady_clock::now();
  runner::RunOptions options = runner_options(o, odometry, warnings);
  if (progress) {
    options.on_scan = [&input, start](std::size_t index, const pipeline::FrameResult&,
                                      const std::vector<io::TrackRow>&) {
      print_progress(index + 1, input.size(), start);
    };
  }
  runner::Run run(input, config, std::move(options), &status);
  while (run.step()) {
  }
  // With no scan, finish() reports "no scans found" before any warning (as it always did).
  if (run.scans() > 0) {
    if (const auto warning = input.warning(); !warning.empty()) {
      std::fprintf(stderr, "ringtrack: warning: %s\n", warning.c_str());
    }
    if (progress) std::fprintf(stderr, "\n");
  }
  const runner::RunSummary summary = run.finish();
  const bool plotted =
      summary.raw_map &&
      run_plot_script("plot_maps.py", {fs::path(o.out), fs::path(o.out) / "maps.png"});
  print_summary(o, config, odometry, input, status, summary, plotted);
}

void run(const RunOptions& o) {
  // For the whole command: a signal while the maps are written still lets them finish.
  const StopSignals stop_signals;
  // The two pose sources are checked before the configuration and the input are read.
  if (o.odometry == "on" && !o.poses.empty())
    (void)runner::use_odometry(o.odometry, false, o.poses);
  core::Config config = o.config.load();
  io::RunStatusFile status_file(fs::path(o.out) / "run.json", new_run_status("run", o.input));
  io::RunStatus& status = status_file.status();
  SkipWarnings warnings(o.input);
  runner::RunInput input(o.input, run_input_options(o),
                         [&status, &warnings](std::uint64_t index, const std::string& error) {
                           ++status.scans_skipped_unreadable;
                           status.add_skipped(index, "unreadable: " + error);
                           warnings.warn(index, "unreadable, skipped: " + error);
                         });
  // A simulated sequence knows how high its sensor stands; the user's configuration wins.
  const bool odometry = runner::prepare_run(input, config, o.odometry, o.poses, o.no_deskew,
                                            o.config.sets("detection.sensor_height_m"));

  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec) throw core::InputError(o.out + ": cannot create the output folder: " + ec.message());
  // From here on the folder holds outputs: run.json says whether they are whole.
  status_file.start();
  try {
    run_into(o, config, odometry, status, warnings, input);
  } catch (const std::exception& e) {
    status_file.fail(e.what());
    throw;
  }
  status_file.finish(StopSignals::signal_name());
}

}  // namespace

void register_run(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "run", "run the pipeline over a sequence folder or a folder of organized PCD files");
  auto o = std::make_shared<RunOptions>();
  cmd->add_option(
         "input", o->input,
         "sequence folder or folder of organized PCD files (docs/formats.md), .pcap/.pcapng, "
         ".bag, rosbag2 folder (sqlite3 or mcap), .mcap, or udp://HOST:PORT (docs/inputs.md)")
      ->required();
  o->source.add_to(*cmd);
  cmd->add_option("--on-bad-scan", o->on_bad_scan,
                  "a scan that cannot be read or decoded (a truncated PCD, a corrupt bag "
                  "message): skip it (counted in the summary and run.json) or stop with an error")
      ->check(CLI::IsMember({"skip", "stop"}))
      ->capture_default_str();
  cmd->add_option("--out", o->out, "output folder (created)")->required();
  cmd->add_option("--poses", o->poses,
                  "sensor poses (sensor in world; replaces a sequence's poses.txt)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--poses-format", o->poses_format,
                  "tum (t x y z qx qy qz qw) or kitti (3x4 per scan)")
      ->check(CLI::IsMember({"tum", "kitti"}));
  cmd->add_flag("--filtered-scans", o->filtered_scans,
                "also write each scan (as processed: motion-compensated when deskewed) without its "
                "dynamic-object points as filtered/NNNNNN.pcd");
  cmd->add_flag("--no-deskew", o->no_deskew,
                "do not motion-compensate the scans (by default they are whenever poses give the "
                "sensor's motion, docs/inputs.md)");
  cmd->add_option("--odometry", o->odometry,
                  "estimate the sensor poses from the scans (docs/odometry.md): on; off (poses "
                  "from --poses or the sequence, else a static sensor); auto: on for a recording "
                  "(pcap, bag, udp) without --poses")
      ->check(CLI::IsMember({"auto", "on", "off"}))
      ->capture_default_str();
  cmd->add_option("--odometry-start", o->odometry_start,
                  "TUM trajectory whose pose at the first scan's stamp places the odometry's "
                  "world frame (default: the first scan's frame), e.g. a simulated sequence's "
                  "poses.txt to compare estimates with its ground truth")
      ->check(CLI::ExistingFile);
  cmd->add_option("--mcap", o->mcap,
                  "also write an MCAP file for Foxglove: scans with labels, detections, tracks, "
                  "poses, static map, metadata (docs/visualisation.md)");
  cmd->add_option("--mcap-compression", o->mcap_compression, "MCAP chunk compression")
      ->check(CLI::IsMember({"zstd", "lz4", "none"}));
  cmd->add_option("--mcap-map-every", o->mcap_map_every,
                  "also write the static map to the MCAP every N scans (0: only at the end)");
  cmd->add_flag("--quiet", o->quiet, "no progress on stderr");
  cmd->add_flag("--no-plots", o->no_plots,
                "no raw_map.ply and maps.png (the accumulated raw points beside the static map, "
                "as the paper's Fig. 7; needs python3-matplotlib)");
  o->config.add_to(*cmd);
  cmd->callback([o] { run(*o); });
}

}  // namespace ringtrack::cli
