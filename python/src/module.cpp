// mbsflow._core: the library for Python (pybind11). The package mbsflow (python/mbsflow/)
// builds its API on it.
#include "bindings.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/version.hpp"

namespace mbsflow::python {

py::array_t<double> to_numpy(std::vector<double>&& values, std::vector<py::ssize_t> shape) {
  auto* owned = new std::vector<double>(std::move(values));
  py::capsule free(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>(std::move(shape), owned->data(), free);
}

py::array_t<double> to_numpy(const Eigen::VectorXd& values) {
  return to_numpy(std::vector<double>(values.data(), values.data() + values.size()), {values.size()});
}

py::array_t<double> readonly_view(const double* data, py::ssize_t rows, py::ssize_t cols, py::handle owner) {
  py::array_t<double> a({rows, cols}, {static_cast<py::ssize_t>(sizeof(double)) * cols, static_cast<py::ssize_t>(sizeof(double))},
                        data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

Eigen::VectorXd to_vector(const py::handle& values, Eigen::Index size, const char* what) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!a) throw InputError(std::string(what) + ": not an array of numbers");
  if (a.ndim() > 1 || (size >= 0 && a.size() != size))
    throw InputError(std::string(what) + ": " + std::to_string(a.size()) + " values where " + std::to_string(size) +
                     " are needed");
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.size());
}

}  // namespace mbsflow::python

PYBIND11_MODULE(_core, m) {
  using namespace mbsflow::python;
  m.doc() = "mbsflow: multibody dynamics and large ODE systems (the compiled part; use the package mbsflow)";
  m.attr("__version__") = MBSFLOW_VERSION;
  bind_errors(m);
  bind_model(m);
  bind_results(m);
  bind_run(m);
  bind_simulation(m);
  bind_ivp(m);
  bind_analysis(m);
}
