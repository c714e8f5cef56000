#include "mbsflow/analysis/modes.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "constrained.hpp"
#include "mode_solvers.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/real_eigen.hpp"

namespace mbsflow {

double modal_rate_scale(const LinearModel& m) {
  double fastest = 0.0;
  for (Eigen::Index i = 0; i < m.M.rows(); ++i) {
    const double mi = m.M.coeff(i, i), ki = std::abs(m.K.coeff(i, i));
    if (mi > 0.0) fastest = std::max(fastest, std::sqrt(ki / mi));
  }
  return fastest > 0.0 ? fastest : 1.0;
}

namespace {

using Sparse = Eigen::SparseMatrix<double>;
using Complex = std::complex<double>;

// The largest absolute row sum: a scale for residuals.
double norm_of(const Sparse& a) {
  Eigen::VectorXd rows = Eigen::VectorXd::Zero(a.rows());
  for (Eigen::Index c = 0; c < a.outerSize(); ++c)
    for (Sparse::InnerIterator it(a, c); it; ++it) rows[it.row()] += std::abs(it.value());
  return rows.size() ? rows.maxCoeff() : 0.0;
}

// Rigid-body motions first, then ascending |lambda|: the order modes are reported in.
bool reported_before(const FoundMode& a, const FoundMode& b) {
  if (a.rigid != b.rigid) return a.rigid;
  return std::abs(a.lambda) < std::abs(b.lambda);
}

// The modes of the model on the columns of basis (which satisfy C x = 0): those of
// lambda^2 Mr + lambda Dr + Kr damped; undamped, of the symmetric part of Kr against Mr.
std::vector<FoundMode> projected_dense_modes(const LinearModel& m, const Eigen::MatrixXd& basis, bool damped) {
  const Eigen::Index free = basis.cols();
  if (free == 0) return {};
  const Eigen::MatrixXd mr = basis.transpose() * (m.M * basis);
  const Eigen::MatrixXd kr = basis.transpose() * (m.K * basis);
  const Eigen::MatrixXd dr = damped ? Eigen::MatrixXd(basis.transpose() * (m.D * basis)) : Eigen::MatrixXd::Zero(free, free);
  const Eigen::LLT<Eigen::MatrixXd> mass(mr);
  if (mass.info() != Eigen::Success) throw InputError("the mass matrix is not positive definite: a body without mass or inertia");
  const double zero = zero_rate * modal_rate_scale(m);
  std::vector<FoundMode> out;
  // Rigid-body motions: the null space of the stiffness on the allowed motions.
  const Eigen::MatrixXd ks = 0.5 * (kr + kr.transpose());
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> sym(ks, mr);
  for (Eigen::Index i = 0; i < free; ++i)
    if (std::abs(sym.eigenvalues()[i]) < zero * zero)  // lambda = 0 wherever K x = 0, damped or not
      out.push_back({0.0, (basis * sym.eigenvectors().col(i)).cast<Complex>(), true});
  if (!damped) {
    for (Eigen::Index i = 0; i < free; ++i) {
      const double mu = sym.eigenvalues()[i];
      if (std::abs(mu) < zero * zero) continue;
      // omega^2 < 0: a static instability, lambda real and positive.
      const Complex lambda = mu > 0.0 ? Complex(0.0, std::sqrt(mu)) : Complex(std::sqrt(-mu), 0.0);
      out.push_back({lambda, (basis * sym.eigenvectors().col(i)).cast<Complex>()});
    }
    return out;
  }
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * free, 2 * free);
  a.topRightCorner(free, free).setIdentity();
  a.bottomLeftCorner(free, free) = -mass.solve(kr);
  a.bottomRightCorner(free, free) = -mass.solve(dr);
  const RealEigen eig = real_eigen(a, true);
  if (!eig.converged) throw RunError("the dense eigensolver did not converge");
  for (Eigen::Index i = 0; i < 2 * free; ++i) {
    const Complex lambda = eig.values[i];
    if (lambda.imag() < 0.0 || std::abs(lambda) < zero) continue;  // the conjugate's partner; rigid-body motions above
    out.push_back({lambda, basis * eig.vectors.col(i).head(free)});
  }
  return out;
}

}  // namespace

