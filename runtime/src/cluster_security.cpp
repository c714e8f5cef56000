// Who may take part in a run across processes (docs/reliability.md): with keys, only the
// holders of the keys the cluster file lists; without, only what runs on this host.
#include "wire_format.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/runtime/cluster.hpp"

namespace mbsflow {

void check_cluster_security(const ClusterConfig& c) {
  if (c.keys) {
    if (c.keys->public_key != c.coordinator_key)
      throw InputError("the secret key file is not the coordinator's: its public key " + c.keys->public_key +
                       " is not the coordinator's public_key " + (c.coordinator_key.empty() ? "(none given)" : c.coordinator_key));
    for (const ClusterWorker& w : c.workers)
      if (!is_curve_key(w.public_key)) throw InputError("worker " + w.name + " has no public_key in the cluster file");
    return;
  }
  if (c.insecure == Insecure::no)
    throw InputError("the cluster file gives no keys: make a key pair per host with `mbsflow keygen`, name the public "
                     "keys and the local secret_key in the cluster file, or ask for an unauthenticated run on this "
                     "host with --insecure");
  if (c.insecure == Insecure::anywhere) return;
  std::vector<std::string> endpoints{c.results_bind, c.results_address};
  for (const ClusterWorker& w : c.workers) endpoints.insert(endpoints.end(), {w.address, w.data_bind, w.data_address});
  for (const std::string& e : endpoints)
    if (!e.empty() && !wire::loopback(e))
      throw InputError("--insecure runs on this host only, and " + e +
                       " is not a loopback endpoint: give the cluster keys (mbsflow keygen), or --insecure-network "
                       "on a network where everyone who can reach these ports is trusted");
}

}  // namespace mbsflow
