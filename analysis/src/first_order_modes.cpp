// The lowest modes by shift-invert Arnoldi on the first-order pencil: 2n numbers per
// vector, any damping. The damped modes of a large model, and the undamped ones where the
// Lanczos of undamped_modes.cpp does not serve. The Arnoldi is ours, without restarts
// (arnoldi.cpp); Spectra's restarted one takes over where that does not converge.
#include <Spectra/GenEigsRealShiftSolver.h>
#include <algorithm>
#include <cmath>

#include "arnoldi.hpp"
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
  // D itself or an empty matrix, not a copy of D (which would be 130 MB more at 100 000 bodies).
  ShiftSolve(const LinearModel& m, bool damped) : m_(m), none_(m.M.rows(), m.M.cols()), d_(damped ? m.D : none_) {}
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
    // Into buffers kept from call to call: a fresh vector of a million numbers is fresh
    // pages, which the kernel clears (a tenth of the eigensolver's time).
    moved_ = d + sigma_ * c;
    rhs_.noalias() = m_.M * moved_;
    rhs_.noalias() += d_ * c;
    rhs_ = -rhs_;
    solve_.solve_into(rhs_, a);
    b = c + sigma_ * a;
  }

 private:
  const LinearModel& m_;
  const Sparse none_;
  const Sparse& d_;
  double sigma_ = 0.0;
  ConstrainedSolve solve_;
  mutable Eigen::VectorXd rhs_, moved_;
};

// The member of a conjugate pair of eigenvalues that is dropped (its mode is the other's).
bool is_lower_of_pair(Complex lambda) { return lambda.imag() < -1e-12 * std::abs(lambda); }

}  // namespace

std::vector<FoundMode> first_order_modes(const LinearModel& m, int count, bool damped, bool* restarted,
                                         const ModeOptions::Notice& notice) {
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
  Eigen::VectorXcd values;
  Eigen::MatrixXcd vectors;  // the coordinates: the first n numbers of each
  // The basis without restarts up to 1.5 GB (156 vectors of a 100 000-body model, which
  // converges its 24 wanted at 58) and 400 vectors (the dense eigensolver of the Ritz
  // values, at each test, grows as the cube of the basis), or as many as Spectra's would
  // hold where -n asks for more.
  ArnoldiOptions o;
  o.wanted = nev;
  o.first = ncv;
  o.largest = std::max(ncv, std::min<Eigen::Index>(400, static_cast<Eigen::Index>(1.5e9 / (8.0 * static_cast<double>(n2)))));
  o.rows = m.size();
  // Of a conjugate pair, the value of positive imaginary part alone is kept below: the
  // other's vector is not formed. Near zero both are (a rigid-body motion's Jordan block
  // may come back as such a pair, whose two vectors hold two motions).
  const double zero = zero_rate * scale;
  const auto eigenvalue = [sigma](Complex nu) { return sigma + 1.0 / nu; };  // of the shifted inverse's nu
  o.returned = [eigenvalue, zero](Complex nu) {
    const Complex lambda = eigenvalue(nu);
    return std::abs(lambda) < zero || !is_lower_of_pair(lambda);
  };
  op.set_shift(sigma);
  const auto apply = [&op](const double* in, double* out) { op.perform_op(in, out); };
  std::optional<ArnoldiPairs> pairs = arnoldi_largest(apply, n2, o);
  *restarted = !pairs;
  if (pairs) {
    values = pairs->values.unaryExpr(eigenvalue);
    vectors = std::move(pairs->vectors);
  } else {
    if (notice)
      notice("the Arnoldi without restarts did not converge: Spectra's restarted Arnoldi takes over (up to 300 restarts; "
             "minutes on a large model with many modes clustered near zero)");
    Spectra::GenEigsRealShiftSolver<ShiftSolve> eigs(op, nev, ncv, sigma);
    eigs.init();
    eigs.compute(Spectra::SortRule::LargestMagn, 300, 1e-10);  // restarts: clustered near-zero modes may not converge
    if (eigs.info() != Spectra::CompInfo::Successful)
      throw RunError("the sparse eigensolver (Spectra, shift-invert) did not converge to " + std::to_string(nev) +
                     " eigenvalues; ask for fewer modes (-n) or the dense solver");
    values = eigs.eigenvalues();
    vectors = eigs.eigenvectors().topRows(m.size());
  }
  std::vector<FoundMode> out;
  Eigen::MatrixXcd rigid(m.size(), 0);  // rigid-body motions found so far, M-orthonormal
  for (Eigen::Index i = 0; i < values.size(); ++i) {
    const Complex lambda = values[i];
    // The augmented pencil's constraint directions are eigenvalues at infinity: the shifted
    // inverse maps them to zero, and they come back here as huge or not finite.
    if (!std::isfinite(lambda.real()) || !std::isfinite(lambda.imag()) || std::abs(lambda) > 1e8 * scale) continue;
    Eigen::VectorXcd x = vectors.col(i);
    if (std::abs(lambda) < zero) {
      // A zero eigenvalue's Jordan pair gives the same motion twice: kept once.
      for (Eigen::Index k = 0; k < rigid.cols(); ++k) x -= rigid.col(k) * (rigid.col(k).adjoint() * (m.M * x))(0);
      const double size = std::sqrt(std::abs((x.adjoint() * (m.M * x))(0)));
      if (size < 1e-6 * std::sqrt(std::abs((vectors.col(i).adjoint() * (m.M * vectors.col(i)))(0))))
        continue;
      x /= size;
      rigid.conservativeResize(Eigen::NoChange, rigid.cols() + 1);
      rigid.col(rigid.cols() - 1) = x;
      out.push_back({0.0, x, true});
      continue;
    }
    if (is_lower_of_pair(lambda)) continue;
    out.push_back({lambda.imag() < 0.0 ? std::conj(lambda) : lambda, x});
  }
  return out;
}

}  // namespace mbsflow
