// mbsflow._core's small-motion analysis: the static equilibrium, the linearisation as sparse
// matrices, the modes and the frequency response (python/mbsflow/analysis.py wraps them).
#include <pybind11/complex.h>

#include "bindings.hpp"
#include "mbsflow/analysis/equilibrium.hpp"
#include "mbsflow/analysis/frequency_response.hpp"
#include "mbsflow/analysis/modes.hpp"

namespace mbsflow::python {
namespace {

// A sparse matrix as (data, indices, indptr, shape) of scipy's csc_matrix.
py::tuple csc(const Eigen::SparseMatrix<double>& a) {
  Eigen::SparseMatrix<double> c = a;
  c.makeCompressed();
  std::vector<double> data(c.valuePtr(), c.valuePtr() + c.nonZeros());
  std::vector<py::ssize_t> indices(c.innerIndexPtr(), c.innerIndexPtr() + c.nonZeros());
  std::vector<py::ssize_t> indptr(c.outerIndexPtr(), c.outerIndexPtr() + c.outerSize() + 1);
  return py::make_tuple(to_numpy(std::move(data), {c.nonZeros()}), py::array_t<py::ssize_t>(static_cast<py::ssize_t>(indices.size()), indices.data()),
                        py::array_t<py::ssize_t>(static_cast<py::ssize_t>(indptr.size()), indptr.data()),
                        py::make_tuple(c.rows(), c.cols()));
}

// The system of a model and the state to linearise about: "equilibrium" or "initial".
struct Point {
  std::unique_ptr<MultibodySystem> sys;
  Eigen::VectorXd y;
  double t = 0.0;
  Eigen::SparseMatrix<double> jacobian;  // the equilibrium's, refilled by linearize (which makes it where empty)
};

Point working_point(const Model& model, const std::string& at) {
  if (at != "equilibrium" && at != "initial") throw InputError("{at=" + at + "}: equilibrium or initial");
  Point p;
  p.sys = std::make_unique<MultibodySystem>(model);
  p.t = model.simulation.t_start;
  p.y = p.sys->initial_state();
  if (at == "equilibrium") {
    py::gil_scoped_release release;
    Equilibrium e = find_equilibrium(*p.sys, p.t, p.y);
    p.y = std::move(e.state);
    p.jacobian.swap(e.jacobian);  // Eigen 3.4's SparseMatrix has no move: a "move" copies
  }
  return p;
}

py::dict linear_model(const LinearModel& lm) {
  py::dict out;
  out["M"] = csc(lm.M);
  out["D"] = csc(lm.D);
  out["K"] = csc(lm.K);
  out["C"] = csc(lm.C);
  out["bodies"] = lm.coords.bodies;
  out["start"] = lm.coords.start;
  out["state"] = to_numpy(lm.state);
  return out;
}

}  // namespace

void bind_analysis(py::module_& m) {
  m.def(
      "_linearize",
      [](const Model& model, const std::string& at) {
        Point p = working_point(model, at);
        return linear_model(linearize(*p.sys, p.t, p.y, &p.jacobian));
      },
      py::arg("model"), py::arg("at"));
  m.def(
      "_modes",
      [](const Model& model, int n, const std::string& at, bool damped, const std::string& solver) {
        Point p = working_point(model, at);
        const LinearModel lm = linearize(*p.sys, p.t, p.y, &p.jacobian);
        ModeOptions o;
        o.count = n;
        o.damped = damped;
        if (solver != "auto" && solver != "dense" && solver != "sparse") throw InputError("{solver=" + solver + "}: auto, dense or sparse");
        o.solver = solver == "dense" ? ModeSolver::dense : solver == "sparse" ? ModeSolver::sparse : ModeSolver::automatic;
        Modes modes;
        {
          py::gil_scoped_release release;
          modes = compute_modes(lm, o);
        }
        const auto k = static_cast<py::ssize_t>(modes.frequency.size());
        const auto bodies = static_cast<py::ssize_t>(model.bodies.size());
        py::array_t<std::complex<double>> shape({k, bodies, py::ssize_t{6}});
        auto s = shape.mutable_unchecked<3>();
        std::vector<double> kinetic(static_cast<std::size_t>(k * bodies), 0.0), strain(kinetic.size(), 0.0);
        const Eigen::SparseMatrix<std::complex<double>> motion = body_motion(lm).cast<std::complex<double>>();
        for (py::ssize_t j = 0; j < k; ++j) {
          const Eigen::VectorXcd x = motion * modes.shape.col(j);
          for (py::ssize_t b = 0; b < bodies; ++b)
            for (py::ssize_t e = 0; e < 6; ++e) s(j, b, e) = x[6 * b + e];
          for (std::size_t b = 0; b < lm.coords.bodies.size(); ++b) {
            const auto body = static_cast<py::ssize_t>(lm.coords.bodies[b]);
            kinetic[static_cast<std::size_t>(j * bodies + body)] = modes.kinetic_share(static_cast<Eigen::Index>(b), j);
            strain[static_cast<std::size_t>(j * bodies + body)] = modes.strain_share(static_cast<Eigen::Index>(b), j);
          }
        }
        py::dict out;
        out["frequency"] = modes.frequency;
        out["damping_ratio"] = modes.damping_ratio;
        out["eigenvalue"] = modes.eigenvalue;
        out["rigid_body"] = modes.rigid_body;
        out["residual"] = modes.residual;
        out["shape"] = shape;
        out["kinetic_share"] = to_numpy(std::move(kinetic), {k, bodies});
        out["strain_share"] = to_numpy(std::move(strain), {k, bodies});
        out["solver"] = modes.solver;
        out["state"] = to_numpy(lm.state);
        return out;
      },
      py::arg("model"), py::arg("n"), py::arg("at"), py::arg("damped"), py::arg("solver"));
  m.def(
      "_frf",
      [](const Model& model, const std::vector<std::string>& inputs, const std::vector<std::string>& outputs,
         const std::vector<double>& hz, const std::string& at) {
        Point p = working_point(model, at);
        const LinearModel lm = linearize(*p.sys, p.t, p.y, &p.jacobian);
        std::vector<Channel> in, out;
        for (const std::string& s : inputs) in.push_back(parse_channel(model, s, true));
        for (const std::string& s : outputs) out.push_back(parse_channel(model, s, false));
        FrequencyResponse r;
        {
          py::gil_scoped_release release;
          r = frequency_response(lm, in, out, hz);
        }
        const auto f = static_cast<py::ssize_t>(hz.size()), no = static_cast<py::ssize_t>(out.size()),
                   ni = static_cast<py::ssize_t>(in.size());
        py::array_t<std::complex<double>> h({f, no, ni});
        auto v = h.mutable_unchecked<3>();
        for (py::ssize_t k = 0; k < f; ++k)
          for (py::ssize_t o = 0; o < no; ++o)
            for (py::ssize_t i = 0; i < ni; ++i) v(k, o, i) = r.h[static_cast<std::size_t>(k)](o, i);
        return h;
      },
      py::arg("model"), py::arg("inputs"), py::arg("outputs"), py::arg("hz"), py::arg("at"));
}

}  // namespace mbsflow::python
