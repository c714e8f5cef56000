#include "mbsflow/methods/uncontrolled.hpp"

#include <cstdio>

namespace mbsflow {

std::string uncontrolled_warning(const Eigen::VectorXd& largest, double atol, const Eigen::VectorXd& atols,
                                 const std::function<std::string(Eigen::Index)>& name, const std::string& where) {
  Eigen::Index first = -1, count = 0;
  for (Eigen::Index i = 0; i < largest.size(); ++i)
    if (largest(i) < (atols.size() ? atols(i) : atol)) {
      if (first < 0) first = i;
      ++count;
    }
  if (first < 0) return "";
  char numbers[96];
  std::snprintf(numbers, sizeof numbers, "%.3g (largest |y| %.3g %s)", atols.size() ? atols(first) : atol, largest(first),
                where.c_str());
  return name(first) + " never exceeded its absolute tolerance " + numbers +
         (count > 1 ? " and so did " + std::to_string(count - 1) + " more components" : std::string()) +
         ": held to atol in absolute terms only, none of its digits need be right, and a solution that depends on it can end "
         "far off (give per-component tolerances, {atol=A1,A2,...}, each below its component's size)";
}

}  // namespace mbsflow
