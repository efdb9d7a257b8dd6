// Recordings as Python iterators of scans: packet captures, bags and live UDP through
// io::open_source, sequence and PCD folders through io::SequenceReader.

#include <memory>
#include <optional>
#include <string>

#include "bindings.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/core/sensor_model.hpp"
#include "ringtrack/io/scan_source.hpp"
#include "ringtrack/io/sequence.hpp"

namespace ringtrack::python {
namespace {

// A source and the scans it yields; next() releases the GIL while decoding.
class SourceIterator {
 public:
  SourceIterator(const std::string& input, const io::ScanSourceOptions& options)
      : source_(io::open_source(input, options)) {}
  core::OrganizedScan next() {
    std::optional<core::OrganizedScan> scan;
    {
      py::gil_scoped_release release;
      scan = source_->next();
    }
    if (!scan) throw py::stop_iteration();
    return std::move(*scan);
  }
  const core::SensorModel& model() const { return source_->model(); }
  std::string summary() const { return source_->summary(); }
  std::string warning() const { return source_->warning(); }

 private:
  std::unique_ptr<io::ScanSource> source_;
};

class SequenceIterator {
 public:
  SequenceIterator(const std::string& folder, const io::SequenceReadOptions& options)
      : reader_(folder, options) {}
  py::tuple next() {
    io::SequenceScan s;
    bool more = false;
    {
      py::gil_scoped_release release;
      more = reader_.next(s);
    }
    if (!more) throw py::stop_iteration();
    py::object labels =
        s.labels.empty() ? py::object(py::none())
                         : py::object(copy_of(s.labels.data(), {s.scan.rings(), s.scan.columns()}));
    return py::make_tuple(std::move(s.scan), s.pose, labels);
  }
  const io::SequenceReader& reader() const { return reader_; }

 private:
  io::SequenceReader reader_;
};

io::ScanSourceOptions source_options(const std::string& format, const std::string& topic,
                                     const std::string& sensor, const std::string& calibration,
                                     const std::string& metadata, double scan_rate_hz) {
  io::ScanSourceOptions o;
  o.format = io::parse_scan_input_format(format);
  o.topic = topic;
  o.velodyne.decoder.model = sensor;
  o.velodyne.decoder.scan_rate_hz = scan_rate_hz;
  o.calibration = calibration;
  o.metadata = metadata;
  return o;
}

}  // namespace

void bind_sources(py::module_& m) {
  py::class_<SourceIterator>(m, "ScanSource",
                             "Scans of a recording or live sensor, in order (an iterator).")
      .def("__iter__", [](SourceIterator& s) -> SourceIterator& { return s; })
      .def("__next__", &SourceIterator::next)
      .def_property_readonly("model", &SourceIterator::model, "The sensor (after the first scan).")
      .def_property_readonly("summary", &SourceIterator::summary)
      .def_property_readonly("warning", &SourceIterator::warning);
  m.def(
      "open",
      [](const std::string& input, const std::string& format, const std::string& topic,
         const std::string& sensor, const std::string& calibration, const std::string& metadata,
         double scan_rate_hz) {
        return std::make_unique<SourceIterator>(
            input, source_options(format, topic, sensor, calibration, metadata, scan_rate_hz));
      },
      py::arg("input"), py::arg("format") = "auto", py::arg("topic") = "", py::arg("sensor") = "",
      py::arg("calibration") = "", py::arg("metadata") = "", py::arg("scan_rate_hz") = 10.0,
      "Opens a pcap/pcapng capture, a ROS 1 bag, a ROS 2 bag (sqlite3 or MCAP) or udp://HOST:PORT "
      "(docs/inputs.md); Hesai needs calibration=, Ouster metadata=.");

  py::class_<SequenceIterator>(m, "Sequence",
                               "A sequence folder, or a folder of PCD files or KITTI-style .bin "
                               "files: iterates (scan, pose, labels or None).")
      .def(py::init([](const std::string& folder, const std::string& poses,
                       const std::string& poses_format, const std::string& sensor,
                       double scan_rate_hz) {
             io::SequenceReadOptions o;
             o.poses = poses;
             o.scan_rate_hz = scan_rate_hz;
             // Plain folders: the grid clouds without rings are organized into (what `ringtrack
             // run --sensor` gives); without it a sensor measured on the first cloud.
             if (!sensor.empty()) {
               try {
                 o.sensor = core::SensorModel::by_name(sensor, scan_rate_hz);
               } catch (const core::Error& e) {
                 throw core::ConfigError(std::string("sensor: ") + e.what());
               }
             }
             if (poses_format == "kitti") {
               o.poses_format = io::PoseFileFormat::kKitti;
             } else if (poses_format != "tum") {
               throw core::ConfigError("poses_format: expected tum or kitti, got '" + poses_format +
                                       "'");
             }
             return std::make_unique<SequenceIterator>(folder, o);
           }),
           py::arg("folder"), py::arg("poses") = "", py::arg("poses_format") = "tum",
           py::arg("sensor") = "", py::arg("scan_rate_hz") = 10.0,
           "sensor: a built-in model (`ringtrack sensors`, e.g. hdl64e for KITTI) for plain "
           "folders; scan_rate_hz: their stamps (i / rate) without stamps.txt.")
      .def("__iter__", [](SequenceIterator& s) -> SequenceIterator& { return s; })
      .def("__next__", &SequenceIterator::next)
      .def("__len__", [](const SequenceIterator& s) { return s.reader().size(); })
      .def_property_readonly("model", [](const SequenceIterator& s) { return s.reader().sensor(); })
      .def_property_readonly("has_poses",
                             [](const SequenceIterator& s) { return s.reader().has_poses(); })
      .def_property_readonly("sensor_height_m",
                             [](const SequenceIterator& s) -> py::object {
                               const auto h = s.reader().meta().sensor_height_m;
                               return h ? py::object(py::float_(*h)) : py::object(py::none());
                             })
      .def_property_readonly("objects_csv", [](const SequenceIterator& s) -> py::object {
        const auto p = s.reader().objects_csv();
        return p ? py::object(py::str(p->string())) : py::object(py::none());
      });
}

}  // namespace ringtrack::python
