#pragma once
// Workers of a cluster run on threads of a test process (real ZeroMQ sockets, tcp on
// 127.0.0.1 or ipc), a cluster configuration over them, and a short run of a model.
#include <cmath>
#include <functional>
#include <future>
#include <string>
#include <thread>
#include <vector>

#include "mbsflow/graph/stable_step.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/runtime/cluster.hpp"

namespace mbsflow::test {

inline Model short_run(Model m, int steps) {
  m.simulation.step = 0.5 * estimate_stable_step(m).step;
  m.simulation.t_end = m.simulation.t_start + steps * *m.simulation.step;
  m.simulation.output_every = 7;  // chunks of 7 steps; the last snapshot falls off the grid of 7
  return m;
}

// Workers on threads of this process; each serves one run. The promises that hand back
// the bound endpoints live here, not in the threads: none is destroyed by one thread while
// another reads its future.
struct ThreadWorkers {
  std::vector<std::thread> threads;
  std::vector<std::string> endpoints;
  std::vector<std::string> errors;
  std::vector<std::promise<std::string>> bound;

  // adjust(i, options): what worker i differs in (keys, say).
  ThreadWorkers(const std::vector<std::string>& listen, std::function<void(std::size_t, WorkerOptions&)> adjust = {})
      : errors(listen.size()), bound(listen.size()) {
    for (std::size_t i = 0; i < listen.size(); ++i) {
      threads.emplace_back([this, i, l = listen[i], adjust] {
        WorkerOptions o;
        o.listen = l;
        o.threads = 1;
        o.insecure = Insecure::loopback;  // the keyed runs: test_cluster_security.cpp
        o.idle_timeout_s = 30.0;
        o.read_model = [](const std::string& text) { return read_model_text(text, "model from the coordinator"); };
        o.listening = [this, i](const std::string& e) { bound[i].set_value(e); };
        if (adjust) adjust(i, o);
        try {
          serve_worker(o);
        } catch (const std::exception& e) {
          errors[i] = e.what();
          try {  // a worker that never listened: the constructor's get() throws instead of waiting
            bound[i].set_exception(std::current_exception());
          } catch (const std::future_error&) {
          }
        }
      });
      endpoints.push_back(bound[i].get_future().get());
    }
  }
  ~ThreadWorkers() {
    for (auto& t : threads) t.join();
  }
};

inline ClusterConfig cluster_of(const std::vector<std::string>& controls, const std::string& data_bind,
                         const std::string& results_bind) {
  ClusterConfig c;
  c.insecure = Insecure::loopback;
  c.results_bind = results_bind;
  for (std::size_t i = 0; i < controls.size(); ++i) {
    ClusterWorker w;
    w.name = "w" + std::to_string(i);
    w.address = controls[i];
    w.data_bind = data_bind.empty() ? "" : data_bind + std::to_string(i);
    c.workers.push_back(w);
  }
  return c;
}


}  // namespace mbsflow::test
