// The lowest modes by shift-invert Arnoldi on the first-order pencil: 2n numbers per
// vector, any damping. The damped modes of a large model, and the undamped ones where the
// Lanczos of undamped_modes.cpp does not serve.
#include <Spectra/GenEigsRealShiftSolver.h>
#include <cmath>

#include "constrained.hpp"
#include "mbsflow/error.hpp"
#include "mode_solvers.hpp"

namespace mbsflow {
namespace {

using Sparse = Eigen::SparseMatrix<double>;
using Complex = std::complex<double>;

// (A - sigma B)^-1 B of the first-order pencil A = [0 I; -K -D], B = [I 0; 0 M], with the
// rigid joints' rows held through the augmented matrix [P C^T; C 0], P = K + sigma D + sigma^2 M.
class ShiftSolve {
 public:
  using Scalar = double;
  ShiftSolve(const LinearModel& m, bool damped) : m_(m), d_(damped ? m.D : Sparse(m.M.rows(), m.M.cols())) {}
  Eigen::Index rows() const { return 2 * m_.size(); }
  Eigen::Index cols() const { return 2 * m_.size(); }
  void set_shift(double sigma) {
    sigma_ = sigma;
    solve_.factor(m_.K + sigma * d_ + (sigma * sigma) * m_.M, m_.C);
  }
  void perform_op(const double* in, double* out) const {
    const Eigen::Index n = m_.size();
    const Eigen::Map<const Eigen::VectorXd> c(in, n), d(in + n, n);
    Eigen::Map<Eigen::VectorXd> a(out, n), b(out + n, n);
    a = solve_(-(m_.M * d) - d_ * c - sigma_ * (m_.M * c));
    b = c + sigma_ * a;
  }

 private:
  const LinearModel& m_;
  Sparse d_;
  double sigma_ = 0.0;
  ConstrainedSolve solve_;
};

}  // namespace

std::vector<FoundMode> first_order_modes(const LinearModel& m, int count, bool damped) {
  ShiftSolve op(m, damped);
  const Eigen::Index n2 = op.rows();
  // Each vibration is a conjugate pair of the first-order pencil; rigid-body motions a
  // pair at zero: twice the modes asked for, and a few more.
  const Eigen::Index nev = std::min<Eigen::Index>(2 * count + 4, n2 - 2);
  const Eigen::Index ncv = std::min<Eigen::Index>(n2, std::max<Eigen::Index>(2 * nev + 1, 30));
  // A shift just off zero: the modes nearest it are the lowest, rigid-body ones included,
  // and the shifted matrix stays regular where the stiffness is not. It must lie well
  // below the lowest vibration: the inverse separates lambda_1 and lambda_k only by
  // |lambda_k - sigma| / |lambda_1 - sigma|, and a long chain's lowest modes are 1e-5 of
  // its fastest rate (sigma at 1e-4 of it made 100 000 links take minutes of restarts).
  const double scale = modal_rate_scale(m);
  const double sigma = -zero_rate * scale;
  Spectra::GenEigsRealShiftSolver<ShiftSolve> eigs(op, nev, ncv, sigma);
  eigs.init();
  eigs.compute(Spectra::SortRule::LargestMagn, 300, 1e-10);  // restarts: clustered near-zero modes may not converge
  if (eigs.info() != Spectra::CompInfo::Successful)
    throw RunError("the sparse eigensolver (Spectra, shift-invert) did not converge to " + std::to_string(nev) +
                   " eigenvalues; ask for fewer modes (-n) or the dense solver");
  const Eigen::VectorXcd values = eigs.eigenvalues();
  const Eigen::MatrixXcd vectors = eigs.eigenvectors();
  const double zero = zero_rate * scale;
  std::vector<FoundMode> out;
  Eigen::MatrixXcd rigid(m.size(), 0);  // rigid-body motions found so far, M-orthonormal
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    const Complex lambda = values[i];
    // The augmented pencil's constraint directions are eigenvalues at infinity: the shifted
    // inverse maps them to zero, and they come back here as huge or not finite.
    if (!std::isfinite(lambda.real()) || !std::isfinite(lambda.imag()) || std::abs(lambda) > 1e8 * scale) continue;
    Eigen::VectorXcd x = vectors.col(i).head(m.size());
    if (std::abs(lambda) < zero) {
      // A zero eigenvalue's Jordan pair gives the same motion twice: kept once.
      for (Eigen::Index k = 0; k < rigid.cols(); ++k) x -= rigid.col(k) * (rigid.col(k).adjoint() * (m.M * x))(0);
      const double size = std::sqrt(std::abs((x.adjoint() * (m.M * x))(0)));
      if (size < 1e-6 * std::sqrt(std::abs((vectors.col(i).head(m.size()).adjoint() * (m.M * vectors.col(i).head(m.size())))(0))))
        continue;
      x /= size;
      rigid.conservativeResize(Eigen::NoChange, rigid.cols() + 1);
      rigid.col(rigid.cols() - 1) = x;
      out.push_back({0.0, x, true});
      continue;
    }
    if (lambda.imag() < -1e-12 * std::abs(lambda)) continue;
    out.push_back({lambda.imag() < 0.0 ? std::conj(lambda) : lambda, x});
  }
  return out;
}

}  // namespace mbsflow