Modes compute_modes(const LinearModel& m, const ModeOptions& o) {
  if (o.count < 1) throw InputError("modes: the count must be >= 1");
  const Eigen::Index n = m.size();
  const Eigen::Index free = n - m.C.rows();
  const bool dense = o.solver == ModeSolver::dense ||
                     (o.solver == ModeSolver::automatic && (free <= ModeOptions::dense_limit || 4 * o.count + 8 > free)) ||
                     2 * n < 2 * o.count + 8;
  Modes out;
  std::vector<FoundMode> found;
  if (dense) {
    const Eigen::MatrixXd basis = null_space(m.C, m.size());
    found = projected_dense_modes(m, basis, o.damped);
    out.free_coordinates = basis.cols();
    out.solver = "dense (Eigen), on a null-space basis of the rigid joints' rows";
  } else {
    out.free_coordinates = n - m.C.rows();
    std::optional<std::vector<FoundMode>> lanczos;
    if (!o.damped) lanczos = undamped_modes(m, o.count);
    if (lanczos) {
      found = std::move(*lanczos);
      out.solver = "sparse shift-invert (Spectra, symmetric Lanczos) on a KLU factorisation, rigid joints through the augmented matrix";
    } else {
      bool restarted = false;
      found = first_order_modes(m, o.count, o.damped, &restarted, o.notice);
      out.solver = std::string("sparse shift-invert (") + (restarted ? "Spectra, restarted Arnoldi" : "Arnoldi") +
                   " on the first-order pencil) on a KLU factorisation, "
                   "rigid joints through the augmented pencil";
    }
  }
  std::stable_sort(found.begin(), found.end(), reported_before);
  if (static_cast<int>(found.size()) > o.count) found.resize(static_cast<std::size_t>(o.count));
  const auto k = static_cast<Eigen::Index>(found.size());
  const auto bodies = static_cast<Eigen::Index>(m.coords.bodies.size());
  out.shape.resize(n, k);
  out.kinetic_share = Eigen::MatrixXd::Zero(bodies, k);
  out.strain_share = Eigen::MatrixXd::Zero(bodies, k);
  const Sparse none(n, n);
  const Sparse& d = o.damped ? m.D : none;  // not a copy of D
  const double nm = norm_of(m.M), nd = norm_of(d), nk = norm_of(m.K);
  // The residual is taken on the motions the joints allow: its part along C^T (the
  // joints' reactions) is removed.
  Eigen::SimplicialLDLT<Sparse> cct;
  if (m.C.rows() > 0) {
    Sparse g = m.C * Sparse(m.C.transpose());
    Sparse eps(g.rows(), g.cols());
    eps.setIdentity();
    cct.compute(g + 1e-12 * (norm_of(g) + 1.0) * eps);
  }
  for (Eigen::Index j = 0; j < k; ++j) {
    FoundMode& f = found[static_cast<std::size_t>(j)];
    Eigen::VectorXcd x = f.x;
    // Mass-normalised, its largest coordinate real and positive.
    const double size = std::sqrt(std::abs((x.adjoint() * (m.M * x))(0)));
    if (size > 0.0) x /= size;
    Eigen::Index at = 0;
    x.cwiseAbs().maxCoeff(&at);
    if (std::abs(x[at]) > 0.0) x *= std::conj(x[at]) / std::abs(x[at]);
    out.shape.col(j) = x;
    const Complex lambda = f.lambda;
    out.eigenvalue.push_back(lambda);
    out.rigid_body.push_back(f.rigid);
    out.frequency.push_back(std::abs(lambda) / (2.0 * std::numbers::pi));
    out.damping_ratio.push_back(f.rigid || std::abs(lambda) == 0.0 ? 0.0 : 0.0 - lambda.real() / std::abs(lambda));
    const Eigen::VectorXcd mx = m.M * x, kx_full = m.K * x;
    Eigen::VectorXcd r = lambda * lambda * mx + lambda * (d * x) + kx_full;
    if (m.C.rows() > 0) {
      const Eigen::VectorXd re = cct.solve(m.C * r.real()), im = cct.solve(m.C * r.imag());
      r -= (Sparse(m.C.transpose()) * re).cast<Complex>() + Complex(0.0, 1.0) * (Sparse(m.C.transpose()) * im).cast<Complex>();
    }
    const double scale = (std::norm(lambda) * nm + std::abs(lambda) * nd + nk) * x.norm();
    out.residual.push_back(scale > 0.0 ? r.norm() / scale : r.norm());
    // K's symmetric part on x without forming it (a copy of K, 11 million entries at
    // 100 000 bodies): K^T x is a dot product per column of K.
    const Eigen::VectorXcd kx = 0.5 * (kx_full + m.K.transpose() * x);
    double kinetic = 0.0, strain = 0.0;
    for (Eigen::Index b = 0; b < bodies; ++b) {
      const Eigen::Index first = m.coords.start[static_cast<std::size_t>(b)], size = m.coords.count(static_cast<std::size_t>(b));
      const double e = (x.segment(first, size).adjoint() * mx.segment(first, size))(0).real();
      const double s = (x.segment(first, size).adjoint() * kx.segment(first, size))(0).real();
      out.kinetic_share(b, j) = e;
      out.strain_share(b, j) = s;
      kinetic += e;
      strain += s;
    }
    if (kinetic > 0.0) out.kinetic_share.col(j) /= kinetic;
    if (std::abs(strain) > 1e-12 * std::norm(lambda) * kinetic && !f.rigid)
      out.strain_share.col(j) /= strain;
    else
      out.strain_share.col(j).setZero();
  }
  return out;
}

}  // namespace mbsflow
