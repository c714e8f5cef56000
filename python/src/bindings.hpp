#pragma once
// The pieces of the Python module mbsflow._core, one file each, and what they share.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <Eigen/Core>
#include "mbsflow/error.hpp"
#include <string>
#include <vector>

namespace mbsflow {
struct RunRequest;
}

namespace mbsflow::python {

namespace py = pybind11;

void bind_errors(py::module_& m);
// A setting named in a library message ({name} or {name=value}) as the Python keyword.
std::string keyword_for(const std::string& setting, const std::string* value);
void bind_model(py::module_& m);
// A request from the keywords given at `place` (SettingPlace: in_python for mbsflow.run,
// in_simulation for mbsflow.Simulation), each checked as its declaration says: its type,
// range or choices (InputError naming it and its value, or `caller` and an unknown one).
// None is the default, as not given.
RunRequest request_of(const py::dict& settings, unsigned place, const char* caller);
// The settings given at `place`: (keyword, default, help) each, in declaration order.
py::list settings_of(unsigned place);
void bind_results(py::module_& m);
void bind_run(py::module_& m);
void bind_simulation(py::module_& m);
void bind_ivp(py::module_& m);
void bind_analysis(py::module_& m);

// A numpy array that owns the vector's storage (no copy), in the given C-order shape.
py::array_t<double> to_numpy(std::vector<double>&& values, std::vector<py::ssize_t> shape);
py::array_t<double> to_numpy(const Eigen::VectorXd& values);  // a copy
// A read-only view of `rows` x `cols` doubles at `data` (C order), kept alive by `owner`.
py::array_t<double> readonly_view(const double* data, py::ssize_t rows, py::ssize_t cols, py::handle owner);
// A 1-d float64 vector of any array-like; InputError naming `what` for another size (when size >= 0).
Eigen::VectorXd to_vector(const py::handle& values, Eigen::Index size, const char* what);

}  // namespace mbsflow::python
