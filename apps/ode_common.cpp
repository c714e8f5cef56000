#include "ode_common.hpp"

#include <algorithm>
#include <cstdio>
#include <iostream>

#include "commands.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/methods/uncontrolled.hpp"
#include "mbsflow/version.hpp"

namespace mbsflow::cli {

OdeRecorder::OdeRecorder(const OdeProblem& p, bool keep) : p_(p), keep_(keep) {
  const long count = std::min<long>(p.size, 9);
  for (long i = 0; i < count; ++i) out_.components.push_back(count == 1 ? 0 : i * (p.size - 1) / (count - 1));
}

void OdeRecorder::add(double t, const Eigen::VectorXd& y) {
  const double err = p_.exact ? (y - p_.exact(t)).cwiseAbs().maxCoeff() : 0.0;
  max_error_ = std::max(max_error_, err);
  if (largest_.size() == 0)
    largest_ = y.cwiseAbs();
  else
    largest_ = largest_.cwiseMax(y.cwiseAbs());  // in place: no vector allocated per point
  if (!keep_) return;
  out_.time.push_back(t);
  for (long c : out_.components) out_.values.push_back(y(c));
  if (p_.exact) out_.error.push_back(err);
}

void OdeRecorder::warn_uncontrolled(double atol, const Eigen::VectorXd& atols) const {
  const auto name = [&](Eigen::Index i) { return p_.describe ? p_.describe(i) : "component " + std::to_string(i + 1); };
  const std::string warning = uncontrolled_warning(largest_, atol, atols, name, "at any accepted point");
  if (!warning.empty()) std::fprintf(stderr, "mbsflow ode: warning: %s\n", render(warning, flag_for).c_str());
}

void set_tolerance(const std::vector<double>& given, double& scalar, Eigen::VectorXd& vector) {
  if (given.size() == 1) {
    scalar = given[0];
    vector.resize(0);
  } else if (given.size() > 1) {
    vector = Eigen::Map<const Eigen::VectorXd>(given.data(), Eigen::Index(given.size()));
  }
}

void report_end_error(const OdeProblem& p, const Eigen::VectorXd& y_end) {
  if (p.exact || p.end_reference.size() != y_end.size()) return;
  const double e = (y_end - p.end_reference).cwiseAbs().maxCoeff();
  std::printf("error at t_end %.3e (max over components; relative: %.3e), against %s\n", e,
              ((y_end - p.end_reference).array() / p.end_reference.array().abs()).abs().maxCoeff(), p.end_reference_source.c_str());
}

void OdeRecorder::write(const std::string& path, std::vector<BlockStepRecord> steps,
                        std::vector<std::pair<std::string, std::string>> texts, std::vector<std::pair<std::string, double>> numbers,
                        bool quiet) {
  if (!keep_) return;
  out_.steps = std::move(steps);
  out_.texts = {{"mbsflow_version", MBSFLOW_VERSION}, {"command", invocation()}};
  out_.texts.insert(out_.texts.end(), texts.begin(), texts.end());
  out_.numbers = std::move(numbers);
  out_.numbers.emplace_back("max_error", max_error_);
  write_ode_results(path, out_);
  if (!quiet) std::cerr << "results: " << path << " (plot: mbsflow plot " << path << ")\n";
}

}  // namespace mbsflow::cli
