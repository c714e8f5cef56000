#include "arnoldi.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <vector>

#include "blas_product.hpp"
#include "mbsflow/methods/real_eigen.hpp"

namespace mbsflow {
namespace {

// A reproducible start in [-0.5, 0.5) (splitmix64): the same basis on every machine.
void fill_random(double* v, Eigen::Index n, std::uint64_t seed) {
  for (Eigen::Index i = 0; i < n; ++i) {
    std::uint64_t z = (seed += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    z ^= z >> 31;
    v[i] = static_cast<double>(z >> 11) * 0x1.0p-53 - 0.5;
  }
}

// w -= V h with h = V^T w, and again where the pass cancelled most of w (it then leaves w
// off orthogonal by the cancellation's ratio, which shift-invert makes large): the test of
// Daniel, Gragg, Kaufman and Stewart, with ARPACK's 0.717. h accumulates the passes.
// Returns |w|.
double orthogonalise(const Eigen::MatrixXd& v, Eigen::Index columns, double* w, double* h) {
  const Eigen::Index n = v.rows();
  const Columns basis(v.leftCols(columns));
  Eigen::VectorXd pass(columns);
  std::fill(h, h + columns, 0.0);
  double size = Eigen::Map<const Eigen::VectorXd>(w, n).norm();
  for (int again = 0; again < 2; ++again) {
    transposed_times(basis, w, pass.data());
    subtract_times(basis, pass.data(), w);
    for (Eigen::Index i = 0; i < columns; ++i) h[i] += pass[i];
    const double left = Eigen::Map<const Eigen::VectorXd>(w, n).norm();
    if (left > 0.717 * size) return left;
    size = left;
  }
  return size;
}

struct Ritz {
  Eigen::VectorXcd values;
  Eigen::MatrixXcd vectors;  // of the Hessenberg matrix, unit length
  std::vector<Eigen::Index> order;  // largest |value| first
};

Ritz ritz_pairs(const Eigen::MatrixXd& h) {
  RealEigen e = real_eigen(h, true);
  Ritz r{e.values, e.vectors, std::vector<Eigen::Index>(static_cast<std::size_t>(e.values.size()))};
  for (Eigen::Index i = 0; i < r.vectors.cols(); ++i) r.vectors.col(i).normalize();
  std::iota(r.order.begin(), r.order.end(), Eigen::Index{0});
  // Ties (a conjugate pair) by the imaginary part: the order does not hang on rounding.
  std::stable_sort(r.order.begin(), r.order.end(), [&](Eigen::Index a, Eigen::Index b) {
    const double ma = std::abs(r.values[a]), mb = std::abs(r.values[b]);
    if (ma != mb) return ma > mb;
    return r.values[a].imag() > r.values[b].imag();
  });
  return r;
}

}  // namespace

std::optional<ArnoldiPairs> arnoldi_largest(const std::function<void(const double*, double*)>& op, Eigen::Index n,
                                            const ArnoldiOptions& o) {
  const Eigen::Index largest = std::min(o.largest, n);
  const Eigen::Index wanted = std::min(o.wanted, largest - 1);
  if (wanted < 1) return std::nullopt;
  // Reserved whole, touched a column at a time: the pages of vectors never built are never
  // mapped.
  Eigen::MatrixXd v(n, largest);
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(largest + 1, largest);
  Eigen::VectorXd w(n);
  fill_random(v.col(0).data(), n, 1);
  v.col(0).normalize();
  for (int k = 0; k < 3; ++k) {
    op(v.col(0).data(), w.data());
    v.col(0) = w.normalized();
  }
  int operations = 0;
  Eigen::VectorXd sizes(largest);  // |A v_j|: column j of A V = V H + f e^T holds to eps of it
  Eigen::Index next_test = std::max(std::min(o.first, largest), wanted + 1);
  std::uint64_t seed = 2;
  const double eps = std::numeric_limits<double>::epsilon();
  for (Eigen::Index j = 0; j < largest; ++j) {
    op(v.col(j).data(), w.data());
    ++operations;
    const Eigen::Index m = j + 1;
    const double size = w.norm();
    sizes[j] = size;
    const double beta = orthogonalise(v, m, w.data(), h.col(j).data());
    h(m, j) = beta;
    // The basis spans an invariant subspace when the new direction is rounding: its Ritz
    // pairs are exact. Otherwise the test at the planned sizes.
    const bool invariant = !(beta > 1e3 * eps * size);
    if (invariant || m == next_test || m == largest) {
      const Ritz r = ritz_pairs(h.topLeftCorner(m, m));
      bool converged = static_cast<Eigen::Index>(r.order.size()) >= wanted;
      for (Eigen::Index k = 0; k < wanted && converged; ++k) {
        const Eigen::Index i = r.order[static_cast<std::size_t>(k)];
        // Converged where the residual is below the tolerance and the rounding of the
        // relation A V = V H + f e^T along the pair, eps sum_j |y_j| |A v_j|, is below a
        // millionth of the value: a value under that floor is not known, however small its
        // residual. An augmented pencil's infinite eigenvalues (Jordan blocks at zero of
        // the inverse, whose |A v| reaches 2e8 in a 4-DOF governor) leave such values,
        // 0.00015 beside a true 0.00004; Spectra's restarts purge them, and it takes over.
        const double value = std::abs(r.values[i]);
        const double residual = (invariant ? 0.0 : beta) * std::abs(r.vectors(m - 1, i));
        const double rounding = eps * r.vectors.col(i).head(m).cwiseAbs().dot(sizes.head(m));
        converged = residual <= o.tolerance * value && rounding <= 1e-6 * value;
      }
      if (converged) {
        ArnoldiPairs out;
        out.operations = operations;
        const Eigen::Index rows = o.rows < 0 ? n : std::min(o.rows, n);
        std::vector<Eigen::Index> kept;
        for (Eigen::Index k = 0; k < wanted; ++k)
          if (const Eigen::Index i = r.order[static_cast<std::size_t>(k)]; !o.returned || o.returned(r.values[i])) kept.push_back(i);
        const auto count = static_cast<Eigen::Index>(kept.size());
        // One product for the real and imaginary parts, then the complex vectors: the
        // fewest arrays of the basis's length made.
        Eigen::MatrixXd parts(m, 2 * count);
        out.values.resize(count);
        for (Eigen::Index k = 0; k < count; ++k) {
          const Eigen::Index i = kept[static_cast<std::size_t>(k)];
          out.values[k] = r.values[i];
          parts.col(k) = r.vectors.col(i).real();
          parts.col(count + k) = r.vectors.col(i).imag();
        }
        const Eigen::MatrixXd x = product(Columns(v.topLeftCorner(rows, m)), parts);
        out.vectors.resize(rows, count);
        for (Eigen::Index k = 0; k < count; ++k)
          for (Eigen::Index row = 0; row < rows; ++row) out.vectors(row, k) = {x(row, k), x(row, count + k)};
        return out;
      }
      next_test = std::min(largest, m + std::max<Eigen::Index>(5, m / 5));
    }
    if (m == largest) break;
    if (invariant) {
      // A fresh direction, orthogonal to the basis: the next column of H starts a new block.
      fill_random(w.data(), n, ++seed);
      Eigen::VectorXd ignored(m);
      const double fresh = orthogonalise(v, m, w.data(), ignored.data());
      if (!(fresh > 0.0)) break;
      h(m, j) = 0.0;
      v.col(m) = w / fresh;
    } else {
      v.col(m) = w / beta;
    }
  }
  return std::nullopt;
}

}  // namespace mbsflow
