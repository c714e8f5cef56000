#include "mbsflow/analysis/modes.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SparseCholesky>
#include <Spectra/GenEigsRealShiftSolver.h>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "constrained.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/klu_lu.hpp"
#include "mbsflow/methods/real_eigen.hpp"

namespace mbsflow {
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

// A mode found by a solver: its eigenvalue and its coordinates x.
struct Found {
  Complex lambda;
  Eigen::VectorXcd x;
  bool rigid = false;
};

// An eigenvalue below this fraction of rate_scale counts as zero (a rigid-body motion):
// a zero eigenvalue is a Jordan pair of the first-order pencil, which rounding splits by
// about sqrt(machine epsilon) of the scale, and a 100 000-link chain's lowest vibration
// lies at 2e-6 of it.
constexpr double zero_rate = 1e-7;

// The speed of the model's fastest motions (rad/s): the scale against which an
// eigenvalue counts as zero.
double rate_scale(const LinearModel& m) {
  double fastest = 0.0;
  for (Eigen::Index i = 0; i < m.M.rows(); ++i) {
    const double mi = m.M.coeff(i, i), ki = std::abs(m.K.coeff(i, i));
    if (mi > 0.0) fastest = std::max(fastest, std::sqrt(ki / mi));
  }
  return fastest > 0.0 ? fastest : 1.0;
}

// The modes of the reduced dense problem (Mr, Dr, Kr in the basis n_basis).
std::vector<Found> dense_modes(const LinearModel& m, bool damped, Eigen::Index& free) {
  const Eigen::MatrixXd basis = null_space(m.C, m.size());
  free = basis.cols();
  if (free == 0) return {};
  const Eigen::MatrixXd mr = basis.transpose() * (m.M * basis);
  const Eigen::MatrixXd kr = basis.transpose() * (m.K * basis);
  const Eigen::MatrixXd dr = damped ? Eigen::MatrixXd(basis.transpose() * (m.D * basis)) : Eigen::MatrixXd::Zero(free, free);
  const Eigen::LLT<Eigen::MatrixXd> mass(mr);
  if (mass.info() != Eigen::Success) throw InputError("the mass matrix is not positive definite: a body without mass or inertia");
  const double zero = zero_rate * rate_scale(m);
  std::vector<Found> out;
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
    const Sparse aug = augmented<double>(m_.K + sigma * d_ + (sigma * sigma) * m_.M, m_.C);
    lu_.analyze(aug);
    lu_.factorize(aug);
  }
  void perform_op(const double* in, double* out) const {
    const Eigen::Index n = m_.size();
    const Eigen::Map<const Eigen::VectorXd> c(in, n), d(in + n, n);
    Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n + m_.C.rows());
    rhs.head(n) = -(m_.M * d) - d_ * c - sigma_ * (m_.M * c);
    lu_.solve(rhs);
    Eigen::Map<Eigen::VectorXd> a(out, n), b(out + n, n);
    a = rhs.head(n);
    b = c + sigma_ * a;
  }

 private:
  const LinearModel& m_;
  Sparse d_;
  double sigma_ = 0.0;
  KluLu<double> lu_;
};

std::vector<Found> sparse_modes(const LinearModel& m, int count, bool damped) {
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
  const double scale = rate_scale(m);
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
  std::vector<Found> out;
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

}  // namespace

Modes compute_modes(const LinearModel& m, const ModeOptions& o) {
  if (o.count < 1) throw InputError("modes: the count must be >= 1");
  const Eigen::Index n = m.size();
  const bool dense = o.solver == ModeSolver::dense ||
                     (o.solver == ModeSolver::automatic && n - m.C.rows() <= ModeOptions::dense_limit) || 2 * n < 2 * o.count + 8;
  Modes out;
  Eigen::Index free = n;
  std::vector<Found> found = dense ? dense_modes(m, o.damped, free) : sparse_modes(m, o.count, o.damped);
  out.free_coordinates = dense ? free : n - m.C.rows();
  out.solver = dense ? "dense (Eigen), on a null-space basis of the rigid joints' rows"
                     : "sparse shift-invert (Spectra, Arnoldi) on a KLU factorisation, rigid joints through the augmented pencil";
  std::stable_sort(found.begin(), found.end(), [](const Found& a, const Found& b) {
    if (a.rigid != b.rigid) return a.rigid;
    return std::abs(a.lambda) < std::abs(b.lambda);
  });
  if (static_cast<int>(found.size()) > o.count) found.resize(static_cast<std::size_t>(o.count));
  const auto k = static_cast<Eigen::Index>(found.size());
  const auto bodies = static_cast<Eigen::Index>(m.coords.bodies.size());
  out.shape.resize(n, k);
  out.kinetic_share = Eigen::MatrixXd::Zero(bodies, k);
  out.strain_share = Eigen::MatrixXd::Zero(bodies, k);
  const Sparse ks = 0.5 * (m.K + Sparse(m.K.transpose()));
  const Sparse d = o.damped ? m.D : Sparse(n, n);
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
    Found& f = found[static_cast<std::size_t>(j)];
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
    Eigen::VectorXcd r = lambda * lambda * (m.M * x) + lambda * (d * x) + m.K * x;
    if (m.C.rows() > 0) {
      const Eigen::VectorXd re = cct.solve(m.C * r.real()), im = cct.solve(m.C * r.imag());
      r -= (Sparse(m.C.transpose()) * re).cast<Complex>() + Complex(0.0, 1.0) * (Sparse(m.C.transpose()) * im).cast<Complex>();
    }
    const double scale = (std::norm(lambda) * nm + std::abs(lambda) * nd + nk) * x.norm();
    out.residual.push_back(scale > 0.0 ? r.norm() / scale : r.norm());
    const Eigen::VectorXcd mx = m.M * x, kx = ks * x;
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
