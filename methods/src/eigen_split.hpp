#pragma once
// The simplified Newton iteration of a fully implicit method, split by the eigenvalues of
// its matrix G (a block method's g, or the implicit block A of a Runge-Kutta tableau).
// The system (I - tau G (x) J) dU = -R over k points decouples with G = T diag(mu) T^-1
// into one system (I - tau mu_e J) w_e = z_e per real eigenvalue and one complex system
// per conjugate pair (Hairer & Wanner, IV.8: Radau5 solves one real and one complex
// system for 3-stage Radau IIA). Every system factorises and solves on its own, so each
// can be a node of a flow graph; the transforms work on slices of rows.
#include <Eigen/Core>
#include <complex>
#include <memory>
#include <string>
#include <vector>

#include "mbsflow/methods/shifted_solver.hpp"

namespace mbsflow {

class EigenSplit {
 public:
  // Throws InputError when G is singular or not diagonalisable (`what` names G).
  // elimination: for every system's solver (ShiftedSolver::eliminate_first).
  EigenSplit(const Eigen::MatrixXd& g, Eigen::Index n, const std::string& what,
             const std::shared_ptr<Elimination>& elimination = nullptr);

  int points() const { return static_cast<int>(t_.rows()); }
  int systems() const { return static_cast<int>(systems_.size()); }
  // The eigenvalue of system e (for a pair, the one with positive imaginary part).
  std::complex<double> eigenvalue(int e) const { return systems_[static_cast<std::size_t>(e)].mu; }
  bool is_complex(int e) const { return systems_[static_cast<std::size_t>(e)].complex; }
  // The real system whose eigenvalue is gamma, or -1.
  int real_system(double gamma) const;

  // I - tau mu_e J; throws RunError when singular.
  void factorize(int e, const Eigen::SparseMatrix<double>& jac, double tau, LinearSolverKind kind);
  // z_e = -(T^-1 R)_e for every system, rows [lo, lo + len) of the residuals R_l.
  void load_residuals(const std::vector<Eigen::VectorXd>& r, Eigen::Index lo, Eigen::Index len);
  void solve(int e);  // w_e = (I - tau mu_e J)^-1 z_e, in place
  // (I - tau mu_e J)^-1 v for a real system e.
  void solve_real(int e, Eigen::VectorXd& v) const;
  // dU_i = (T w)_i over rows [lo, lo + len) (a pair contributes twice the real part of one
  // of its columns).
  void correction(int i, Eigen::Index lo, Eigen::Index len, Eigen::VectorXd& du) const;

  // Checkpoints: every system's factors (ShiftedSolver::save).
  void save(StateWriter& out) const;
  void restore(StateReader& in, const Eigen::SparseMatrix<double>& pattern);

 private:
  struct System {
    std::complex<double> mu;
    bool complex = false;
    int column = 0;  // its column of T (its partner's column is the conjugate)
    ShiftedSolver<double> real_solver;
    ShiftedSolver<std::complex<double>> complex_solver;
    Eigen::VectorXd zr;
    Eigen::VectorXcd zc;
  };
  Eigen::MatrixXcd t_, t_inv_;
  std::vector<System> systems_;
};

}  // namespace mbsflow
