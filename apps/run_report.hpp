#pragma once
// What mbsflow run says: the choices made for the model, how it was cut, the coupling's
// errors, the final state and the closing line.
#include <optional>
#include <string>

#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/runtime/async_sink.hpp"
#include "mbsflow/runtime/cluster.hpp"
#include "mbsflow/runtime/loose_coupling.hpp"
#include "mbsflow/runtime/run_settings.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow::cli {

// Which method and step were chosen where the model and the request leave them open (a
// warning for a given RK4 step above the stability estimate s), in one line.
void say_options(const Model& m, const RunRequest& a, const StableStep& s, const RunOptions& o);
// How the run was cut and where its submodels run (cluster: the worker processes, null on
// threads), and an implicit method's Jacobian.
void say_cut(const Model& m, const RunRequest& a, const RunOptions& o, const std::optional<Decomposition>& d,
             const ClusterConfig* cluster, const std::optional<LooseOptions>& loose, int threads);
// The closing lines of a loosely coupled run: its coupling errors, lags and macro steps.
void print_coupling(const LooseStats& ls, bool adaptive, int max_lag, double tol, bool cluster);
// The final state of the first bodies and the energy balance (a run without -o).
void print_summary(const Model& m, MultibodySystem& sys, const RunOptions& o, const RunSummary& r);
// "mbsflow: done: ..." with the steps, evaluations, wall time, results file, checkpoints
// and peak memory.
void say_done(const Model& m, const RunSummary& r, const AsyncSink* sink, const std::string& output, long checkpoints,
              const std::string& checkpoint_at);

}  // namespace mbsflow::cli
