// mbsflow.Model (a checked model: from a file, a dict in the JSON schema, or a generator)
// and mbsflow.generate.
#include "bindings.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/graph/model.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/model_writer.hpp"

namespace mbsflow::python {
namespace {

// Checked as a file is: the same validation and messages, with `name` in place of the
// file's (the dict written as indented JSON, so line numbers count its fields).
Model from_dict(const py::dict& d, const std::string& name) {
  const std::string text = py::module_::import("json").attr("dumps")(d, py::arg("indent") = 2).cast<std::string>();
  return read_model_text(text, name);
}

// A str or os.PathLike as a path.
std::string path_of(const py::object& p) { return py::module_::import("os").attr("fspath")(p).cast<std::string>(); }

py::object to_dict(const Model& m) { return py::module_::import("json").attr("loads")(model_to_json(m)); }

template <class Params>
Model generated(Model (*make)(const Params&), const Params& p, std::optional<double> t_end, std::optional<double> step) {
  Model m = make(p);
  if (t_end) m.simulation.t_end = *t_end;
  if (step) m.simulation.step = *step;
  check_model(m);
  return m;
}

std::vector<std::string> names_of(const auto& items) {
  std::vector<std::string> out;
  out.reserve(items.size());
  for (const auto& i : items) out.push_back(i.name);
  return out;
}

}  // namespace

void bind_model(py::module_& m) {
  py::class_<Model>(m, "Model", "A multibody model, checked as a model file is (docs/model-format.md).")
      .def_static("load", [](const py::object& path) { return read_model_file(path_of(path)); }, py::arg("path"),
                  "Reads and checks a JSON model file.")
      .def_static("from_dict", &from_dict, py::arg("d"), py::arg("name") = "<dict>",
                  "A model from a dict in the JSON schema of model files (the same checks and messages).")
      .def_static("from_json", &read_model_text, py::arg("text"), py::arg("name") = "<json>")
      .def("to_dict", &to_dict, "The model as a dict in the JSON schema (Model.from_dict reads it back).")
      .def("to_json", &model_to_json)
      .def("save", [](const Model& self, const py::object& path) { write_model_file(self, path_of(path)); }, py::arg("path"))
      .def_property_readonly("name", [](const Model& self) { return self.name; })
      .def_property_readonly("body_names", [](const Model& self) { return names_of(self.bodies); })
      .def_property_readonly("joint_names", [](const Model& self) { return names_of(self.joints); })
      .def_property_readonly("n_bodies", [](const Model& self) { return self.bodies.size(); })
      .def_property_readonly("n_joints", [](const Model& self) { return self.joints.size(); })
      .def_property_readonly("t_start", [](const Model& self) { return self.simulation.t_start; })
      .def_property_readonly("t_end", [](const Model& self) { return self.simulation.t_end; })
      .def_property_readonly("method", [](const Model& self) -> std::optional<std::string> {
        if (!self.simulation.method) return std::nullopt;  // chosen at the run (rk4, or dopri5 where no joint gives a step)
        return std::string(self.simulation.method->name());
      })
      .def("__repr__", [](const Model& self) {
        return "<mbsflow.Model '" + self.name + "': " + std::to_string(self.bodies.size()) + " bodies, " +
               std::to_string(self.joints.size()) + " joints>";
      });

  py::module_ g = m.def_submodule("generate", "Benchmark and example models of any size (as `mbsflow generate`).");
  const ChainParams chain;
  g.def("chain",
        [](int n, double link_length, double mass, double stiffness, double rotational_stiffness, double damping_ratio,
           std::optional<double> t_end, std::optional<double> step) {
          return generated(&make_chain, ChainParams{n, link_length, mass, stiffness, rotational_stiffness, damping_ratio},
                           t_end, step);
        },
        "A chain of n rod-like links hanging from the ground, released horizontally under gravity.", py::arg("n") = chain.bodies,
        py::arg("link_length") = chain.link_length, py::arg("mass") = chain.mass, py::arg("stiffness") = chain.stiffness,
        py::arg("rotational_stiffness") = chain.rotational_stiffness, py::arg("damping_ratio") = chain.damping_ratio,
        py::arg("t_end") = py::none(), py::arg("step") = py::none());
  const GridParams grid;
  g.def("grid",
        [](int rows, int cols, double spacing, double mass, double stiffness, double rotational_stiffness,
           double damping_ratio, std::optional<double> t_end, std::optional<double> step) {
          return generated(&make_grid, GridParams{rows, cols, spacing, mass, stiffness, rotational_stiffness, damping_ratio},
                           t_end, step);
        },
        "A plate of rows x cols bodies clamped along one edge, bending under gravity.", py::arg("rows") = grid.rows,
        py::arg("cols") = grid.cols, py::arg("spacing") = grid.spacing, py::arg("mass") = grid.mass,
        py::arg("stiffness") = grid.stiffness, py::arg("rotational_stiffness") = grid.rotational_stiffness,
        py::arg("damping_ratio") = grid.damping_ratio, py::arg("t_end") = py::none(), py::arg("step") = py::none());
  const TrainParams train;
  g.def("train",
        [](int wagons, double speed, double vertical_roughness, double lateral_roughness, unsigned seed,
           std::optional<double> t_end, std::optional<double> step) {
          return generated(&make_train, TrainParams{wagons, speed, vertical_roughness, lateral_roughness, seed}, t_end, step);
        },
        "A train of wagons (7 bodies each) running over a rough track.", py::arg("wagons") = train.wagons,
        py::arg("speed") = train.speed, py::arg("vertical_roughness") = train.vertical_roughness,
        py::arg("lateral_roughness") = train.lateral_roughness, py::arg("seed") = train.seed, py::arg("t_end") = py::none(),
        py::arg("step") = py::none());
  const RandomTreeParams tree;
  g.def("random",
        [](int bodies, int cycles, unsigned seed, std::optional<double> t_end, std::optional<double> step) {
          return generated(&make_random_tree, RandomTreeParams{bodies, cycles, seed}, t_end, step);
        },
        "A random tree of bodies hanging from the ground, with extra joints closing cycles.", py::arg("bodies") = tree.bodies,
        py::arg("cycles") = tree.cycles, py::arg("seed") = tree.seed, py::arg("t_end") = py::none(),
        py::arg("step") = py::none());
}

}  // namespace mbsflow::python
