// Pipeline and what one scan produced (copied out of the pipeline's buffers, so a frame stays
// valid after the next scan).

#include "ringtrack/pipeline/pipeline.hpp"

#include <string>

#include "bindings.hpp"
#include "ringtrack/core/error.hpp"

namespace ringtrack::python {
namespace {

// Positions are in the world frame of the poses, in double: the pipeline's local frame plus its
// origin (UTM-scale worlds need more than float's 24 bits).
struct Detection {
  Eigen::Vector3d centroid;
  Eigen::Vector3d box_min, box_max;
  std::vector<std::uint32_t> cells;
  bool relaxed{false}, sparse{false};
};

struct Track {
  std::uint64_t id{0};
  Eigen::Vector3d position, velocity_mps;
  Eigen::Vector3d box_min, box_max;
  bool dynamic{false}, ever_dynamic{false}, person{false}, confirmed{false}, reported{false};
  int age_scans{0}, missed_scans{0}, hits{0};
  std::size_t points{0};
};

struct Frame {
  std::int64_t stamp_ns{0};
  int rings{0}, columns{0};
  std::vector<std::uint8_t> segment_labels;
  std::vector<Detection> detections;
  std::vector<Track> tracks;
  std::vector<std::uint32_t> removed_cells;
  std::size_t retroactive_points{0};
  Eigen::Vector3d origin{Eigen::Vector3d::Zero()};
  pipeline::StageTimes times;
  bool skipped{false};
  std::string skip_reason;
};

Frame snapshot(const pipeline::FrameResult& r, const core::OrganizedScan& scan) {
  Frame f;
  f.stamp_ns = r.stamp_ns;
  f.rings = scan.rings();
  f.columns = scan.columns();
  f.segment_labels.assign(r.segment_labels.begin(), r.segment_labels.end());
  const Eigen::Vector3d& o = r.origin;
  const auto world = [&o](const Eigen::Vector3f& p) -> Eigen::Vector3d {
    return p.cast<double>() + o;
  };
  f.origin = o;
  for (const core::Detection& d : r.detections) {
    f.detections.push_back({world(d.object_centroid()), world(d.box.min), world(d.box.max),
                            d.indices, d.relaxed, d.sparse});
    Detection& last = f.detections.back();
    last.cells.insert(last.cells.end(), d.completion.begin(), d.completion.end());
  }
  for (const tracking::Hypothesis& h : r.hypotheses) {
    f.tracks.push_back({h.id, h.reported_position + o, h.velocity_mps, world(h.box.min),
                        world(h.box.max), h.dynamic, h.ever_dynamic, h.person, h.confirmed,
                        h.reported, h.age_scans, h.missed_scans, h.hits, h.points});
  }
  f.removed_cells.assign(r.removed_cells.begin(), r.removed_cells.end());
  f.retroactive_points = r.retroactive_points;
  f.times = r.times;
  f.skipped = r.skipped;
  f.skip_reason = r.skip_reason;
  return f;
}

void bind_frame(py::module_& m) {
  py::class_<Detection>(m, "Detection", "A detected object (world frame).")
      .def_readonly("centroid", &Detection::centroid, "Mean of its cells' points, m.")
      .def_readonly("box_min", &Detection::box_min)
      .def_readonly("box_max", &Detection::box_max)
      .def_property_readonly(
          "cells",
          [](const Detection& d) {
            return copy_of(d.cells.data(), {static_cast<py::ssize_t>(d.cells.size())});
          },
          "Grid cells (ring * columns + column), completion cells included.")
      .def_readonly("relaxed", &Detection::relaxed)
      .def_readonly("sparse", &Detection::sparse);
  py::class_<Track>(m, "Track", "A track hypothesis after the scan's update (world frame).")
      .def_readonly("id", &Track::id)
      .def_readonly("position", &Track::position, "Reported position, m.")
      .def_readonly("velocity_mps", &Track::velocity_mps)
      .def_readonly("box_min", &Track::box_min)
      .def_readonly("box_max", &Track::box_max)
      .def_readonly("dynamic", &Track::dynamic)
      .def_readonly("ever_dynamic", &Track::ever_dynamic)
      .def_readonly("person", &Track::person)
      .def_readonly("confirmed", &Track::confirmed)
      .def_readonly("reported", &Track::reported, "What tracks.csv lists.")
      .def_readonly("age_scans", &Track::age_scans)
      .def_readonly("missed_scans", &Track::missed_scans)
      .def_readonly("hits", &Track::hits)
      .def_readonly("points", &Track::points)
      .def("__repr__", [](const Track& t) {
        return "<Track " + std::to_string(t.id) + (t.dynamic ? " dynamic" : " static") + ">";
      });
  py::class_<Frame>(m, "Frame", "What the pipeline made of one scan (a copy).")
      .def_readonly("stamp_ns", &Frame::stamp_ns)
      .def_property_readonly(
          "segment_labels",
          [](const Frame& f) {
            if (f.segment_labels.empty()) return py::array_t<std::uint8_t>();
            return copy_of(f.segment_labels.data(), {f.rings, f.columns});
          },
          "(rings, columns) uint8: 1 where the cell's point is in a segment.")
      .def_readonly("detections", &Frame::detections)
      .def_readonly("tracks", &Frame::tracks, "Every hypothesis; reported ones are the output.")
      .def_property_readonly("reported_tracks",
                             [](const Frame& f) {
                               std::vector<Track> out;
                               for (const Track& t : f.tracks) {
                                 if (t.reported) out.push_back(t);
                               }
                               return out;
                             })
      .def_property_readonly("removed_cells",
                             [](const Frame& f) {
                               return copy_of(f.removed_cells.data(),
                                              {static_cast<py::ssize_t>(f.removed_cells.size())});
                             })
      .def_readonly("retroactive_points", &Frame::retroactive_points)
      .def_readonly("origin", &Frame::origin,
                    "Origin of the pipeline's local frame in the world frame (m); positions here "
                    "are already in the world frame.")
      .def_property_readonly("times_ms",
                             [](const Frame& f) {
                               py::dict d;
                               d["segmentation"] = f.times.segmentation_ms;
                               d["detection"] = f.times.detection_ms;
                               d["tracking"] = f.times.tracking_ms;
                               d["mapping"] = f.times.mapping_ms;
                               d["odometry"] = f.times.odometry_ms;
                               d["total"] = f.times.total_ms;
                               return d;
                             })
      .def_readonly("skipped", &Frame::skipped)
      .def_readonly("skip_reason", &Frame::skip_reason);
}

// A scan of another sensor's size would be read out of bounds by the stages.
void check_scan_fits(const pipeline::Pipeline& p, const core::OrganizedScan& scan) {
  const core::SensorModel& model = p.sensor_model();
  if (scan.rings() == model.rings() && scan.columns() == model.columns()) return;
  throw core::InputError("scan of " + std::to_string(scan.rings()) + " x " +
                         std::to_string(scan.columns()) + " cells; the pipeline's sensor has " +
                         std::to_string(model.rings()) + " x " + std::to_string(model.columns()));
}

// Voxel means as an (N, 3) float64 array in the world frame (local + origin).
py::array_t<double> world_points(const std::vector<mapping::MapPoint>& points,
                                 const Eigen::Vector3d& origin) {
  py::array_t<double> xyz({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto a = xyz.mutable_unchecked<2>();
  for (std::size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      a(static_cast<py::ssize_t>(i), k) = static_cast<double>(points[i].position[k]) + origin[k];
    }
  }
  return xyz;
}

}  // namespace

void bind_pipeline(py::module_& m) {
  bind_frame(m);
  py::class_<pipeline::Pipeline>(m, "Pipeline",
                                 "Segmentation, detection, tracking and the dynamic-object filter "
                                 "for one sensor stream.")
      .def(py::init<const core::Config&, core::SensorModel>(), py::arg("config"), py::arg("model"))
      .def(
          "process",
          [](pipeline::Pipeline& p, const core::OrganizedScan& scan, const core::Pose& pose) {
            check_scan_fits(p, scan);
            py::gil_scoped_release release;
            return snapshot(p.process(scan, pose), scan);
          },
          py::arg("scan"), py::arg("pose") = core::Pose(),
          "Processes one scan taken at pose (sensor in world) and returns its Frame.")
      .def(
          "process_with_odometry",
          [](pipeline::Pipeline& p, core::OrganizedScan& scan) {
            check_scan_fits(p, scan);
            py::gil_scoped_release release;
            return snapshot(p.process_with_odometry(scan), scan);
          },
          py::arg("scan"),
          "Processes a scan without a pose: the LiDAR odometry estimates it (docs/odometry.md) "
          "and motion-compensates the scan in place; odometry_result tells the pose and how "
          "reliable it is. Do not mix with process() on one pipeline.")
      .def("set_odometry_start", &pipeline::Pipeline::set_odometry_start, py::arg("pose"),
           "The first scan's pose in the world the odometry reports in (default identity); call "
           "before the first process_with_odometry().")
      .def_property_readonly(
          "odometry_result",
          [](const pipeline::Pipeline& p) {
            const odometry::OdometryResult& r = p.odometry_result();
            py::dict d;
            d["pose"] = r.pose;
            d["first"] = r.first;
            d["registered"] = r.registered;
            d["degenerate"] = r.degenerate;
            d["weak"] = r.weak;
            d["weakest_share"] = r.weakest_share;
            d["iterations"] = r.iterations;
            d["source_points"] = r.source_points;
            d["correspondences"] = r.correspondences;
            d["excluded_points"] = r.excluded_points;
            d["threshold_m"] = r.threshold_m;
            return d;
          },
          "The odometry's account of the last scan: pose (world_T_sensor), registered, "
          "degenerate (unreliable), ...")
      .def("finish", &pipeline::Pipeline::finish, py::call_guard<py::gil_scoped_release>(),
           "Moves the scans the filter still holds into the static map.")
      .def_property_readonly("skipped_scans", &pipeline::Pipeline::skipped_scans)
      .def_property_readonly(
          "origin", [](const pipeline::Pipeline& p) -> Eigen::Vector3d { return p.origin(); },
          "Origin of the local frame the pipeline works in (the first pose rounded to 100 m), "
          "in the world frame of the poses (m).")
      .def(
          "static_map",
          [](const pipeline::Pipeline& p) {
            return world_points(p.static_map().points(), p.origin());
          },
          "The static map's voxel means, (N, 3) float64, in the world frame of the poses "
          "(complete after finish(); with mapping.map_radius_m, the part still in memory).")
      .def(
          "evicted_map",
          [](const pipeline::Pipeline& p) {
            return world_points(p.dynamic_filter().evicted(), p.origin());
          },
          "The static-map voxels the last process() moved out of memory for lying beyond "
          "mapping.map_radius_m of the sensor, (N, 3) float64, world frame: take them after "
          "every call to keep the whole map.");
}

}  // namespace ringtrack::python
