#include "eigen_split.hpp"

#include <Eigen/LU>
#include <cmath>

#include "mbsflow/error.hpp"
#include "mbsflow/methods/real_eigen.hpp"

namespace mbsflow {

// g = T diag(mu) T^-1, with real columns for real eigenvalues and conjugate columns for a
// complex pair, so that only one system per pair is solved.
EigenSplit::EigenSplit(const Eigen::MatrixXd& g, Eigen::Index n, const std::string& what,
                       const std::shared_ptr<Elimination>& elimination) {
  const auto k = static_cast<int>(g.rows());
  const RealEigen eig = real_eigen(g, true);
  if (!eig.converged) throw InputError("cannot diagonalise " + what);
  const Eigen::VectorXcd& mu = eig.values;
  const Eigen::MatrixXcd& v = eig.vectors;
  t_.resize(k, k);
  std::vector<bool> done(static_cast<std::size_t>(k), false);
  for (int e = 0; e < k; ++e) {
    if (done[static_cast<std::size_t>(e)]) continue;
    done[static_cast<std::size_t>(e)] = true;
    System sys;
    sys.mu = mu(e);
    sys.column = e;
    const double scale_mu = std::max(1.0, std::abs(mu(e)));
    if (std::abs(mu(e).imag()) <= 1e-12 * scale_mu) {
      sys.mu = mu(e).real();
      Eigen::VectorXd col = v.col(e).real();
      t_.col(e) = (col / col.norm()).cast<std::complex<double>>();
      sys.zr.resize(n);
    } else {
      sys.complex = true;
      if (mu(e).imag() < 0) sys.mu = std::conj(mu(e));
      t_.col(e) = mu(e).imag() < 0 ? Eigen::VectorXcd(v.col(e).conjugate()) : Eigen::VectorXcd(v.col(e));
      int partner = -1;
      for (int o = 0; o < k; ++o)
        if (!done[static_cast<std::size_t>(o)] && std::abs(mu(o) - std::conj(mu(e))) <= 1e-10 * scale_mu) {
          partner = o;
          break;
        }
      if (partner < 0) throw InputError(what + ": complex eigenvalue without its conjugate");
      done[static_cast<std::size_t>(partner)] = true;
      t_.col(partner) = t_.col(e).conjugate();
      sys.zc.resize(n);
    }
    if (std::abs(sys.mu) == 0) throw InputError(what + " is singular");
    sys.real_solver.eliminate_first(elimination);
    sys.complex_solver.eliminate_first(elimination);
    systems_.push_back(std::move(sys));
  }
  Eigen::FullPivLU<Eigen::MatrixXcd> lu(t_);
  if (!lu.isInvertible()) throw InputError(what + " is not diagonalisable");
  t_inv_ = lu.inverse();
}

int EigenSplit::real_system(double gamma) const {
  for (int e = 0; e < systems(); ++e) {
    const System& s = systems_[static_cast<std::size_t>(e)];
    if (!s.complex && std::abs(s.mu.real() - gamma) <= 1e-12 * std::abs(gamma)) return e;
  }
  return -1;
}

void EigenSplit::factorize(int e, const Eigen::SparseMatrix<double>& jac, double tau, LinearSolverKind kind) {
  System& sys = systems_[static_cast<std::size_t>(e)];
  if (sys.complex)
    sys.complex_solver.factorize(jac, tau * sys.mu, kind);
  else
    sys.real_solver.factorize(jac, tau * sys.mu.real(), kind);
}

void EigenSplit::save(StateWriter& out) const {
  for (const System& sys : systems_) {
    if (sys.complex)
      sys.complex_solver.save(out);
    else
      sys.real_solver.save(out);
  }
}

void EigenSplit::restore(StateReader& in, const Eigen::SparseMatrix<double>& pattern) {
  for (System& sys : systems_) {
    if (sys.complex)
      sys.complex_solver.restore(in, pattern);
    else
      sys.real_solver.restore(in, pattern);
  }
}

void EigenSplit::load_residuals(const std::vector<Eigen::VectorXd>& r, Eigen::Index lo, Eigen::Index len) {
  const int k = points();
  for (System& sys : systems_) {
    if (sys.complex) {
      auto z = sys.zc.segment(lo, len);
      z.setZero();
      for (int l = 0; l < k; ++l) {  // a complex times a real vector: two real products
        const std::complex<double> c = t_inv_(sys.column, l);
        z.real() -= c.real() * r[static_cast<std::size_t>(l)].segment(lo, len);
        z.imag() -= c.imag() * r[static_cast<std::size_t>(l)].segment(lo, len);
      }
    } else {
      auto z = sys.zr.segment(lo, len);
      z.setZero();
      for (int l = 0; l < k; ++l) z -= t_inv_(sys.column, l).real() * r[static_cast<std::size_t>(l)].segment(lo, len);
    }
  }
}

void EigenSplit::solve(int e) {
  System& sys = systems_[static_cast<std::size_t>(e)];
  if (sys.complex)
    sys.complex_solver.solve(sys.zc);
  else
    sys.real_solver.solve(sys.zr);
}

void EigenSplit::solve_real(int e, Eigen::VectorXd& v) const { systems_[static_cast<std::size_t>(e)].real_solver.solve(v); }

void EigenSplit::correction(int i, Eigen::Index lo, Eigen::Index len, Eigen::VectorXd& du) const {
  du.setZero(len);
  for (const System& sys : systems_) {
    if (sys.complex)
      du += (2.0 * t_(i, sys.column).real()) * sys.zc.segment(lo, len).real() -
            (2.0 * t_(i, sys.column).imag()) * sys.zc.segment(lo, len).imag();
    else
      du += t_(i, sys.column).real() * sys.zr.segment(lo, len);
  }
}

}  // namespace mbsflow
