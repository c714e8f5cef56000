#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <thread>

#include "mbsflow/error.hpp"
#include "mbsflow/runtime/async_sink.hpp"
#include "mbsflow/runtime/simulation.hpp"
#include "memory_sink.hpp"
#include "test_support.hpp"

using namespace mbsflow;

namespace {

// Its first write holds the writer thread until the computation has found the queue full
// (AsyncSink::waits), whatever the timing of the build.
struct SlowSink : test::MemorySink {
  int fail_at = -1;
  const AsyncSink* owner = nullptr;
  void write(Snapshot&& s) override {
    if (times.empty() && owner)
      while (owner->waits() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    if (static_cast<int>(times.size()) == fail_at) throw Error("disk full");
    test::MemorySink::write(std::move(s));
  }
};

Model falling_body() {
  Model m;
  m.gravity = {0, -9.81, 0};
  m.bodies.push_back(test::make_body("b", 1.0, {1, 1, 1}));
  return m;
}

// One second of free fall in 200 steps: 201 snapshots.
void run_free_fall(AsyncSink& sink) {
  MultibodySystem sys(falling_body());
  RunOptions o;
  o.t_end = 1.0;
  o.step = 0.005;
  run_simulation(sys, o, &sink);
}

}  // namespace

TEST_CASE("asynchronous sink keeps every snapshot in order and waits only when full", "[runtime]") {
  auto inner = std::make_unique<SlowSink>();
  SlowSink* seen = inner.get();
  AsyncSink sink(std::move(inner), 1);  // room for 1 snapshot only
  seen->owner = &sink;
  run_free_fall(sink);
  REQUIRE(seen->times.size() == 201);
  for (std::size_t i = 0; i < seen->times.size(); ++i) CHECK(seen->times[i] == Approx(0.005 * static_cast<double>(i)));
  CHECK(seen->ended);
  CHECK(sink.stats().snapshots == 201);
  CHECK(sink.stats().waits > 0);  // the slow writer held the run back
}

TEST_CASE("an error in the writer thread ends the run with that error", "[runtime]") {
  auto inner = std::make_unique<SlowSink>();
  inner->fail_at = 10;
  SlowSink* seen = inner.get();
  AsyncSink sink(std::move(inner), 1);
  CHECK_THROWS_WITH(run_free_fall(sink), "disk full");
  CHECK(seen->times.size() == 10);
  CHECK(seen->ended);  // closed all the same
}

namespace {
// A disk slower than the run: every write takes 100 ms.
struct CrawlingSink : test::MemorySink {
  std::atomic<int> written{0};  // what other threads may read while it writes
  void write(Snapshot&& s) override {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    test::MemorySink::write(std::move(s));
    ++written;
  }
};
}  // namespace

TEST_CASE("a stopped run with output outrunning the disk drops what is queued and says how much", "[runtime]") {
  auto inner = std::make_unique<CrawlingSink>();
  CrawlingSink* seen = inner.get();
  AsyncSink sink(std::move(inner), std::size_t{1} << 20);  // room for every snapshot of the run
  std::atomic<bool> stop{false};
  sink.set_stop(&stop);
  MultibodySystem sys(falling_body());
  RunOptions o;
  o.t_end = 1.0;
  o.step = 0.005;
  o.stop = &stop;
  std::thread stopper([&] {  // once the run has queued snapshots faster than they are written
    while (sink.waits() == 0 && seen->written == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    stop = true;
  });
  // The 201 snapshots are queued at once: without a stop the writer would need 20 s.
  std::string message;
  const auto start = std::chrono::steady_clock::now();
  try {
    run_simulation(sys, o, &sink);
  } catch (const RunError& e) {
    message = e.what();
  }
  stopper.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const SinkLoss loss = sink.loss();
  INFO(message);
  // The run may have finished computing before the stop came; it still ends interrupted.
  CHECK(loss.dropped > 0);
  CHECK_THAT(message, Catch::Contains(std::to_string(loss.dropped) + " snapshots not yet written were dropped to stop in time"));
  CHECK(loss.dropped + static_cast<long>(seen->times.size()) == 201);
  CHECK(seen->ended);
  CHECK(loss.t_last_kept == seen->times.back());
  CHECK(seconds < 10.0);  // 20 s if it had written them all
}

TEST_CASE("a checkpoint through an asynchronous sink finds every snapshot before it written and synced", "[runtime][checkpoint]") {
  // A slow inner sink that records, at each sync, how many snapshots it had: sync() must
  // wait for the queue to be written first.
  struct CountingSink : test::MemorySink {
    std::vector<std::size_t> at_sync;
    void write(Snapshot&& s) override {
      std::this_thread::sleep_for(std::chrono::microseconds(200));
      test::MemorySink::write(std::move(s));
    }
    void sync() override { at_sync.push_back(times.size()); }
  };
  auto inner = std::make_unique<CountingSink>();
  CountingSink* seen = inner.get();
  AsyncSink sink(std::move(inner));
  std::vector<long> counted;  // snapshots the run had handed over at each checkpoint
  Checkpointing c;
  c.every_s = 1e-12;
  MultibodySystem sys(falling_body());
  RunOptions o;
  o.t_end = 1.0;
  o.step = 0.005;
  o.checkpoint = &c;
  c.write = [&](std::vector<std::uint8_t>&& state) {
    StateReader in(state, "state");
    in.expect("simulation");
    in.text();  // the method; then the snapshots written (sink_runner.hpp: checkpoint_head)
    counted.push_back(static_cast<long>(in.integer()));
  };
  run_simulation(sys, o, &sink);
  REQUIRE(counted.size() == 199);  // after every step but the last
  REQUIRE(seen->at_sync.size() == counted.size());
  for (std::size_t i = 0; i < counted.size(); ++i) CHECK(static_cast<long>(seen->at_sync[i]) == counted[i]);
}

TEST_CASE("with room for one snapshot a run may gather the next only once the writer is done with the last", "[runtime]") {
  // The writer holds its first snapshot until released.
  struct HeldSink : test::MemorySink {
    std::atomic<bool> release{false};
    void write(Snapshot&& s) override {
      while (!release) std::this_thread::sleep_for(std::chrono::milliseconds(1));
      test::MemorySink::write(std::move(s));
    }
  };
  auto inner = std::make_unique<HeldSink>();
  HeldSink* seen = inner.get();
  AsyncSink sink(std::move(inner), 1);  // room for one: queued or being written
  MultibodySystem sys(falling_body());
  sink.begin(sys);
  sink.make_room();  // nothing in flight: returns at once
  CHECK(sink.waits() == 0);
  Snapshot s;
  s.state = sys.initial_state();
  sink.write(std::move(s));
  std::atomic<bool> returned{false};
  std::thread run([&] {
    sink.make_room();
    returned = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  CHECK_FALSE(returned);  // the writer still holds the first
  seen->release = true;
  run.join();
  CHECK(returned);
  CHECK(sink.waits() == 1);
  sink.end();
  CHECK(seen->times.size() == 1);
}

TEST_CASE("the writer thread projects dense output onto the rigid joints as the run's thread would, bit for bit", "[runtime][rigid]") {
  // A double pendulum of rigid rods (a spherical pivot, a revolute elbow) through DOPRI5
  // with an output grid: every snapshot but the first lies between steps.
  Model m;
  m.gravity = {0, -9.81, 0};
  m.bodies.push_back(test::make_body("upper", 1.0, {1e-3, 1.0 / 12, 1.0 / 12, 0, 0, 0}, {0.5, 0, 0}));
  m.bodies.push_back(test::make_body("lower", 1.0, {1e-3, 1.0 / 12, 1.0 / 12, 0, 0, 0}, {1.5, 0, 0}));
  m.bodies[1].velocity = {0, 0, 0.3};
  m.joints.push_back(test::make_joint(JointType::spherical, ground, 0, {0, 0, 0}, {-0.5, 0, 0}));
  m.joints.push_back(test::make_joint(JointType::revolute, 0, 1, {0.5, 0, 0}, {-0.5, 0, 0}));
  for (Joint& j : m.joints) j.frame2 = rest_frame2(m, j);
  RunOptions o;
  o.method = Method::dopri5;
  o.t_end = 0.5;
  o.rtol = o.atol = 1e-4;
  o.output_interval = 0.01;
  auto run_into = [&](ResultSink& sink) {
    MultibodySystem sys(m);
    run_simulation(sys, o, &sink);
  };
  test::MemorySink direct;  // projects nothing itself: the run projects
  REQUIRE_FALSE(direct.content().projects);
  run_into(direct);
  auto inner = std::make_unique<test::MemorySink>();
  test::MemorySink* seen = inner.get();
  AsyncSink async(std::move(inner));
  REQUIRE(async.content().projects);
  run_into(async);
  REQUIRE(direct.times.size() == 51);
  CHECK(test::same_snapshots(direct, *seen));
  MultibodySystem sys(m);
  for (std::size_t k = 0; k < seen->states.size(); ++k) {
    CHECK_FALSE(seen->snapshots[k].unprojected);
    CHECK(sys.constraint_violation(seen->times[k], seen->states[k]) < 1e-9);
  }
}
