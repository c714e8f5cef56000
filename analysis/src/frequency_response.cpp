#include "mbsflow/analysis/frequency_response.hpp"

#include <cstdio>
#include <fstream>
#include <numbers>

#include "constrained.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/klu_lu.hpp"

namespace mbsflow {
namespace {

using Sparse = Eigen::SparseMatrix<double>;
using Complex = std::complex<double>;

const char* const input_names[6] = {"fx", "fy", "fz", "tx", "ty", "tz"};
const char* const output_names[6] = {"x", "y", "z", "rx", "ry", "rz"};

// Each channel's row of the bodies' small motions (body_motion) as a column: the
// combination of coordinates that is the channel's motion, and (by virtual work) the
// generalised force of a unit force or torque there. InputError for a driven body.
Sparse selection(const LinearModel& m, const Sparse& motion_t, const std::vector<Channel>& channels) {
  std::vector<Eigen::Triplet<double>> e;
  for (std::size_t j = 0; j < channels.size(); ++j) {
    const std::size_t before = e.size();
    for (Sparse::InnerIterator it(motion_t, 6 * channels[j].body + channels[j].dof); it; ++it)
      e.emplace_back(it.row(), static_cast<Eigen::Index>(j), it.value());
    if (e.size() == before)
      throw InputError("body '" + m.model->bodies[static_cast<std::size_t>(channels[j].body)].name +
                       "' is driven: its motion is prescribed, it has no response");
  }
  Sparse s(m.size(), static_cast<Eigen::Index>(channels.size()));
  s.setFromTriplets(e.begin(), e.end());
  return s;
}

Sparse motion_transposed(const LinearModel& m) { return Sparse(body_motion(m).transpose()); }

Sparse from_dense(const Eigen::MatrixXd& a) { return a.sparseView(0.0, 0.0); }

}  // namespace

Channel parse_channel(const Model& model, const std::string& text, bool input) {
  const std::size_t colon = text.rfind(':');
  const std::string what = input ? "--input" : "--output";
  const std::string allowed = input ? "fx, fy, fz, tx, ty, tz" : "x, y, z, rx, ry, rz (v... for velocity, a... for acceleration)";
  if (colon == std::string::npos || colon == 0)
    throw InputError(what + " " + text + ": give BODY:WHAT, WHAT one of " + allowed);
  const std::string name = text.substr(0, colon);
  std::string dof = text.substr(colon + 1);
  Channel c;
  c.body = -1;
  for (std::size_t b = 0; b < model.bodies.size(); ++b)
    if (model.bodies[b].name == name) c.body = static_cast<int>(b);
  if (c.body < 0) throw InputError(what + " " + text + ": the model has no body '" + name + "'");
  if (!input && dof.size() > 1 && (dof[0] == 'v' || dof[0] == 'a') && dof != "rx" && dof != "ry" && dof != "rz") {
    c.kind = dof[0] == 'v' ? Channel::Kind::velocity : Channel::Kind::acceleration;
    dof.erase(0, 1);
  }
  const char* const* names = input ? input_names : output_names;
  c.dof = -1;
  for (int i = 0; i < 6; ++i)
    if (dof == names[i]) c.dof = i;
  if (c.dof < 0) throw InputError(what + " " + text + ": '" + text.substr(colon + 1) + "' is not one of " + allowed);
  return c;
}

std::string channel_name(const Model& model, const Channel& c, bool input) {
  const std::string kind = input || c.kind == Channel::Kind::displacement ? "" : c.kind == Channel::Kind::velocity ? "v" : "a";
  return model.bodies[static_cast<std::size_t>(c.body)].name + ":" + kind + (input ? input_names : output_names)[c.dof];
}

FrequencyResponse frequency_response(const LinearModel& m, const std::vector<Channel>& inputs,
                                     const std::vector<Channel>& outputs, const std::vector<double>& hz) {
  if (inputs.empty() || outputs.empty()) throw InputError("a frequency response needs at least one input and one output");
  const Eigen::Index n = m.size(), r = m.C.rows();
  const Sparse motion_t = motion_transposed(m);
  const Sparse b = selection(m, motion_t, inputs);
  const Eigen::SparseMatrix<Complex> pick = Sparse(selection(m, motion_t, outputs).transpose()).cast<Complex>();
  FrequencyResponse out;
  out.frequency = hz;
  // The augmented matrix's pattern: K, D, M and the joints' rows, the same at every frequency.
  KluLu<Complex> lu;
  bool analysed = false;
  for (double f : hz) {
    const double omega = 2.0 * std::numbers::pi * f;
    Eigen::SparseMatrix<Complex> a =
        m.K.cast<Complex>() + Complex(0.0, omega) * m.D.cast<Complex>() + Complex(-omega * omega, 0.0) * m.M.cast<Complex>();
    augment(a, m.C);
    if (!analysed) lu.analyze(a);
    analysed = true;
    try {
      lu.factorize(a);
    } catch (const RunError&) {
      throw RunError("the frequency response is singular at " + std::to_string(f) +
                     " Hz: an undamped mode sits there, or a body moves freely (no stiffness holds it)");
    }
    Eigen::MatrixXcd h(static_cast<Eigen::Index>(outputs.size()), static_cast<Eigen::Index>(inputs.size()));
    for (Eigen::Index j = 0; j < b.cols(); ++j) {
      Eigen::VectorXcd x = Eigen::VectorXcd::Zero(n + r);
      x.head(n) = Eigen::VectorXd(b.col(j)).cast<Complex>();
      lu.solve(x);
      const Eigen::VectorXcd motion = pick * x.head(n);
      for (std::size_t o = 0; o < outputs.size(); ++o) {
        const Complex d = motion[static_cast<Eigen::Index>(o)];
        const Channel::Kind k = outputs[o].kind;
        h(static_cast<Eigen::Index>(o), j) =
            k == Channel::Kind::displacement ? d : k == Channel::Kind::velocity ? Complex(0.0, omega) * d : -omega * omega * d;
      }
    }
    out.h.push_back(std::move(h));
  }
  return out;
}

StateSpace state_space(const LinearModel& m, const std::vector<Channel>& inputs, const std::vector<Channel>& outputs) {
  const Eigen::Index n = m.size();
  // The allowed motions: the bodies' coordinates, or a null-space basis of the joints' rows.
  Eigen::MatrixXd basis;
  if (m.C.rows() > 0) {
    if (n > 6000) throw InputError("a state-space model of rigid joints is formed dense: at most 1000 free bodies");
    basis = null_space(m.C, n);
  }
  const Sparse motion_t = motion_transposed(m);
  const Sparse bin = selection(m, motion_t, inputs), cout = selection(m, motion_t, outputs);
  StateSpace s;
  Eigen::MatrixXd minv_k, minv_d, minv_b, pick;  // pick: outputs x free coordinates
  Eigen::Index f = n;
  if (basis.size() > 0) {
    f = basis.cols();
    const Eigen::MatrixXd mr = basis.transpose() * (m.M * basis);
    const Eigen::LDLT<Eigen::MatrixXd> mass(mr);
    minv_k = mass.solve(basis.transpose() * (m.K * basis));
    minv_d = mass.solve(basis.transpose() * (m.D * basis));
    minv_b = mass.solve(basis.transpose() * Eigen::MatrixXd(bin));
    pick = Eigen::MatrixXd(cout).transpose() * basis;
  } else {
    // M is block diagonal (a block per free body): inverted block by block, kept sparse.
    std::vector<Eigen::Triplet<double>> e;
    for (std::size_t k = 0; k < m.coords.bodies.size(); ++k) {
      const Eigen::Index at = m.coords.start[k], size = m.coords.count(k);
      const Eigen::MatrixXd inv = Eigen::MatrixXd(m.M.block(at, at, size, size)).inverse();
      for (Eigen::Index i = 0; i < size; ++i)
        for (Eigen::Index j = 0; j < size; ++j)
          if (inv(i, j) != 0.0) e.emplace_back(at + i, at + j, inv(i, j));
    }
    Sparse minv(n, n);
    minv.setFromTriplets(e.begin(), e.end());
    const Sparse mk = minv * m.K, mdd = minv * m.D, mb = minv * bin;
    std::vector<Eigen::Triplet<double>> a, b;
    for (Eigen::Index i = 0; i < n; ++i) a.emplace_back(i, n + i, 1.0);
    for (Eigen::Index col = 0; col < n; ++col) {
      for (Sparse::InnerIterator it(mk, col); it; ++it) a.emplace_back(n + it.row(), it.col(), -it.value());
      for (Sparse::InnerIterator it(mdd, col); it; ++it) a.emplace_back(n + it.row(), n + it.col(), -it.value());
    }
    for (Eigen::Index col = 0; col < mb.outerSize(); ++col)
      for (Sparse::InnerIterator it(mb, col); it; ++it) b.emplace_back(n + it.row(), it.col(), it.value());
    s.A.resize(2 * n, 2 * n);
    s.A.setFromTriplets(a.begin(), a.end());
    s.B.resize(2 * n, bin.cols());
    s.B.setFromTriplets(b.begin(), b.end());
    // An output's row: its motion's combination of the coordinates (displacement), of
    // their rates (velocity), or of the accelerations' rows of A and B.
    const Sparse pick = Sparse(cout.transpose());
    const Sparse acc_x = -(pick * mk), acc_v = -(pick * mdd), acc_u = pick * mb;
    const auto kind = [&](Eigen::Index row) { return outputs[static_cast<std::size_t>(row)].kind; };
    std::vector<Eigen::Triplet<double>> c, d;
    for (Eigen::Index col = 0; col < n; ++col) {
      for (Sparse::InnerIterator it(pick, col); it; ++it) {
        if (kind(it.row()) == Channel::Kind::displacement) c.emplace_back(it.row(), col, it.value());
        if (kind(it.row()) == Channel::Kind::velocity) c.emplace_back(it.row(), n + col, it.value());
      }
      for (Sparse::InnerIterator it(acc_x, col); it; ++it)
        if (kind(it.row()) == Channel::Kind::acceleration) c.emplace_back(it.row(), col, it.value());
      for (Sparse::InnerIterator it(acc_v, col); it; ++it)
        if (kind(it.row()) == Channel::Kind::acceleration) c.emplace_back(it.row(), n + col, it.value());
    }
    for (Eigen::Index col = 0; col < acc_u.outerSize(); ++col)
      for (Sparse::InnerIterator it(acc_u, col); it; ++it)
        if (kind(it.row()) == Channel::Kind::acceleration) d.emplace_back(it.row(), col, it.value());
    s.C.resize(static_cast<Eigen::Index>(outputs.size()), 2 * n);
    s.C.setFromTriplets(c.begin(), c.end());
    s.D.resize(static_cast<Eigen::Index>(outputs.size()), bin.cols());
    s.D.setFromTriplets(d.begin(), d.end());
    return s;
  }
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * f, 2 * f), b = Eigen::MatrixXd::Zero(2 * f, bin.cols());
  a.topRightCorner(f, f).setIdentity();
  a.bottomLeftCorner(f, f) = -minv_k;
  a.bottomRightCorner(f, f) = -minv_d;
  b.bottomRows(f) = minv_b;
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(outputs.size()), 2 * f);
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(outputs.size()), bin.cols());
  for (std::size_t o = 0; o < outputs.size(); ++o) {
    const auto row = static_cast<Eigen::Index>(o);
    if (outputs[o].kind == Channel::Kind::displacement) c.row(row).head(f) = pick.row(row);
    if (outputs[o].kind == Channel::Kind::velocity) c.row(row).tail(f) = pick.row(row);
    if (outputs[o].kind == Channel::Kind::acceleration) {
      c.row(row) = pick.row(row) * a.bottomRows(f);
      d.row(row) = pick.row(row) * minv_b;
    }
  }
  s.A = from_dense(a);
  s.B = from_dense(b);
  s.C = from_dense(c);
  s.D = from_dense(d);
  return s;
}

void write_matrix_market(const std::string& path, const Eigen::SparseMatrix<double>& a) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw InputError("cannot write " + path);
  std::fprintf(f, "%%%%MatrixMarket matrix coordinate real general\n%% written by mbsflow\n%ld %ld %ld\n",
               static_cast<long>(a.rows()), static_cast<long>(a.cols()), static_cast<long>(a.nonZeros()));
  for (Eigen::Index c = 0; c < a.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(a, c); it; ++it)
      std::fprintf(f, "%ld %ld %.17g\n", static_cast<long>(it.row() + 1), static_cast<long>(it.col() + 1), it.value());
  const bool ok = std::fclose(f) == 0;
  if (!ok) throw InputError("cannot write " + path);
}

}  // namespace mbsflow
