#pragma once
#include <atomic>
// Runs another sink on its own thread behind a bounded queue, so that writing results
// never holds the computation back unless the queue is full. What the inner sink wants
// besides the state (energies, joint wrenches) is computed on the writer thread too,
// from the writer's own copy of the system, and so is the projection of a dense output's
// state onto the constraints (a rigid cluster's factorisations per snapshot).
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>

#include "mbsflow/runtime/result_sink.hpp"

namespace mbsflow {

struct AsyncSinkStats {
  long snapshots = 0;
  long waits = 0;             // times the computation found the queue full
  double wait_seconds = 0.0;  // and how long it waited in all
  double writer_seconds = 0.0;  // time the writer thread spent in the inner sink's write()
};

class AsyncSink : public ResultSink {
 public:
  // capacity_bytes bounds the memory of the snapshots queued and being written (at least
  // one). A million bodies' state is 104 MB: the run hands over the next snapshot once the
  // writer is done with the last.
  explicit AsyncSink(std::unique_ptr<ResultSink> inner, std::size_t capacity_bytes = std::size_t{128} << 20);
  ~AsyncSink() override;

  SnapshotContent content() const override {  // the writer computes the rest
    SnapshotContent c;
    c.projects = true;
    return c;
  }
  void begin(const MultibodySystem& system) override;
  void write(Snapshot&& snapshot) override;
  void make_room() override;  // waits until write() would not
  void write_coupling(const std::vector<CouplingRecord>& records) override;  // handed on at end()
  void end() override;
  void sync() override;  // waits until the queue is written, then syncs the inner sink
  std::string identity() const override { return inner_->identity(); }
  void resume(const MultibodySystem& system, long snapshots, const std::string& identity) override;
  const AsyncSinkStats& stats() const { return stats_; }  // after end()
  // Once *stop is set, end() drops the queued snapshots instead of writing them (and a full
  // queue takes no more), so that a stopped run ends within a second or so whatever the
  // disk's speed; loss() says how many.
  void set_stop(const std::atomic<bool>* stop) { stop_ = stop; }
  SinkLoss loss() const override;
  long waits() const;  // times the computation found the queue full so far (any thread)

 private:
  void run();
  void start_writer(const MultibodySystem& system);
  void rethrow_writer_error();
  bool wait_for_room(std::unique_lock<std::mutex>& lock);
  bool stopping() const;

  std::unique_ptr<ResultSink> inner_;
  std::unique_ptr<MultibodySystem> system_;  // the writer's copy, for projections, energies and joint wrenches
  std::size_t capacity_bytes_;
  std::size_t capacity_ = 1;  // snapshots queued and being written
  mutable std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<Snapshot> queue_;
  std::vector<CouplingRecord> coupling_;
  bool closing_ = false;
  std::exception_ptr error_;
  std::thread writer_;
  AsyncSinkStats stats_;
  const std::atomic<bool>* stop_ = nullptr;
  long dropped_ = 0;
  double t_taken_ = 0.0;  // of the last snapshot the writer took
  bool took_any_ = false;
  bool writing_ = false;  // the writer holds a snapshot it took from the queue
};

}  // namespace mbsflow
