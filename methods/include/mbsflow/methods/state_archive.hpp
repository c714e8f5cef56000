#pragma once
// The bytes of a checkpoint: what a stepper or a run loop needs to go on bit for bit,
// written as a flat sequence of tagged values (doubles as their bits, so nothing is
// rounded). A reader checks every tag and length and throws InputError on anything that
// does not fit, so a damaged or foreign checkpoint is refused, never half-read.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "mbsflow/error.hpp"

namespace mbsflow {

class StateWriter {
 public:
  void real(double v) { raw('d', &v, sizeof v); }
  void integer(std::int64_t v) { raw('i', &v, sizeof v); }
  void flag(bool v) { integer(v ? 1 : 0); }
  void text(std::string_view s) { block('s', s.data(), s.size()); }
  void vector(const Eigen::VectorXd& v) { block('v', v.data(), static_cast<std::size_t>(v.size()) * sizeof(double)); }
  void vectors(const std::vector<Eigen::VectorXd>& vs) {
    integer(static_cast<std::int64_t>(vs.size()));
    for (const Eigen::VectorXd& v : vs) vector(v);
  }
  void sparse(const Eigen::SparseMatrix<double>& m);
  void bytes(std::span<const std::uint8_t> b) { block('b', b.data(), b.size()); }
  const std::vector<std::uint8_t>& data() const { return out_; }
  std::vector<std::uint8_t> take() { return std::move(out_); }

 private:
  void raw(char tag, const void* p, std::size_t n);
  void block(char tag, const void* p, std::size_t n);
  std::vector<std::uint8_t> out_;
};

class StateReader {
 public:
  // what: names the source in messages ("checkpoint run.ckpt").
  StateReader(std::span<const std::uint8_t> data, std::string what) : in_(data), what_(std::move(what)) {}
  double real();
  std::int64_t integer();
  std::int64_t integer(std::int64_t min, std::int64_t max);  // InputError outside [min, max]
  bool flag() { return integer(0, 1) != 0; }
  std::string text();
  Eigen::VectorXd vector();
  Eigen::VectorXd vector(Eigen::Index size);  // InputError for another size
  std::vector<Eigen::VectorXd> vectors(Eigen::Index size);
  Eigen::SparseMatrix<double> sparse();
  std::vector<std::uint8_t> bytes();
  // The next value must be the text `expected` (a section's name); InputError else.
  void expect(std::string_view expected);
  bool at_end() const { return at_ == in_.size(); }
  [[noreturn]] void fail(const std::string& why) const;

 private:
  void raw(char tag, void* p, std::size_t n);
  std::span<const std::uint8_t> block(char tag);
  std::span<const std::uint8_t> in_;
  std::size_t at_ = 0;
  std::string what_;
};

}  // namespace mbsflow
