// McapWriter: the pipeline's results as an MCAP file for Foxglove (io::FoxgloveSink, what
// `ringtrack run --mcap` writes; docs/visualisation.md).

#include <map>
#include <memory>
#include <optional>
#include <string>

#include "bindings.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/io/foxglove_sink.hpp"
#include "ringtrack/pipeline/pipeline.hpp"
#include "ringtrack/version.hpp"

namespace ringtrack::python {
namespace {

// The sink, with what finishing needs: the last pipeline written from (kept alive by Python)
// and the last scan's stamp. A writer dropped without finish() removes its file (no partial
// output passed off as complete).
class McapOutput {
 public:
  McapOutput(const std::string& path, const std::string& compression, std::uint32_t map_every)
      : path_(path) {
    io::FoxgloveSinkOptions options;
    options.mcap.compression = io::parse_mcap_compression(compression);
    options.mcap.library = std::string("ringtrack ") + kVersion;
    options.map_every_scans = map_every;
    sink_ = std::make_unique<io::FoxgloveSink>(path, options);
    sink_->write_metadata("ringtrack", {{"version", kVersion}, {"command", "python"}});
  }

  void write_metadata(const std::string& name, const std::map<std::string, std::string>& entries) {
    open_sink().write_metadata(name, io::McapStringMap(entries.begin(), entries.end()));
  }

  // The frame of the scan `pipeline` processed last, taken at world_pose.
  void write(const py::object& pipeline_object, const core::OrganizedScan& scan,
             const core::Pose& world_pose) {
    io::FoxgloveSink& sink = open_sink();
    const auto& pipeline = pipeline_object.cast<const pipeline::Pipeline&>();
    const pipeline::FrameResult& result = pipeline.last_result();
    if (result.stamp_ns != scan.stamp_ns) {
      throw core::InputError(path_ +
                             ": write() takes the scan the pipeline processed last (stamp " +
                             std::to_string(result.stamp_ns) + " ns), not one stamped " +
                             std::to_string(scan.stamp_ns) + " ns");
    }
    if (result.skipped) return;  // as `run`: a skipped scan has no result to show
    sink.write_pipeline_frame(scan, world_pose, result, pipeline.static_map());
    pipeline_ = pipeline_object;
    last_stamp_ns_ = scan.stamp_ns;
  }

  // Writes the final map of the last pipeline written from and closes the file.
  void finish() {
    io::FoxgloveSink& sink = open_sink();
    if (pipeline_.is_none()) {
      throw core::InputError(path_ + ": finish() before any scan was written");
    }
    sink.finish(pipeline_.cast<const pipeline::Pipeline&>().static_map(), last_stamp_ns_);
    finished_ = true;
  }

  // Drops an unfinished file (an exception left the with-block).
  void abandon() {
    if (!finished_) sink_.reset();
  }

  [[nodiscard]] py::dict stats() const {
    py::dict d;
    if (sink_ == nullptr) return d;
    d["scans"] = sink_->stats().scans;
    d["points"] = sink_->stats().points;
    d["track_entities"] = sink_->stats().track_entities;
    d["maps"] = sink_->stats().maps;
    d["messages"] = sink_->mcap_stats().messages;
    d["chunks"] = sink_->mcap_stats().chunks;
    d["file_bytes"] = sink_->mcap_stats().file_bytes;
    return d;
  }

  [[nodiscard]] bool finished() const { return finished_; }

 private:
  io::FoxgloveSink& open_sink() {
    if (finished_ || sink_ == nullptr) {
      throw core::Error(path_ + ": the MCAP writer is closed");
    }
    return *sink_;
  }

  std::string path_;
  std::unique_ptr<io::FoxgloveSink> sink_;
  py::object pipeline_ = py::none();
  std::int64_t last_stamp_ns_{0};
  bool finished_{false};
};

}  // namespace

void bind_mcap(py::module_& m) {
  py::class_<McapOutput>(
      m, "McapWriter",
      "The pipeline's results as one MCAP file for Foxglove, as `ringtrack run --mcap` writes it "
      "(docs/visualisation.md): call write(pipeline, scan, pose) after each "
      "pipeline.process(scan, pose), then finish() (or use it in a with-block, which finishes "
      "it; an exception inside the block removes the unfinished file).")
      .def(py::init<const std::string&, const std::string&, std::uint32_t>(), py::arg("path"),
           py::arg("compression") = "zstd", py::arg("map_every_scans") = 0,
           "Creates the file; compression: zstd, lz4 or none; map_every_scans: also write the "
           "static map every N scans (0: at the end only).")
      .def("write_metadata", &McapOutput::write_metadata, py::arg("name"), py::arg("entries"),
           "Writes a Metadata record of string entries (e.g. your experiment's settings).")
      .def("write", &McapOutput::write, py::arg("pipeline"), py::arg("scan"),
           py::arg("pose") = core::Pose(),
           "Writes the scan the pipeline processed last, taken at pose (world frame, as given to "
           "process): labelled cloud, detections, tracks, the pose; skipped scans are not written.")
      .def("finish", &McapOutput::finish,
           "Writes the final static map (call pipeline.finish() first) and closes the file.")
      .def_property_readonly("stats", &McapOutput::stats,
                             "Counts written so far: scans, points, messages, chunks, ...")
      .def("__enter__", [](McapOutput& w) -> McapOutput& { return w; })
      .def("__exit__",
           [](McapOutput& w, const py::object& type, const py::object&, const py::object&) {
             if (!type.is_none()) {
               w.abandon();
             } else if (!w.finished()) {
               w.finish();
             }
             return false;
           });
}

}  // namespace ringtrack::python
