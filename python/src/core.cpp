// Config, SensorModel, Pose and OrganizedScan.

#include <cmath>
#include <sstream>
#include <string>

#include "bindings.hpp"
#include "ringtrack/core/config.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/core/organized_scan.hpp"
#include "ringtrack/core/pose.hpp"
#include "ringtrack/core/sensor_model.hpp"

namespace ringtrack::python {
namespace {

// A Python scalar as the YAML text apply_config_override reads ("true", "0.25", "name").
std::string yaml_scalar(const py::handle& value) {
  if (py::isinstance<py::bool_>(value)) return value.cast<bool>() ? "true" : "false";
  if (py::isinstance<py::int_>(value)) return std::to_string(value.cast<long long>());
  if (py::isinstance<py::float_>(value)) {
    std::ostringstream o;
    o.precision(17);
    o << value.cast<double>();
    return o.str();
  }
  if (py::isinstance<py::str>(value)) return value.cast<std::string>();
  throw core::ConfigError("value of type " +
                          py::str(py::type::handle_of(value).attr("__name__")).cast<std::string>() +
                          " is not a number, bool or string");
}

void set_key(core::Config& c, const std::string& key, const py::handle& value) {
  std::string assignment = key;
  assignment.push_back('=');
  assignment.append(yaml_scalar(value));
  core::apply_config_override(c, assignment);
}

void bind_config(py::module_& m) {
  py::class_<core::Config>(m, "Config",
                           "Every parameter of the pipeline (docs: `ringtrack dump-config`).")
      .def(py::init<>(), "The defaults.")
      .def_static(
          "load",
          [](const std::string& path) {
            core::Config c;
            core::apply_config_file(c, path);
            core::validate_config(c);
            return c;
          },
          py::arg("path"), "Defaults overridden by a YAML file (unknown keys are errors).")
      .def_static(
          "from_yaml",
          [](const std::string& text, const std::string& source) {
            core::Config c;
            core::apply_config_yaml(c, text, source);
            core::validate_config(c);
            return c;
          },
          py::arg("text"), py::arg("source") = "<string>", "Defaults overridden by YAML text.")
      .def("to_yaml", &core::dump_config, "Every key as commented YAML (what dump-config prints).")
      .def("set", &set_key, py::arg("key"), py::arg("value"),
           "Sets one key, e.g. set('tracking.max_missed_scans', 8); ConfigError names a bad key "
           "or value.")
      .def(
          "keys",
          [](const core::Config& c) {
            py::list out;
            for (const core::ConfigKeyInfo& k : core::describe_config(c)) out.append(k.key);
            return out;
          },
          "Every key, \"section.name\".")
      .def(
          "get_text",
          [](const core::Config& c, const std::string& key) {
            for (const core::ConfigKeyInfo& k : core::describe_config(c)) {
              if (k.key == key) return k.value;
            }
            throw core::ConfigError("unknown configuration key '" + key + "'");
          },
          py::arg("key"), "A key's value as YAML text.")
      .def(
          "describe",
          [](const core::Config& c, const std::string& key) {
            for (const core::ConfigKeyInfo& k : core::describe_config(c)) {
              if (k.key == key) return k.description;
            }
            throw core::ConfigError("unknown configuration key '" + key + "'");
          },
          py::arg("key"), "A key's meaning and allowed range.")
      .def("validate", &core::validate_config,
           "Checks relations between keys (e.g. min < max); raises ConfigError.")
      .def("__copy__", [](const core::Config& c) { return core::Config(c); })
      .def("__deepcopy__", [](const core::Config& c, py::dict) { return core::Config(c); });
}

void bind_sensor_model(py::module_& m) {
  py::class_<core::SensorModel>(m, "SensorModel", "A spinning LiDAR's geometry and timing.")
      .def_static("by_name", &core::SensorModel::by_name, py::arg("name"),
                  py::arg("scan_rate_hz") = 10.0,
                  "vlp16, vlp32c, hdl32e, hdl64e (`ringtrack sensors`)")
      .def_static("vlp16", &core::SensorModel::vlp16, py::arg("scan_rate_hz") = 10.0)
      .def_readonly("name", &core::SensorModel::name)
      .def_property_readonly("rings", &core::SensorModel::rings)
      .def_property_readonly("columns", &core::SensorModel::columns)
      .def_readonly("min_range_m", &core::SensorModel::min_range_m)
      .def_readonly("max_range_m", &core::SensorModel::max_range_m)
      .def_readonly("scan_rate_hz", &core::SensorModel::scan_rate_hz)
      .def_readonly("vertical_offset_m", &core::SensorModel::vertical_offset_m,
                    "Per ring, bottom to top: the beam origin's height above the sensor origin.")
      .def_property_readonly("elevation_deg", [](const core::SensorModel& s) {
        std::vector<double> deg;
        for (const double r : s.elevation_rad) deg.push_back(r * 180.0 / M_PI);
        return deg;
      });
}

void bind_pose(py::module_& m) {
  py::class_<core::Pose>(m, "Pose", "Sensor in world: a rotation and a translation (metres).")
      .def(py::init([](const Eigen::Vector3d& t, const Eigen::Vector4d& q_wxyz) {
             const Eigen::Quaterniond q(q_wxyz[0], q_wxyz[1], q_wxyz[2], q_wxyz[3]);
             if (!t.allFinite() || !q.coeffs().allFinite() || q.norm() < 1e-9) {
               throw core::InputError(
                   "pose: translation and quaternion must be finite and the "
                   "quaternion non-zero");
             }
             core::Pose p;
             p.translation = t;
             p.rotation = q.normalized();
             return p;
           }),
           py::arg("translation") = Eigen::Vector3d::Zero(),
           py::arg("quaternion_wxyz") = Eigen::Vector4d(1, 0, 0, 0))
      .def_static(
          "from_matrix",
          [](const Eigen::Matrix4d& t) {
            if (!t.allFinite()) throw core::InputError("pose: matrix is not finite");
            core::Pose p;
            p.translation = t.block<3, 1>(0, 3);
            p.rotation = Eigen::Quaterniond(Eigen::Matrix3d(t.block<3, 3>(0, 0))).normalized();
            return p;
          },
          py::arg("matrix"), "From a 4x4 homogeneous transform.")
      .def("matrix", [](const core::Pose& p) { return Eigen::Matrix4d(p.isometry().matrix()); })
      .def_readwrite("translation", &core::Pose::translation)
      .def_property_readonly("quaternion_wxyz", [](const core::Pose& p) {
        return Eigen::Vector4d(p.rotation.w(), p.rotation.x(), p.rotation.y(), p.rotation.z());
      });
}

py::array_t<float> grid_view(const core::OrganizedScan& s, const std::vector<float>& v,
                             py::handle owner) {
  return view(v, {s.rings(), s.columns()}, owner);
}

// A property returning one of the scan's per-cell float arrays as a (rings, columns) view.
auto grid_property(const std::vector<float>& (core::OrganizedScan::*array)() const) {
  return [array](py::object self) {
    const auto& s = self.cast<const core::OrganizedScan&>();
    return grid_view(s, (s.*array)(), self);
  };
}

core::OrganizedScan scan_from_ranges(
    const core::SensorModel& model,
    py::array_t<float, py::array::c_style | py::array::forcecast> ranges,
    std::optional<py::array_t<float, py::array::c_style | py::array::forcecast>> intensity,
    std::int64_t stamp_ns) {
  const int rings = model.rings(), cols = model.columns();
  if (ranges.ndim() != 2 || ranges.shape(0) != rings || ranges.shape(1) != cols) {
    throw core::InputError("ranges: expected shape (" + std::to_string(rings) + ", " +
                           std::to_string(cols) + ") for " + model.name);
  }
  if (intensity &&
      (intensity->ndim() != 2 || intensity->shape(0) != rings || intensity->shape(1) != cols)) {
    throw core::InputError("intensity: expected the shape of ranges");
  }
  core::OrganizedScan scan(rings, cols);
  scan.set_uniform_columns(model, stamp_ns);
  const float* r = ranges.data();
  const float* in = intensity ? intensity->data() : nullptr;
  for (int ring = 0; ring < rings; ++ring) {
    for (int c = 0; c < cols; ++c) {
      const std::size_t i = scan.index(ring, c);
      scan.set_range(model, ring, c, r[i], in ? in[i] : 0.0f);
    }
  }
  return scan;
}

void bind_scan(py::module_& m) {
  py::enum_<core::ReturnStatus>(m, "ReturnStatus")
      .value("NO_RETURN", core::ReturnStatus::kNoReturn)
      .value("VALID", core::ReturnStatus::kValid)
      .value("TOO_CLOSE", core::ReturnStatus::kTooClose)
      .value("TOO_FAR", core::ReturnStatus::kTooFar);
  py::class_<core::OrganizedScan>(
      m, "OrganizedScan",
      "One revolution as rings x columns (ring 0 at the bottom). Array properties are read-only "
      "numpy views of the scan's memory (no copy); copy them to keep them past the scan.")
      .def_static("from_ranges", &scan_from_ranges, py::arg("model"), py::arg("ranges"),
                  py::arg("intensity") = py::none(), py::arg("stamp_ns") = 0,
                  "A scan from a (rings, columns) range image in metres (NaN or 0: no return), "
                  "points computed from the model's geometry.")
      .def_property_readonly("rings", &core::OrganizedScan::rings)
      .def_property_readonly("columns", &core::OrganizedScan::columns)
      .def_readonly("stamp_ns", &core::OrganizedScan::stamp_ns)
      .def_property_readonly("ranges", grid_property(&core::OrganizedScan::ranges))
      .def_property_readonly("intensity", grid_property(&core::OrganizedScan::intensities))
      .def_property_readonly("x", grid_property(&core::OrganizedScan::xs))
      .def_property_readonly("y", grid_property(&core::OrganizedScan::ys))
      .def_property_readonly("z", grid_property(&core::OrganizedScan::zs))
      .def_property_readonly(
          "status",
          [](py::object self) {
            const auto& s = self.cast<const core::OrganizedScan&>();
            const auto* p = reinterpret_cast<const std::uint8_t*>(s.statuses().data());
            py::array_t<std::uint8_t> a({s.rings(), s.columns()}, {}, p, self);
            a.attr("setflags")(py::arg("write") = false);
            return a;
          },
          "Per cell: ReturnStatus values (1 = valid).")
      .def_property_readonly("column_stamp_ns",
                             [](py::object self) {
                               const auto& s = self.cast<const core::OrganizedScan&>();
                               return view(s.column_stamp_ns, {s.columns()}, self);
                             })
      .def(
          "points",
          [](const core::OrganizedScan& s) {
            std::vector<float> xyz;
            xyz.reserve(s.size() * 3);
            for (std::size_t i = 0; i < s.size(); ++i) {
              if (!s.valid(i)) continue;
              xyz.insert(xyz.end(), {s.xs()[i], s.ys()[i], s.zs()[i]});
            }
            return copy_of(xyz.data(), {static_cast<py::ssize_t>(xyz.size() / 3), 3});
          },
          "The valid points, (N, 3) float32 in the sensor frame (a copy).")
      .def("valid_count", &core::OrganizedScan::valid_count);
}

}  // namespace

void bind_core(py::module_& m) {
  bind_config(m);
  bind_sensor_model(m);
  bind_pose(m);
  bind_scan(m);
}

}  // namespace ringtrack::python
