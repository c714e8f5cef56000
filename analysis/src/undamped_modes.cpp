// The lowest undamped modes of a large model, K x = omega^2 M x with K's symmetric part:
// symmetric shift-invert Lanczos (Spectra) on n numbers per vector. The Arnoldi on the
// first-order pencil that the damped modes need keeps 2n numbers per vector and twice as
// many of them, and spends nearly all its time orthogonalising them.
#include <Spectra/SymGEigsShiftSolver.h>
#include <cmath>

#include "constrained.hpp"
#include "mode_solvers.hpp"

namespace mbsflow {
namespace {

using Sparse = Eigen::SparseMatrix<double>;

// (Ks - sigma M)^-1 on the motions the rigid joints allow (the augmented solve). With M's
// inner product, its operator S M is symmetric, as the Lanczos needs.
class ConstrainedInverse {
 public:
  using Scalar = double;
  ConstrainedInverse(const LinearModel& m, const Sparse& ks) : m_(m), ks_(ks) {}
  Eigen::Index rows() const { return m_.size(); }
  Eigen::Index cols() const { return m_.size(); }
  void set_shift(double sigma) { solve_.factor(ks_ - sigma * m_.M, m_.C); }
  void perform_op(const double* in, double* out) const {
    const Eigen::Index n = m_.size();
    Eigen::Map<Eigen::VectorXd>(out, n) = solve_(Eigen::Map<const Eigen::VectorXd>(in, n));
  }

 private:
  const LinearModel& m_;
  const Sparse& ks_;
  ConstrainedSolve solve_;
};

// M v: the Lanczos's inner product.
struct MassProduct {
  using Scalar = double;
  const Sparse& mass;
  Eigen::Index rows() const { return mass.rows(); }
  Eigen::Index cols() const { return mass.cols(); }
  void perform_op(const double* in, double* out) const {
    Eigen::Map<Eigen::VectorXd>(out, mass.rows()).noalias() = mass * Eigen::Map<const Eigen::VectorXd>(in, mass.cols());
  }
};

}  // namespace

std::optional<std::vector<FoundMode>> undamped_modes(const LinearModel& m, int count) {
  const Eigen::Index n = m.size(), free = n - m.C.rows();
  // A few more than asked: room for the restarts to sort the lowest from their neighbours
  // (and for a rigid-body motion to show itself, which sends the model to the Arnoldi).
  const Eigen::Index nev = std::min<Eigen::Index>(count + 4, free - 1);
  const Eigen::Index ncv = std::min<Eigen::Index>(free, std::max<Eigen::Index>(2 * nev + 1, 20));
  // A Krylov space nearly as wide as the allowed motions breaks down before it restarts.
  if (nev < 1 || 2 * ncv > free) return std::nullopt;
  // The shift (on omega^2) just below zero, as the Arnoldi's (there on lambda): the
  // rigid-body motions' zeros stay regular, the lowest vibration stays nearest.
  const double zero = zero_rate * modal_rate_scale(m), sigma = -zero * zero;
  const Sparse ks = 0.5 * (m.K + Sparse(m.K.transpose()));
  ConstrainedInverse inverse(m, ks);
  MassProduct mass{m.M};
  Spectra::SymGEigsShiftSolver<ConstrainedInverse, MassProduct, Spectra::GEigsMode::ShiftInvert> lanczos(inverse, mass, nev, ncv, sigma);
  lanczos.init();
  lanczos.compute(Spectra::SortRule::LargestMagn, 300, 1e-10);
  if (lanczos.info() != Spectra::CompInfo::Successful) return std::nullopt;
  const Eigen::VectorXd omega2 = lanczos.eigenvalues();
  const Eigen::MatrixXd vectors = lanczos.eigenvectors();
  // A rigid-body motion maps to 1 / |sigma|, 1e14 times the fast motions' images: the
  // Lanczos's rounding at that scale leaves the vibrations' values at 1e-7 where the test
  // asks 1e-10 (a floating chain of 20 links, against the dense solver). The Arnoldi,
  // whose shift is on lambda (1e7), serves such models.
  if ((omega2.array().abs() < zero * zero).any()) return std::nullopt;
  std::vector<FoundMode> out;
  for (Eigen::Index i = 0; i < omega2.size(); ++i) {
    const double w2 = omega2[i];
    // omega^2 < 0: a static instability, lambda real and positive (as the dense solver).
    const std::complex<double> lambda = w2 > 0.0 ? std::complex<double>(0.0, std::sqrt(w2)) : std::sqrt(-w2);
    out.push_back({lambda, vectors.col(i).cast<std::complex<double>>(), false});
  }
  return out;
}

}  // namespace mbsflow
