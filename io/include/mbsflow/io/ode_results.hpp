#pragma once
// Results of an ODE run (mbsflow ode) in HDF5: the solution at every accepted point for
// chosen components, its error against the exact solution, and the record of every step.
#include <string>
#include <utility>
#include <vector>

#include "mbsflow/methods/block_integrator.hpp"

namespace mbsflow {

struct OdeResults {
  std::vector<std::pair<std::string, std::string>> texts;  // root attributes
  std::vector<std::pair<std::string, double>> numbers;
  std::vector<long> components;  // which components are kept
  std::vector<double> time;      // accepted points
  std::vector<double> values;    // time x components, row-major
  std::vector<double> error;     // max |y - exact| over all components per point (empty: no exact solution)
  std::vector<BlockStepRecord> steps;
};

// /solution/{time, components, values, error}, /steps/{t, tau, taken, error, iterations_s,
// iterations_s1, iteration_failed}, attributes on the root. Throws Error on failure.
void write_ode_results(const std::string& path, const OdeResults& r);

}  // namespace mbsflow
