// ringtrack.run(): a whole run (runner::RunInput + runner::Run) into an output folder, as
// `ringtrack run` does it, returning the figures of its summary.

#include <Python.h>

#include <atomic>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "bindings.hpp"
#include "ringtrack/io/bad_scans.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/runner/run.hpp"
#include "ringtrack/runner/run_input.hpp"

namespace ringtrack::python {
namespace {

// The run's options in the CLI's terms (docs/python.md, "ringtrack.run").
struct PyRunOptions {
  std::string input, out, format, sensor, calibration, metadata, poses, poses_format, odometry,
      mcap, on_bad_scan;
  bool no_deskew{false}, filtered_scans{false}, raw_map{false}, keep_sensor_height{false};
};

runner::RunInputOptions input_options(const PyRunOptions& o) {
  runner::RunInputOptions options;
  options.source.format = io::parse_scan_input_format(o.format);
  options.source.velodyne.decoder.model = o.sensor;
  options.source.calibration = o.calibration;
  options.source.metadata = o.metadata;
  options.poses = o.poses;
  options.poses_format = o.poses_format;
  options.no_deskew = o.no_deskew;
  options.on_bad_scan = io::parse_bad_scan_policy(o.on_bad_scan);
  return options;
}

py::dict summary_dict(const runner::RunSummary& s, const runner::RunInput& input,
                      const std::string& odometry_mode) {
  py::dict d;
  d["scans"] = s.scans;
  d["scans_read"] = input.read();
  d["scans_unreadable"] = input.unreadable();
  d["tracks"] = s.tracks;
  d["dynamic_tracks"] = s.dynamic_tracks;
  d["map_voxels"] = s.map_voxels;
  d["origin"] = py::make_tuple(s.origin.x(), s.origin.y(), s.origin.z());
  d["total_ms"] = s.total_ms;
  d["stopped"] = s.stopped;
  d["odometry_degenerate"] = s.odometry_degenerate;
  d["odometry_weak"] = s.odometry_weak;
  d["poses"] = input.pose_summary(odometry_mode);
  d["deskew"] = input.deskew_summary();
  d["input"] = input.summary();
  d["warning"] = input.warning();
  return d;
}

py::dict run(const PyRunOptions& o, const std::optional<core::Config>& given) {
  // The two pose sources are checked before the input is opened, as `ringtrack run` does.
  (void)runner::use_odometry(o.odometry, false, o.poses);
  core::Config config = given.value_or(core::Config{});
  runner::RunInput input(o.input, input_options(o));
  const bool odometry =
      runner::prepare_run(input, config, o.odometry, o.poses, o.no_deskew, o.keep_sensor_height);
  std::filesystem::create_directories(o.out);
  runner::RunOptions options;
  options.out = o.out;
  options.odometry = odometry;
  options.filtered_scans = o.filtered_scans;
  options.raw_map = o.raw_map;
  options.mcap = o.mcap;
  // Ctrl-C (Python's SIGINT handler) stops the run after the scan at hand, outputs complete.
  std::atomic<bool> stop{false};
  options.stop = &stop;
  options.on_scan = [&stop](std::size_t, const pipeline::FrameResult&,
                            const std::vector<io::TrackRow>&) {
    if (PyErr_CheckSignals() != 0) {
      PyErr_Clear();
      stop = true;
    }
  };
  const runner::RunSummary summary = runner::run(input, config, options);
  return summary_dict(summary, input, o.odometry);
}

}  // namespace

void bind_runner(py::module_& m) {
  m.def(
      "run",
      [](const std::string& input, const std::string& out, std::optional<core::Config> config,
         const std::string& poses, const std::string& poses_format, const std::string& odometry,
         bool no_deskew, bool filtered_scans, bool raw_map, const std::string& mcap,
         const std::string& format, const std::string& sensor, const std::string& calibration,
         const std::string& metadata, const std::string& on_bad_scan, bool keep_sensor_height) {
        const PyRunOptions o{input,       out,       format,         sensor,   calibration,
                             metadata,    poses,     poses_format,   odometry, mcap,
                             on_bad_scan, no_deskew, filtered_scans, raw_map,  keep_sensor_height};
        return run(o, config);
      },
      py::arg("input"), py::arg("out"), py::arg("config") = py::none(), py::arg("poses") = "",
      py::arg("poses_format") = "tum", py::arg("odometry") = "auto", py::arg("no_deskew") = false,
      py::arg("filtered_scans") = false, py::arg("raw_map") = false, py::arg("mcap") = "",
      py::arg("format") = "auto", py::arg("sensor") = "", py::arg("calibration") = "",
      py::arg("metadata") = "", py::arg("on_bad_scan") = "skip",
      py::arg("keep_sensor_height") = false,
      "Runs the pipeline over a recording or sequence folder into the folder `out` as `ringtrack "
      "run` does (tracks.csv, timing.csv, poses.txt, static_map.ply/.pcd, config.yaml, ...) and "
      "returns the summary's figures as a dict (docs/python.md).");
}

}  // namespace ringtrack::python
