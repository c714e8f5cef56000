// The Arnoldi without restarts (analysis/src/arnoldi.cpp) against matrices whose
// eigenvalues are known: real and complex, a basis that closes on an invariant subspace,
// and a cap too small to converge.
#include <catch2/catch.hpp>
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "arnoldi.hpp"

namespace {

// S diag-blocks(values) S^-1: real values on the diagonal, a + bi as [a b; -b a].
Eigen::MatrixXd with_spectrum(const std::vector<std::complex<double>>& values, int seed) {
  std::vector<Eigen::Index> at;
  Eigen::Index n = 0;
  for (const auto& v : values) {
    at.push_back(n);
    n += v.imag() == 0.0 ? 1 : 2;
  }
  Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const auto k = at[i];
    if (values[i].imag() == 0.0) {
      d(k, k) = values[i].real();
    } else {
      d.block<2, 2>(k, k) << values[i].real(), values[i].imag(), -values[i].imag(), values[i].real();
    }
  }
  std::srand(static_cast<unsigned>(seed));
  const Eigen::MatrixXd s = Eigen::MatrixXd::Identity(n, n) + 0.3 * Eigen::MatrixXd::Random(n, n) / std::sqrt(double(n));
  return s * d * s.inverse();
}

std::function<void(const double*, double*)> product_with(const Eigen::MatrixXd& a) {
  return [&a](const double* in, double* out) {
    Eigen::Map<Eigen::VectorXd>(out, a.rows()).noalias() = a * Eigen::Map<const Eigen::VectorXd>(in, a.cols());
  };
}

}  // namespace

TEST_CASE("arnoldi: the largest eigenvalues of a matrix with known spectrum, real and complex") {
  // Values 1/k, as a shift-invert's, and two conjugate pairs among the largest.
  std::vector<std::complex<double>> values;
  values.emplace_back(2.0, 1.5);  // |.| = 2.5 and its conjugate
  values.emplace_back(-1.8, 0.0);
  values.emplace_back(0.5, -1.2);  // |.| = 1.3
  for (int k = 1; k <= 300; ++k) values.emplace_back(1.0 / (k + 1.0), 0.0);
  const Eigen::MatrixXd a = with_spectrum(values, 3);
  mbsflow::ArnoldiOptions o;
  o.wanted = 8;
  const auto pairs = mbsflow::arnoldi_largest(product_with(a), a.rows(), o);
  REQUIRE(pairs);
  const std::vector<std::complex<double>> expected{{2.0, 1.5}, {2.0, -1.5}, {-1.8, 0.0}, {0.5, 1.2}, {0.5, -1.2},
                                                   {0.5, 0.0}, {1.0 / 3.0, 0.0}, {0.25, 0.0}};
  for (std::size_t i = 0; i < expected.size(); ++i) {
    CHECK(std::abs(pairs->values[static_cast<Eigen::Index>(i)] - expected[i]) < 1e-10);
    // A x = lambda x for the vector returned.
    const Eigen::VectorXcd x = pairs->vectors.col(static_cast<Eigen::Index>(i));
    const Eigen::VectorXcd r = a.cast<std::complex<double>>() * x - expected[i] * x;
    CHECK(r.norm() < 1e-8 * x.norm());
  }
  CHECK(pairs->operations < 150);
}

TEST_CASE("arnoldi: only the values a caller keeps come back with their vectors") {
  // One of each conjugate pair, as first_order_modes keeps them: the converged set is the
  // same, the pairs' other members are left out, and the vectors still fit their values.
  std::vector<std::complex<double>> values;
  values.emplace_back(2.0, 1.5);
  values.emplace_back(-1.8, 0.0);
  values.emplace_back(0.5, -1.2);
  for (int k = 1; k <= 300; ++k) values.emplace_back(1.0 / (k + 1.0), 0.0);
  const Eigen::MatrixXd a = with_spectrum(values, 3);
  mbsflow::ArnoldiOptions o;
  o.wanted = 8;
  o.returned = [](std::complex<double> v) { return v.imag() >= 0.0; };
  const auto pairs = mbsflow::arnoldi_largest(product_with(a), a.rows(), o);
  REQUIRE(pairs);
  const std::vector<std::complex<double>> expected{{2.0, 1.5}, {-1.8, 0.0}, {0.5, 1.2}, {0.5, 0.0}, {1.0 / 3.0, 0.0}, {0.25, 0.0}};
  REQUIRE(pairs->values.size() == static_cast<Eigen::Index>(expected.size()));
  REQUIRE(pairs->vectors.cols() == pairs->values.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    CHECK(std::abs(pairs->values[static_cast<Eigen::Index>(i)] - expected[i]) < 1e-10);
    const Eigen::VectorXcd x = pairs->vectors.col(static_cast<Eigen::Index>(i));
    const Eigen::VectorXcd r = a.cast<std::complex<double>>() * x - expected[i] * x;
    CHECK(r.norm() < 1e-8 * x.norm());
  }
}

TEST_CASE("arnoldi: a basis that closes on an invariant subspace gives its pairs") {
  // Rank 5: the Krylov space closes after five vectors, whose Ritz pairs are exact.
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(60, 60);
  const double diagonal[5] = {5.0, -4.0, 3.0, 2.0, 1.0};
  for (int i = 0; i < 5; ++i) a(i * 7, i * 7) = diagonal[i];
  mbsflow::ArnoldiOptions o;
  o.wanted = 5;
  o.first = 5;
  const auto pairs = mbsflow::arnoldi_largest(product_with(a), a.rows(), o);
  REQUIRE(pairs);
  for (int i = 0; i < 5; ++i) CHECK(std::abs(pairs->values[i] - diagonal[i]) < 1e-12);
}

TEST_CASE("arnoldi: nothing where the cap on the basis comes before convergence") {
  std::vector<std::complex<double>> values;
  for (int k = 0; k < 200; ++k) values.emplace_back(1.0 - 1e-3 * k, 0.0);  // clustered: slow
  const Eigen::MatrixXd a = with_spectrum(values, 5);
  mbsflow::ArnoldiOptions o;
  o.wanted = 6;
  o.first = 10;
  o.largest = 12;
  CHECK_FALSE(mbsflow::arnoldi_largest(product_with(a), a.rows(), o));
}
