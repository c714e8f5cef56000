// The results file for Python: ResultsFile's reads as numpy arrays (mbsflow.Results in
// python/mbsflow/results.py builds on it).
#include "bindings.hpp"
#include "mbsflow/io/results_file.hpp"

namespace mbsflow::python {
namespace {

std::vector<py::ssize_t> shape_of(const ResultsFile& f, const std::string& dataset) {
  std::vector<py::ssize_t> shape;
  for (std::uint64_t n : f.shape(dataset)) shape.push_back(static_cast<py::ssize_t>(n));
  return shape;
}

}  // namespace

void bind_results(py::module_& m) {
  py::class_<ResultsFile>(m, "ResultsFile", "A results file of mbsflow run or mbsflow ode, open for reading.")
      .def(py::init<const std::string&>(), py::arg("path"))
      .def_property_readonly("path", &ResultsFile::path)
      .def_property_readonly("ode", &ResultsFile::ode)
      .def_property_readonly("live", &ResultsFile::live)
      .def("has", &ResultsFile::has, py::arg("dataset"))
      .def("shape", &shape_of, py::arg("dataset"))
      .def("time", [](const ResultsFile& f) {
        std::vector<double> t = f.time();
        const auto n = static_cast<py::ssize_t>(t.size());
        return to_numpy(std::move(t), {n});
      })
      .def("read",
           [](const ResultsFile& f, const std::string& dataset) {
             if (!f.has(dataset)) throw InputError(f.path() + ": no dataset " + dataset);
             std::vector<py::ssize_t> shape = shape_of(f, dataset);
             std::vector<double> values;
             {
               py::gil_scoped_release release;
               values = f.read(dataset);
             }
             // A live file may have grown between the two reads: keep the rows read.
             py::ssize_t per_row = 1;
             for (std::size_t i = 1; i < shape.size(); ++i) per_row *= shape[i];
             if (!shape.empty()) shape[0] = per_row > 0 ? static_cast<py::ssize_t>(values.size()) / per_row : shape[0];
             return to_numpy(std::move(values), std::move(shape));
           },
           py::arg("dataset"), "A whole float64 dataset, in its shape.")
      .def_property_readonly("body_names", &ResultsFile::body_names)
      .def_property_readonly("joint_names", &ResultsFile::joint_names)
      .def("string_attribute", &ResultsFile::string_attribute, py::arg("name"))
      .def_property_readonly("model_text", &ResultsFile::model_text, "The model the run integrated (JSON text), or None.")
      .def("number_attribute", &ResultsFile::number_attribute, py::arg("name"))
      .def("dataset_string_attribute", &ResultsFile::dataset_string_attribute, py::arg("dataset"), py::arg("name"))
      .def("size_bytes", &ResultsFile::size_bytes)
      .def("export_csv", &export_csv, py::arg("dir"), py::arg("bodies") = std::vector<std::string>{},
           "CSV files in dir (as mbsflow export); returns the files written.");
}

}  // namespace mbsflow::python
