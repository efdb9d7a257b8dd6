#pragma once
// Shared helpers of the pybind11 bindings (one file per area, registered from module.cpp).

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstddef>
#include <nlohmann/json.hpp>
#include <vector>

namespace ringtrack::python {

namespace py = pybind11;

/// A read-only numpy view of a vector owned by `owner` (kept alive by the array): no copy.
template <typename T>
py::array_t<T> view(const std::vector<T>& data, std::vector<py::ssize_t> shape, py::handle owner) {
  py::array_t<T> a(shape, {}, data.data(), owner);
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

/// A numpy array holding a copy of data, with the given shape.
template <typename T>
py::array_t<T> copy_of(const T* data, std::vector<py::ssize_t> shape) {
  py::array_t<T> a(shape);
  std::size_t n = 1;
  for (const py::ssize_t s : shape) n *= static_cast<std::size_t>(s);
  std::copy(data, data + n, a.mutable_data());
  return a;
}

/// A JSON value as the equivalent Python object (dict, list, float, int, str, None).
py::object to_python(const nlohmann::ordered_json& j);

void bind_core(py::module_& m);
void bind_pipeline(py::module_& m);
void bind_sources(py::module_& m);
void bind_runner(py::module_& m);
void bind_sim(py::module_& m);
void bind_experiment(py::module_& m);
void bind_mcap(py::module_& m);

}  // namespace ringtrack::python
