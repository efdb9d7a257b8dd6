// The simulator: built-in scenarios and scenario files as iterators of labelled scans.

#include <filesystem>
#include <optional>
#include <string>

#include "bindings.hpp"
#include "ringtrack/sim/scenario.hpp"
#include "ringtrack/sim/scenario_file.hpp"
#include "ringtrack/sim/simulator.hpp"
#include "sim_scenario.hpp"

namespace ringtrack::python {

sim::Scenario scenario_from(const std::string& name_or_file, std::optional<double> duration_s,
                            bool moving) {
  const bool file = name_or_file.size() > 5 &&
                    (name_or_file.ends_with(".yaml") || name_or_file.ends_with(".yml"));
  sim::Scenario s =
      file ? sim::load_scenario_file(name_or_file) : sim::builtin_scenario(name_or_file);
  if (duration_s) s.duration_s = *duration_s;
  if (moving && s.sensor.motion == sim::SensorMotion::kStatic) s = sim::with_moving_sensor(s);
  sim::validate(s, s.name);
  return s;
}

namespace {

py::dict object_dict(const sim::ObjectTruth& o) {
  py::dict d;
  d["id"] = o.id;
  d["class"] = std::string(sim::class_name(o.object_class));
  d["hit_points"] = o.hit_points;
  d["centroid"] = o.centroid_m;
  d["body_center"] = o.body_center_m;
  d["velocity_mps"] = o.velocity_mps;
  d["moving"] = o.moving;
  return d;
}

class SimulatorIterator {
 public:
  SimulatorIterator(const sim::Scenario& s, std::uint64_t seed) : simulator_(s, seed) {}
  py::object next() {
    if (simulator_.next_index() >= simulator_.scan_count()) throw py::stop_iteration();
    sim::SimulatedScan s;
    {
      py::gil_scoped_release release;
      simulator_.next(s);
    }
    py::dict out;
    out["index"] = s.index;
    out["labels"] = copy_of(s.labels.data(), {s.scan.rings(), s.scan.columns()});
    out["pose"] = s.pose;
    py::list objects;
    for (const sim::ObjectTruth& o : s.objects) objects.append(object_dict(o));
    out["objects"] = objects;
    out["scan"] = std::move(s.scan);
    return out;
  }
  const sim::Simulator& simulator() const { return simulator_; }

 private:
  sim::Simulator simulator_;
};

}  // namespace

void bind_sim(py::module_& m) {
  m.def(
      "scenarios",
      [] {
        py::list out;
        for (const sim::ScenarioInfo& i : sim::builtin_scenarios()) {
          py::dict d;
          d["number"] = i.number;
          d["name"] = i.name;
          d["description"] = i.description;
          out.append(d);
        }
        return out;
      },
      "The built-in scenarios (docs/simulator.md).");
  py::class_<SimulatorIterator>(
      m, "Simulator",
      "Simulated VLP-16 scans of a scenario: iterates dicts with scan, labels (object id per "
      "cell), pose and objects (ground truth).")
      .def(py::init([](const std::string& scenario, std::uint64_t seed,
                       std::optional<double> duration_s, bool moving) {
             return std::make_unique<SimulatorIterator>(scenario_from(scenario, duration_s, moving),
                                                        seed);
           }),
           py::arg("scenario"), py::arg("seed") = 1, py::arg("duration_s") = py::none(),
           py::arg("moving") = false,
           "scenario: a built-in's number or name, or a scenario file (.yaml); moving: the "
           "sensor on its figure 8.")
      .def("__iter__", [](SimulatorIterator& s) -> SimulatorIterator& { return s; })
      .def("__next__", &SimulatorIterator::next)
      .def("__len__", [](const SimulatorIterator& s) { return s.simulator().scan_count(); })
      .def_property_readonly("model",
                             [](const SimulatorIterator& s) { return s.simulator().model(); })
      .def(
          "sensor_pose_at",
          [](const SimulatorIterator& s, std::int64_t t_ns) {
            return s.simulator().sensor_pose_at(t_ns);
          },
          py::arg("t_ns"), "The sensor's true pose at a time (for deskewing).");
}

}  // namespace ringtrack::python
