#include "mbsflow/runtime/async_sink.hpp"

#include <algorithm>
#include <chrono>

namespace mbsflow {

AsyncSink::AsyncSink(std::unique_ptr<ResultSink> inner, std::size_t capacity_bytes)
    : inner_(std::move(inner)), capacity_bytes_(capacity_bytes) {}

AsyncSink::~AsyncSink() {
  try {
    end();
  } catch (...) {  // a destructor must not throw; end() was the place to see the error
  }
}

void AsyncSink::begin(const MultibodySystem& system) {
  inner_->begin(system);
  start_writer(system);
}

void AsyncSink::resume(const MultibodySystem& system, long snapshots, const std::string& identity) {
  inner_->resume(system, snapshots, identity);
  start_writer(system);
}

void AsyncSink::start_writer(const MultibodySystem& system) {
  system_ = std::make_unique<MultibodySystem>(system);  // its workspace is made only if used
  const std::size_t bytes = static_cast<std::size_t>(system.dimension()) * sizeof(double) + 64;
  capacity_ = std::max<std::size_t>(1, capacity_bytes_ / bytes);
  writer_ = std::thread([this] { run(); });
}

// Lock held. Waits while capacity_ snapshots are queued or being written (unless the writer
// failed), in slices: a stop request does not signal the condition. False: still full,
// and stopping.
bool AsyncSink::wait_for_room(std::unique_lock<std::mutex>& lock) {
  const auto full = [&] { return queue_.size() + (writing_ ? 1 : 0) >= capacity_ && !error_; };
  if (!full()) return true;
  const auto start = std::chrono::steady_clock::now();
  ++stats_.waits;
  while (!not_full_.wait_for(lock, std::chrono::milliseconds(50), [&] { return !full(); }))
    if (stopping()) break;
  stats_.wait_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return !full();
}

void AsyncSink::make_room() {
  std::unique_lock lock(mutex_);
  wait_for_room(lock);
}

void AsyncSink::write(Snapshot&& snapshot) {
  std::unique_lock lock(mutex_);
  if (!wait_for_room(lock)) {  // stopping: this one is not kept
    ++dropped_;
    return;
  }
  if (error_) {
    lock.unlock();
    rethrow_writer_error();
  }
  queue_.push_back(std::move(snapshot));
  ++stats_.snapshots;
  lock.unlock();
  not_empty_.notify_one();
}

long AsyncSink::waits() const {
  std::lock_guard lock(mutex_);
  return stats_.waits;
}

void AsyncSink::sync() {
  {
    std::unique_lock lock(mutex_);
    not_full_.wait(lock, [&] { return (queue_.empty() && !writing_) || error_; });
    // The writer waits for the next snapshot, which only this thread hands over.
    if (!error_) inner_->sync();
  }
  rethrow_writer_error();
}

void AsyncSink::write_coupling(const std::vector<CouplingRecord>& records) { coupling_ = records; }

void AsyncSink::end() {
  if (writer_.joinable()) {
    {
      std::unique_lock lock(mutex_);
      closing_ = true;
      not_empty_.notify_one();
      // Drains the queue, unless a stop request comes meanwhile (checked in slices: it
      // does not signal): then what is still queued is dropped.
      while (!queue_.empty()) {
        if (stopping()) {
          dropped_ += static_cast<long>(queue_.size());
          queue_.clear();
          break;
        }
        not_full_.wait_for(lock, std::chrono::milliseconds(50));
      }
    }
    writer_.join();
    try {
      if (!coupling_.empty()) inner_->write_coupling(coupling_);
    } catch (...) {
      inner_->end();
      throw;
    }
    inner_->end();
  }
  rethrow_writer_error();
}

bool AsyncSink::stopping() const { return stop_ && stop_->load(std::memory_order_relaxed); }

SinkLoss AsyncSink::loss() const {
  std::lock_guard lock(mutex_);
  return {dropped_, took_any_ ? t_taken_ : 0.0};
}

void AsyncSink::rethrow_writer_error() {
  std::exception_ptr e;
  {
    std::lock_guard lock(mutex_);
    std::swap(e, error_);
  }
  if (e) std::rethrow_exception(e);
}

void AsyncSink::run() {
  while (true) {
    Snapshot s;
    {
      std::unique_lock lock(mutex_);
      not_empty_.wait(lock, [&] { return !queue_.empty() || closing_; });
      if (queue_.empty()) return;  // closing and drained
      s = std::move(queue_.front());
      queue_.pop_front();
      t_taken_ = s.t;
      took_any_ = true;
      writing_ = true;
    }
    not_full_.notify_one();
    try {
      const auto start = std::chrono::steady_clock::now();
      const SnapshotContent want = inner_->content();
      if (s.unprojected) system_->after_step(s.t, s.state);
      s.unprojected = false;
      if (want.energy) s.energy = system_->energy(s.t, s.state);
      if (want.joint_wrench) {
        system_->joint_wrenches(s.t, s.state, s.joint_wrench);
        s.motor_effort = system_->motor_efforts();
      }
      inner_->write(std::move(s));
      s = Snapshot();  // its memory goes before the run is told that there is room
      const double spent = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      {
        std::lock_guard lock(mutex_);
        stats_.writer_seconds += spent;
        writing_ = false;
      }
      not_full_.notify_all();
    } catch (...) {
      std::lock_guard lock(mutex_);
      writing_ = false;
      error_ = std::current_exception();
      queue_.clear();
      not_full_.notify_all();
      return;
    }
  }
}

}  // namespace mbsflow
