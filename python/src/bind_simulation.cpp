// mbsflow.Simulation: a model stepped from Python, with its state read between steps as
// numpy views of the integrator's own state (no copies) and loads set for the next steps.
#include <cmath>
#include <memory>

#include "bindings.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/runtime/run_request.hpp"
#include "mbsflow/runtime/run_settings.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "stop_guard.hpp"

namespace mbsflow::python {
namespace {

// mbsflow.Simulation's keywords (the settings declared in_simulation) on a model.
std::unique_ptr<Simulation> make_simulation(const Model& model, const py::dict& settings) {
  const RunRequest r = request_of(settings, in_simulation, "mbsflow.Simulation");
  Model m = model;
  apply_overrides(m, r);
  RunOptions o = options_from_model(m, estimate_stable_step(m).step);
  if (!std::isfinite(o.step)) throw InputError(m.name + ": no joints to estimate a step from; give {step}");
  o.threads = r.threads;
  o.linear_solver = r.linear_solver;
  o.jacobian = r.jacobian;
  return std::make_unique<Simulation>(m, o);
}

// Runs `call` without the GIL, Ctrl-C stopping it after its current step.
template <class Call>
void interruptible(Simulation& s, Call call) {
  StopGuard guard;
  s.set_stop(guard.flag());
  try {
    py::gil_scoped_release release;
    call();
  } catch (const RunError&) {
    s.set_stop(nullptr);
    guard.raise_if_signalled();
    throw;
  }
  s.set_stop(nullptr);
}

Eigen::Index checked_body(Simulation& s, int i) {
  if (i < 0 || i >= s.system().layout().bodies)
    throw InputError("body index " + std::to_string(i) + " out of range (" + std::to_string(s.system().layout().bodies) +
                     " bodies)");
  return i;
}

// A block of the state (count values per body, from `at`) as a read-only bodies x count view.
py::array_t<double> block(py::object self, Eigen::Index (StateLayout::*at)(Eigen::Index) const, py::ssize_t count) {
  Simulation& s = self.cast<Simulation&>();
  const StateLayout& l = s.system().layout();
  return readonly_view(s.state().data() + (l.*at)(0), l.bodies, count, self);
}

}  // namespace

void bind_simulation(py::module_& m) {
  py::class_<Simulation>(m, "Simulation")
      // mbsflow.Simulation (python/mbsflow/simulation.py) reads its keywords into `settings`.
      .def(py::init(&make_simulation), py::arg("model"), py::arg("settings"))
      .def_property_readonly("t", &Simulation::time)
      .def("step",
           [](Simulation& s, std::optional<double> dt) {
             bool stepped = true;
             if (dt) {
               if (!(*dt >= 0.0) || !std::isfinite(*dt)) throw InputError("step: dt must be finite and >= 0");
               interruptible(s, [&] { s.advance_to(s.time() + *dt); });
             } else {
               interruptible(s, [&] { stepped = s.step(); });
             }
             return stepped;
           },
           py::arg("dt") = py::none(),
           "step(): one step of the method towards t_end (False once there); step(dt): advance_to(t + dt).")
      .def("advance_to", [](Simulation& s, double t) { interruptible(s, [&] { s.advance_to(t); }); }, py::arg("t"),
           "Steps until time t exactly (the last step shortened).")
      .def_property_readonly("state",
                             [](py::object self) {
                               Simulation& s = self.cast<Simulation&>();
                               return readonly_view(s.state().data(), s.state().size(), 1, self).attr("reshape")(-1);
                             })
      .def_property_readonly("positions", [](py::object self) { return block(self, &StateLayout::position, 3); })
      .def_property_readonly("orientations", [](py::object self) { return block(self, &StateLayout::orientation, 4); })
      .def_property_readonly("velocities", [](py::object self) { return block(self, &StateLayout::velocity, 3); })
      .def_property_readonly("angular_velocities",
                             [](py::object self) { return block(self, &StateLayout::angular_velocity, 3); })
      .def("body",
           [](Simulation& s, int i) {
             const BodyState b = s.body(static_cast<int>(checked_body(s, i)));
             py::dict d;
             d["position"] = to_numpy(Eigen::VectorXd(b.position));
             d["velocity"] = to_numpy(Eigen::VectorXd(b.velocity));
             d["angular_velocity"] = to_numpy(Eigen::VectorXd(b.angular_velocity));
             d["orientation"] = to_numpy(Eigen::VectorXd(Eigen::Vector4d(b.orientation.w(), b.orientation.x(),
                                                                         b.orientation.y(), b.orientation.z())));
             return d;
           },
           py::arg("index"), "One body's state, world frame (angular velocity too); orientation w, x, y, z.")
      .def("set_state",
           [](Simulation& s, const py::object& y) { s.set_state(to_vector(y, s.state().size(), "set_state")); },
           py::arg("y"))
      .def("set_load",
           [](Simulation& s, int i, const py::object& force, const py::object& torque) {
             const Eigen::Vector3d f = to_vector(force, 3, "set_load: force");
             const Eigen::Vector3d tq = torque.is_none() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(to_vector(torque, 3, "set_load: torque"));
             s.set_load(static_cast<int>(checked_body(s, i)), f, tq);
           },
           py::arg("body"), py::arg("force"), py::arg("torque") = py::none(),
           "A force and torque (world frame, at the centre of mass) held on a body until set again.")
      .def("energy",
           [](Simulation& s) {
             const Energy e = s.system().energy(s.time(), s.state());
             py::dict d;
             d["kinetic"] = e.kinetic;
             d["gravity"] = e.gravity;
             d["elastic"] = e.elastic;
             return d;
           })
      .def_property_readonly("stats",
                             [](const Simulation& s) {
                               const StepperStats& st = s.stats();
                               py::dict d;
                               d["accepted"] = st.accepted;
                               d["rejected"] = st.rejected;
                               d["evaluations"] = st.evaluations;
                               d["jacobians"] = st.jacobians;
                               d["factorizations"] = st.factorizations;
                               return d;
                             })
      .def_property_readonly("t_end", [](const Simulation& s) { return s.options().t_end; })
      .def_property_readonly("method", [](const Simulation& s) { return std::string(method_name(s.options().method)); })
      .def_property_readonly("step_size", [](const Simulation& s) { return s.options().step; })
      .def_property_readonly("n_bodies", [](Simulation& s) { return s.system().layout().bodies; });
}

}  // namespace mbsflow::python
