#pragma once
// The single-partition run that partitioned runs are compared with, bit for bit; the
// accurate DOPRI5 run that implicit runs are compared with.
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

// 0.05 s of the system with DOPRI5 at tolerance 1e-10, snapshots every 5 ms; o is left set
// for tirk at 1e-7 over the same span and grid.
inline MemorySink dopri5_reference(MultibodySystem& sys, RunOptions& o) {
  o.t_end = o.t_start + 0.05;
  o.output_interval = 0.005;
  o.method = Method::dopri5;
  o.rtol = o.atol = 1e-10;
  MemorySink reference;
  run_simulation(sys, o, &reference);
  o.method = Method::tirk;
  o.rtol = o.atol = 1e-7;
  return reference;
}

}  // namespace mbsflow::test
