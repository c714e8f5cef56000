// The integration loop of mbsflow.solve_ivp (python/mbsflow/ivp.py gives it scipy's
// shape): any registered method on a Python or compiled right-hand side, output at the
// steps or at t_eval from the method's dense output, events, and samples of the dense
// output for a continuous solution. Backward integration runs forward in s = -t.
#include <algorithm>
#include <cmath>
#include <memory>

#include "bindings.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/events.hpp"
#include "mbsflow/methods/stepper.hpp"
#include "mbsflow/methods/uncontrolled.hpp"
#include "stop_guard.hpp"

namespace mbsflow::python {
namespace {

// Chebyshev points of the second kind on [0, 1], ends included: a dense output of degree
// < dense_nodes is sampled exactly (python/mbsflow/ivp.py interpolates them barycentrically).
constexpr int dense_nodes = 8;

using CompiledRhs = void (*)(double t, const double* y, double* dydt);

struct IvpInput {
  py::object fun;                // fun(t, y) -> dydt, unless `compiled`
  std::uintptr_t compiled = 0;   // address of a CompiledRhs
  double t0 = 0, t1 = 1;
  Eigen::VectorXd y0;
  Method method = Method::dopri5;
  StepperSettings settings;
  std::vector<double> t_eval;    // empty: the steps
  bool dense = false;
  py::list events;               // (g, direction, terminal)
  py::object jac;                // None, a callable, or a constant matrix
  py::object jac_sparsity;       // None or a matrix whose nonzeros are the Jacobian's pattern
};

// Values of a Python call that must be n doubles: a list or tuple of floats read directly
// (the common `return [..., ...]`, whose items are numpy's float64 where the function
// indexed its array: a subclass of float), anything else through numpy, which costs about
// a microsecond more per call.
void copy_values(const py::object& r, Eigen::Index n, double* out, const char* what) {
  if ((PyList_CheckExact(r.ptr()) || PyTuple_CheckExact(r.ptr())) && PySequence_Fast_GET_SIZE(r.ptr()) == n) {
    PyObject** items = PySequence_Fast_ITEMS(r.ptr());
    bool floats = true;
    for (Eigen::Index i = 0; i < n && floats; ++i) {
      floats = PyFloat_Check(items[i]);
      if (floats) out[i] = PyFloat_AS_DOUBLE(items[i]);
    }
    if (floats) return;
  }
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(r);
  if (!a || a.size() != n)
    throw InputError(std::string(what) + " returned " + (a ? std::to_string(a.size()) : std::string("no array of")) +
                     " values where " + std::to_string(n) + " are needed");
  std::copy(a.data(), a.data() + n, out);
}

// f(t, y) with a fresh array for y, as scipy passes (a function may keep it), through
// the vectorcall protocol: no argument tuple, a few hundred ns less per call than
// pybind11's call.
py::object call_ty(const py::object& f, double t, const Eigen::VectorXd& y) {
  py::array_t<double> a(y.size());
  std::copy(y.data(), y.data() + y.size(), a.mutable_data());
  const py::float_ time(t);
  PyObject* args[2] = {time.ptr(), a.ptr()};
  PyObject* r = PyObject_Vectorcall(f.ptr(), args, 2, nullptr);
  if (!r) throw py::error_already_set();
  return py::reinterpret_steal<py::object>(r);
}

// The pattern of a dense array or scipy sparse matrix (its nonzeros), n x n.
Eigen::SparseMatrix<double> pattern_of(const py::object& m, Eigen::Index n, const char* what) {
  std::vector<Eigen::Triplet<double>> entries;
  if (py::hasattr(m, "tocsc")) {
    py::object c = m.attr("tocsc")();
    const auto shape = c.attr("shape").cast<std::pair<Eigen::Index, Eigen::Index>>();
    if (shape.first != n || shape.second != n) throw InputError(std::string(what) + ": must be n x n");
    const auto ptr = py::array_t<long long, py::array::forcecast>::ensure(c.attr("indptr"));
    const auto idx = py::array_t<long long, py::array::forcecast>::ensure(c.attr("indices"));
    for (Eigen::Index j = 0; j < n; ++j)
      for (long long k = ptr.at(j); k < ptr.at(j + 1); ++k) entries.emplace_back(idx.at(k), j, 1.0);
  } else {
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(m);
    if (!a || a.ndim() != 2 || a.shape(0) != n || a.shape(1) != n) throw InputError(std::string(what) + ": must be n x n");
    for (Eigen::Index i = 0; i < n; ++i)
      for (Eigen::Index j = 0; j < n; ++j)
        if (a.at(i, j) != 0.0) entries.emplace_back(i, j, 1.0);
  }
  for (Eigen::Index i = 0; i < n; ++i) entries.emplace_back(i, i, 0.0);  // the Newton matrix has the diagonal
  Eigen::SparseMatrix<double> p(n, n);
  p.setFromTriplets(entries.begin(), entries.end());
  return p;
}

Eigen::SparseMatrix<double> dense_pattern(Eigen::Index n) {
  Eigen::MatrixXd ones = Eigen::MatrixXd::Ones(n, n);
  return ones.sparseView();
}

// Fills `jac` (its pattern fixed) from the Python Jacobian's value r, times `sign`.
void fill_jacobian(const py::object& r, double sign, Eigen::SparseMatrix<double>& jac) {
  const Eigen::Index n = jac.rows();
  jac.coeffs().setZero();
  auto put = [&](Eigen::Index i, Eigen::Index j, double v) {
    if (v == 0.0) return;
    const int* begin = jac.innerIndexPtr() + jac.outerIndexPtr()[j];
    const int* end = jac.innerIndexPtr() + jac.outerIndexPtr()[j + 1];
    const int* at = std::lower_bound(begin, end, static_cast<int>(i));
    if (at == end || *at != i)
      throw InputError("jac: a nonzero at (" + std::to_string(i) + ", " + std::to_string(j) +
                       ") outside jac_sparsity");
    jac.valuePtr()[at - jac.innerIndexPtr()] = sign * v;
  };
  if (py::hasattr(r, "tocsc")) {
    py::object c = r.attr("tocsc")();
    const auto ptr = py::array_t<long long, py::array::forcecast>::ensure(c.attr("indptr"));
    const auto idx = py::array_t<long long, py::array::forcecast>::ensure(c.attr("indices"));
    const auto val = py::array_t<double, py::array::forcecast>::ensure(c.attr("data"));
    if (ptr.size() != n + 1) throw InputError("jac: must be n x n");
    for (Eigen::Index j = 0; j < n; ++j)
      for (long long k = ptr.at(j); k < ptr.at(j + 1); ++k) put(idx.at(k), j, val.at(k));
    return;
  }
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(r);
  if (!a || a.ndim() != 2 || a.shape(0) != n || a.shape(1) != n) throw InputError("jac: must be an n x n matrix");
  for (Eigen::Index j = 0; j < n; ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(jac, j); it; ++it) it.valueRef() = sign * a.at(it.row(), j);
}

py::dict solve(IvpInput& in) {
  const Eigen::Index n = in.y0.size();
  const double sign = in.t1 >= in.t0 ? 1.0 : -1.0;  // s = sign * t runs forward
  StepperSystem sys;
  sys.size = n;
  if (in.compiled) {
    const auto f = reinterpret_cast<CompiledRhs>(in.compiled);
    sys.rhs = [f, sign](double s, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
      f(sign * s, y.data(), dy.data());
      if (sign < 0) dy = -dy;
    };
  } else {
    sys.rhs = [&in, n, sign](double s, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
      py::gil_scoped_acquire gil;
      copy_values(call_ty(in.fun, sign * s, y), n, dy.data(), "fun");
      if (sign < 0) dy = -dy;
    };
  }
  if (!in.jac.is_none()) {
    const bool callable = PyCallable_Check(in.jac.ptr());
    Eigen::SparseMatrix<double> pattern =
        !in.jac_sparsity.is_none() ? pattern_of(in.jac_sparsity, n, "jac_sparsity")
        : !callable                ? pattern_of(in.jac, n, "jac")
                                   : dense_pattern(n);
    sys.sparsity = [pattern] { return pattern; };
    sys.jacobian = [&in, callable, sign](double s, const Eigen::VectorXd& y, Eigen::SparseMatrix<double>& jac) {
      py::gil_scoped_acquire gil;
      fill_jacobian(callable ? call_ty(in.jac, sign * s, y) : in.jac, sign, jac);
    };
  } else {
    Eigen::SparseMatrix<double> pattern =
        in.jac_sparsity.is_none() ? dense_pattern(n) : pattern_of(in.jac_sparsity, n, "jac_sparsity");
    sys.sparsity = [pattern] { return pattern; };
  }
  std::vector<EventFunction> functions;
  for (const py::handle e : in.events) {
    const auto [g, direction, terminal] = e.cast<std::tuple<py::object, int, bool>>();
    functions.push_back({"", [g, sign](double s, const Eigen::VectorXd& y) {
                           py::gil_scoped_acquire gil;
                           return call_ty(g, sign * s, y).cast<double>();
                         },
                         static_cast<int>(sign) * direction, terminal});
  }
  std::unique_ptr<Stepper> stepper = make_stepper(in.method, sys, in.settings);
  EventDetector detector(std::move(functions));
  std::vector<double> ts, ys, dense_ts, dense_ys;
  std::vector<std::vector<double>> t_events(static_cast<std::size_t>(py::len(in.events)));
  std::vector<std::vector<double>> y_events(t_events.size());
  int status = 0;
  std::string message = "The solver successfully reached the end of the integration interval.";
  std::size_t next_eval = 0;
  auto keep = [&](double s, const Eigen::VectorXd& y) {
    ts.push_back(sign * s);
    ys.insert(ys.end(), y.data(), y.data() + n);
  };
  StopGuard guard;
  {
    py::gil_scoped_release release;
    const double s0 = sign * in.t0, s1 = sign * in.t1;
    stepper->start(s0, in.y0, s1);
    detector.reset(*stepper);
    if (in.dense) dense_ts.push_back(s0);
    if (in.t_eval.empty()) keep(s0, in.y0);
    Eigen::VectorXd y(n);
    while (!stepper->done()) {
      if (guard.flag() && guard.flag()->load()) {
        status = -1;
        message = "interrupted";
        break;
      }
      try {
        stepper->step();
      } catch (const RunError& e) {
        status = -1;
        message = e.what();
        break;
      }
      const double a = stepper->t_previous();
      double b = stepper->t();
      const std::vector<Event> events = detector.after_step(*stepper);
      for (const Event& e : events) {
        t_events[e.index].push_back(sign * e.t);
        y_events[e.index].insert(y_events[e.index].end(), e.y.data(), e.y.data() + n);
      }
      const bool terminal = !events.empty() && detector.is_terminal(events.back().index);
      if (terminal) b = events.back().t;
      if (in.dense) {
        for (int k = 1; k < dense_nodes; ++k) {
          const double x = 0.5 - 0.5 * std::cos(M_PI * k / (dense_nodes - 1));
          stepper->dense(a + (stepper->t() - a) * x, y);
          dense_ys.insert(dense_ys.end(), y.data(), y.data() + n);
        }
        dense_ts.push_back(stepper->t());
      }
      if (in.t_eval.empty()) {
        if (terminal) keep(b, events.back().y);
        else keep(b, stepper->y());
      } else {
        while (next_eval < in.t_eval.size() && sign * in.t_eval[next_eval] <= b) {
          const double s = sign * in.t_eval[next_eval++];
          stepper->dense(s, y);
          keep(s, y);
        }
      }
      if (terminal) {
        status = 1;
        message = "A termination event occurred.";
        break;
      }
    }
  }
  if (status == -1 && message == "interrupted") guard.raise_if_signalled();
  py::dict out;
  const auto count = static_cast<py::ssize_t>(ts.size());
  out["t"] = to_numpy(std::move(ts), {count});
  out["y"] = to_numpy(std::move(ys), {count, n});
  py::list te, ye;
  for (std::size_t k = 0; k < t_events.size(); ++k) {
    const auto m = static_cast<py::ssize_t>(t_events[k].size());
    te.append(to_numpy(std::move(t_events[k]), {m}));
    ye.append(to_numpy(std::move(y_events[k]), {m, n}));
  }
  out["t_events"] = te;
  out["y_events"] = ye;
  if (in.dense) {
    const auto steps = static_cast<py::ssize_t>(dense_ts.size()) - 1;
    for (double& s : dense_ts) s *= sign;
    out["dense_t"] = to_numpy(std::move(dense_ts), {steps + 1});
    out["dense_y"] = to_numpy(std::move(dense_ys), {steps, dense_nodes - 1, n});
  }
  const StepperStats& st = stepper->stats();
  out["nfev"] = st.evaluations;
  out["njev"] = st.jacobians;
  out["nlu"] = st.factorizations;
  out["accepted"] = st.accepted;
  out["rejected"] = st.rejected;
  out["status"] = status;
  out["message"] = message;
  // The returned points' largest |y| per component: the warning about those below atol.
  Eigen::VectorXd largest = Eigen::VectorXd::Zero(n);
  const py::array_t<double> y_out = out["y"].cast<py::array_t<double>>();
  const auto y_at = y_out.unchecked<2>();
  for (py::ssize_t r = 0; r < y_at.shape(0); ++r)
    for (py::ssize_t c = 0; c < y_at.shape(1); ++c) largest[c] = std::max(largest[c], std::abs(y_at(r, c)));
  const std::string warning = y_at.shape(0) == 0 ? std::string() : uncontrolled_warning(
      largest, in.settings.atol, in.settings.atols, [](Eigen::Index i) { return "y[" + std::to_string(i) + "]"; },
      in.t_eval.empty() ? "at any accepted step" : "at any point of t_eval");
  out["warning"] = warning.empty() ? std::string() : "solve_ivp: " + render(warning, keyword_for);
  return out;
}

}  // namespace

void bind_ivp(py::module_& m) {
  m.def(
      "_solve_ivp",
      [](py::object fun, std::uintptr_t compiled, double t0, double t1, const py::object& y0, const std::string& method,
         const py::object& rtol, const py::object& atol, double first_step, std::vector<double> t_eval, bool dense,
         py::list events, py::object jac, py::object jac_sparsity, const std::string& variant,
         const std::string& linear_solver, int threads) {
        IvpInput in;
        in.fun = std::move(fun);
        in.compiled = compiled;
        in.t0 = t0;
        in.t1 = t1;
        in.y0 = to_vector(y0, -1, "y0");
        const std::optional<Method> m = find_method(method);
        if (!m) throw InputError("{method=" + method + "}: unknown method (" + method_list() + ")");
        in.method = *m;
        const bool implicit = stepper_entry(in.method).implicit;
        for (auto [given, scalar, vector, name] : {std::tuple{&rtol, &in.settings.rtol, &in.settings.rtols, "rtol"},
                                                  std::tuple{&atol, &in.settings.atol, &in.settings.atols, "atol"}}) {
          const Eigen::VectorXd v = to_vector(*given, -1, name);
          if (v.size() == 1) {
            *scalar = v[0];
          } else {
            if (v.size() != in.y0.size()) throw InputError(std::string("{") + name + "}: one value or one per component of y0");
            if (!implicit)
              throw InputError(std::string("{") + name + "}: one value per component only with " +
                               method_names([](const StepperEntry& e) { return e.implicit; }, "or"));
            *vector = v;
            *scalar = v.maxCoeff();
          }
        }
        in.settings.step = first_step;
        in.settings.variant = variant;
        in.settings.linear_solver = linear_solver;
        in.settings.threads = compiled ? threads : 1;  // a Python rhs runs under the GIL: one thread
        in.t_eval = std::move(t_eval);
        in.dense = dense;
        in.events = std::move(events);
        in.jac = std::move(jac);
        in.jac_sparsity = std::move(jac_sparsity);
        return solve(in);
      },
      py::arg("fun"), py::arg("compiled"), py::arg("t0"), py::arg("t1"), py::arg("y0"), py::arg("method"),
      py::arg("rtol"), py::arg("atol"), py::arg("first_step"), py::arg("t_eval"), py::arg("dense"), py::arg("events"),
      py::arg("jac"), py::arg("jac_sparsity"), py::arg("variant"), py::arg("linear_solver"), py::arg("threads"));
}

}  // namespace mbsflow::python
