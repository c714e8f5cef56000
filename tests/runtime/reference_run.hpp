#pragma once
// The single-partition run that partitioned runs are compared with, bit for bit.
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"

namespace mbsflow::test {

// Runs m with the method (rtol = atol = 1e-7 for adaptive ones) on one thread; m keeps
// those settings for the runs compared with it.
inline MemorySink reference_run(Model& m, Method method) {
  m.simulation.method = method;
  m.simulation.rtol = m.simulation.atol = 1e-7;
  MultibodySystem sys(m);
  MemorySink reference;
  run_simulation(sys, options_from_model(m), &reference);
  return reference;
}

}  // namespace mbsflow::test
