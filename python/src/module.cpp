// The `ringtrack._ringtrack` extension: bindings over the C++ library (docs/python.md). C++
// exceptions become Python exceptions with the same text: core::ConfigError -> ConfigError,
// core::InputError -> InputError (both ValueError), anything else -> RuntimeError.

#include "bindings.hpp"
#include "ringtrack/core/error.hpp"
#include "ringtrack/version.hpp"

namespace ringtrack::python {

py::object to_python(const nlohmann::ordered_json& j) {
  // Imported per call (sys.modules makes it cheap): a static py::object would be destroyed
  // after the interpreter finalised.
  return py::module_::import("json").attr("loads")(j.dump());
}

}  // namespace ringtrack::python

PYBIND11_MODULE(_ringtrack, m) {
  namespace py = pybind11;
  using namespace ringtrack::python;
  m.doc() = "ringtrack: detect and track people in spinning-LiDAR scans (C++ bindings)";
  m.attr("__version__") = ringtrack::kVersion;
  // What ringtrack.config_dir (__init__.py) chooses from: the build tree's package reads the
  // source tree's config/, an installed one <prefix>/share/ringtrack/config, found relative to the
  // package so that the prefix can move (docs/python.md, "Installing").
  m.attr("_source_config_dir") = RINGTRACK_SOURCE_CONFIG_DIR;
  m.attr("_build_package_dir") = RINGTRACK_BUILD_PACKAGE_DIR;
  m.attr("_installed_config_dir") = RINGTRACK_INSTALLED_CONFIG_DIR;
  static py::exception<ringtrack::core::ConfigError> config_error(m, "ConfigError",
                                                                  PyExc_ValueError);
  static py::exception<ringtrack::core::InputError> input_error(m, "InputError", PyExc_ValueError);
  // pybind11's translator type is a plain function pointer taking the std::exception_ptr by value.
  // NOLINTNEXTLINE(performance-unnecessary-value-param)
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ringtrack::core::ConfigError& e) {
      config_error(e.what());
    } catch (const ringtrack::core::InputError& e) {
      input_error(e.what());
    }
  });
  bind_core(m);
  bind_pipeline(m);
  bind_sources(m);
  bind_runner(m);
  bind_sim(m);
  bind_experiment(m);
  bind_mcap(m);
}
