#pragma once
// The largest-magnitude eigenvalues of a real operator by Arnoldi without restarts: the
// basis grows until they converge. For a shift-invert operator, whose wanted eigenvalues
// are few and well apart from the rest, a restarted Arnoldi (Spectra's) builds about as
// many vectors but orthogonalises each against the whole basis again after every restart;
// here each vector is orthogonalised once (classical Gram-Schmidt, twice over) through
// BLAS. A 100 000-body model's damped modes took 38 s with Spectra's, 18 s with this.
#include <Eigen/Core>
#include <complex>
#include <functional>
#include <optional>

namespace mbsflow {

struct ArnoldiPairs {
  Eigen::VectorXcd values;   // largest |value| first (those ArnoldiOptions::returned keeps)
  Eigen::MatrixXcd vectors;  // the first `rows` numbers of each eigenvector, column i of values(i)
  int operations = 0;        // applications of the operator
};

struct ArnoldiOptions {
  Eigen::Index wanted = 1;      // eigenvalues
  Eigen::Index first = 30;      // basis size at the first convergence test
  Eigen::Index largest = 300;   // basis size at which it gives up
  Eigen::Index rows = -1;       // eigenvector numbers returned (-1: all)
  double tolerance = 1e-10;     // residual against |value|
  // Which of the wanted values (all converged) are returned with their vectors; empty: all.
  // A caller that keeps one of each conjugate pair says so here, and the other's vector,
  // as large as the kept one's, is never formed.
  std::function<bool(std::complex<double>)> returned;
};

// op(in, out): out = A in, both of size n. Nothing where `largest` vectors do not
// converge the wanted pairs.
std::optional<ArnoldiPairs> arnoldi_largest(const std::function<void(const double*, double*)>& op, Eigen::Index n,
                                            const ArnoldiOptions& o);

}  // namespace mbsflow
