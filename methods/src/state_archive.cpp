#include "mbsflow/methods/state_archive.hpp"

#include <limits>

namespace mbsflow {

void StateWriter::raw(char tag, const void* p, std::size_t n) {
  out_.push_back(static_cast<std::uint8_t>(tag));
  const auto* b = static_cast<const std::uint8_t*>(p);
  out_.insert(out_.end(), b, b + n);
}

void StateWriter::block(char tag, const void* p, std::size_t n) {
  const auto length = static_cast<std::uint64_t>(n);
  raw(tag, &length, sizeof length);
  const auto* b = static_cast<const std::uint8_t*>(p);
  if (n > 0) out_.insert(out_.end(), b, b + n);
}

void StateWriter::sparse(const Eigen::SparseMatrix<double>& m) {
  Eigen::SparseMatrix<double> c = m;
  c.makeCompressed();
  integer(c.rows());
  integer(c.cols());
  const auto nnz = static_cast<std::size_t>(c.nonZeros());
  block('o', c.outerIndexPtr(), static_cast<std::size_t>(c.cols() + 1) * sizeof(int));
  block('n', c.innerIndexPtr(), nnz * sizeof(int));
  block('v', c.valuePtr(), nnz * sizeof(double));
}

void StateReader::fail(const std::string& why) const {
  throw InputError(what_ + ": " + why + " (at byte " + std::to_string(at_) + "; the file is damaged or not from this version)");
}

void StateReader::raw(char tag, void* p, std::size_t n) {
  if (at_ + 1 + n > in_.size()) fail("ends early");
  if (in_[at_] != static_cast<std::uint8_t>(tag))
    fail(std::string("expected a value of kind '") + tag + "', found '" + static_cast<char>(in_[at_]) + "'");
  std::memcpy(p, in_.data() + at_ + 1, n);
  at_ += 1 + n;
}

std::span<const std::uint8_t> StateReader::block(char tag) {
  std::uint64_t n = 0;
  raw(tag, &n, sizeof n);
  if (n > in_.size() - at_) fail("a block is longer than what is left");
  const auto out = in_.subspan(at_, static_cast<std::size_t>(n));
  at_ += static_cast<std::size_t>(n);
  return out;
}

double StateReader::real() {
  double v = 0;
  raw('d', &v, sizeof v);
  return v;
}

std::int64_t StateReader::integer() {
  std::int64_t v = 0;
  raw('i', &v, sizeof v);
  return v;
}

std::int64_t StateReader::integer(std::int64_t min, std::int64_t max) {
  const std::int64_t v = integer();
  if (v < min || v > max) fail("a count of " + std::to_string(v) + " is out of range");
  return v;
}

std::string StateReader::text() {
  const auto b = block('s');
  return {reinterpret_cast<const char*>(b.data()), b.size()};
}

std::vector<std::uint8_t> StateReader::bytes() {
  const auto b = block('b');
  return {b.begin(), b.end()};
}

Eigen::VectorXd StateReader::vector() {
  const auto b = block('v');
  if (b.size() % sizeof(double) != 0) fail("a vector's length is not a whole number of values");
  Eigen::VectorXd v(static_cast<Eigen::Index>(b.size() / sizeof(double)));
  if (!b.empty()) std::memcpy(v.data(), b.data(), b.size());
  return v;
}

Eigen::VectorXd StateReader::vector(Eigen::Index size) {
  Eigen::VectorXd v = vector();
  if (v.size() != size) fail("a vector of " + std::to_string(v.size()) + " values where " + std::to_string(size) + " belong");
  return v;
}

std::vector<Eigen::VectorXd> StateReader::vectors(Eigen::Index size) {
  const auto n = integer(0, 1 << 20);
  std::vector<Eigen::VectorXd> out;
  out.reserve(static_cast<std::size_t>(n));
  for (std::int64_t i = 0; i < n; ++i) out.push_back(vector(size));
  return out;
}

Eigen::SparseMatrix<double> StateReader::sparse() {
  const auto rows = integer(0, std::numeric_limits<int>::max()), cols = integer(0, std::numeric_limits<int>::max());
  const auto outer = block('o'), inner = block('n'), values = block('v');
  const std::size_t nnz = values.size() / sizeof(double);
  if (outer.size() != static_cast<std::size_t>(cols + 1) * sizeof(int) || inner.size() != nnz * sizeof(int) ||
      values.size() % sizeof(double) != 0)
    fail("a sparse matrix's parts do not fit together");
  std::vector<int> op(static_cast<std::size_t>(cols + 1)), ip(nnz);
  std::memcpy(op.data(), outer.data(), outer.size());
  if (nnz > 0) std::memcpy(ip.data(), inner.data(), inner.size());
  if (op.front() != 0 || op.back() != static_cast<int>(nnz)) fail("a sparse matrix's column starts do not fit");
  for (std::size_t c = 0; c + 1 < op.size(); ++c)
    if (op[c] > op[c + 1]) fail("a sparse matrix's column starts are not ordered");
  for (int i : ip)
    if (i < 0 || i >= rows) fail("a sparse matrix's row index is out of range");
  Eigen::SparseMatrix<double> m(rows, cols);
  m.reserve(static_cast<Eigen::Index>(nnz));
  const auto* v = reinterpret_cast<const double*>(values.data());
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(nnz);
  for (std::size_t c = 0; c + 1 < op.size(); ++c)
    for (int k = op[c]; k < op[c + 1]; ++k) {
      double x;
      std::memcpy(&x, reinterpret_cast<const std::uint8_t*>(v) + static_cast<std::size_t>(k) * sizeof(double), sizeof x);
      t.emplace_back(ip[static_cast<std::size_t>(k)], static_cast<int>(c), x);
    }
  // Explicit zeros are kept (setFromTriplets keeps every entry): the pattern is part of the state.
  m.setFromTriplets(t.begin(), t.end());
  m.makeCompressed();
  if (m.nonZeros() != static_cast<Eigen::Index>(nnz)) fail("a sparse matrix has repeated entries");
  return m;
}

void StateReader::expect(std::string_view expected) {
  const std::string got = text();
  if (got != expected) fail("expected the section '" + std::string(expected) + "', found '" + got + "'");
}

}  // namespace mbsflow
