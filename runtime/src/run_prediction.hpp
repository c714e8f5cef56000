#pragma once
// What a tightly coupled run on H hosts of T threads will cost per stage, before it is
// started (mbsflow plan; not installed): the model cut into H x T submodels as a cluster
// run cuts it, each host's submodels on its threads, the seed's performance model for the
// exchange between hosts (Hockney: alpha + m / beta per message).
#include "exchange_cost.hpp"
#include "mbsflow/graph/decomposition.hpp"

namespace mbsflow {

struct StagePrediction {
  int hosts = 1, threads = 1;
  int cut_joints = 0;          // over the whole model (between threads and between hosts)
  double imbalance = 0.0;      // of the submodels' estimated times
  double compute_s = 0.0;      // the slowest host's slowest submodel
  double exchange_s = 0.0;     // that host's messages from other hosts, one after another
  int messages = 0;            // between hosts, per stage, all hosts together
  double bytes = 0.0;          // their payload and headers
  double stage_s() const { return compute_s + exchange_s; }
};

// seconds_per_cost: what one unit of the submodels' estimated time (Submodel::
// estimated_time) takes on this host, measured on the whole model. d must have hosts x
// threads submodels; host h takes submodels h T .. (h+1) T - 1 (what a cluster run of
// equal weights assigns). The exchange within a host (shared memory) is taken as free.
StagePrediction predict_stage(const Decomposition& d, int hosts, int threads, double seconds_per_cost, const Hockney& network);

// Bytes of one boundary message carrying `bodies` bodies (their 13 numbers and the header).
double boundary_message_bytes(std::size_t bodies);

}  // namespace mbsflow
