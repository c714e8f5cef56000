// mbsflow bench output: what writing results costs. The same run of a 6500-body chain
// without output, with a snapshot every 10 steps and every step, to HDF5 through the
// asynchronous writer; and a plain sequential write of the same bytes for reference.
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <vector>

#include "bench.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/hdf5_sink.hpp"
#include "mbsflow/runtime/async_sink.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow::cli {
namespace {

struct Case {
  int every = 0;  // 0: no output
  double wall = std::numeric_limits<double>::infinity();
  double bytes = 0.0, writer_seconds = 0.0;
  long snapshots = 0, waits = 0;
};

// Writes `bytes` in 1 MiB blocks to a file in dir, then fdatasync; returns MB/s
// (what `dd bs=1M conv=fdatasync` measures).
double raw_write_rate(const std::string& dir, double bytes) {
  const std::string path = (std::filesystem::path(dir) / "mbsflow_bench_raw.bin").string();
  const std::vector<char> block(std::size_t{1} << 20, 'x');
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw InputError("--dir: cannot write " + path);
  const auto start = BenchClock::now();
  for (double done = 0; done < bytes; done += static_cast<double>(block.size()))
    if (::write(fd, block.data(), block.size()) < 0) break;
  ::fdatasync(fd);
  const double s = seconds_since(start);
  ::close(fd);
  std::filesystem::remove(path);
  return bytes / s / 1e6;
}

}  // namespace

int bench_output(const BenchArgs& a) {
  const int n = a.bodies.empty() ? 6500 : a.bodies.front();
  ChainParams p;
  p.bodies = n;
  const Model m = make_chain(p);
  RunOptions o = options_from_model(m);
  o.t_end = o.t_start + o.step * a.steps;
  const std::string file = (std::filesystem::path(a.dir) / "mbsflow_bench_output.h5").string();
  std::vector<Case> cases{{0}, {10}, {1}};
  for (int r = 0; r < a.repeats; ++r) {
    for (Case& c : cases) {  // interleaved, so that drift of the machine hits every case alike
      MultibodySystem sys(m);
      RunOptions run = o;
      run.output_every = std::max(1, c.every);
      std::unique_ptr<AsyncSink> sink;
      if (c.every > 0) {
        RunInfo info{"{}", method_name(run.method), run.step, run.t_start, run.t_end, run.output_every, "mbsflow bench output"};
        sink = std::make_unique<AsyncSink>(std::make_unique<Hdf5Sink>(file, FieldSet{}, info));
      }
      const auto start = BenchClock::now();
      const RunSummary s = run_simulation(sys, run, sink.get());
      const double wall = seconds_since(start);
      if (wall < c.wall) {
        c.wall = wall;
        c.snapshots = sink ? s.snapshots : 0;
        c.bytes = sink ? static_cast<double>(std::filesystem::file_size(file)) : 0.0;
        c.writer_seconds = sink ? sink->stats().writer_seconds : 0.0;
        c.waits = sink ? sink->stats().waits : 0;
      }
    }
  }
  std::filesystem::remove(file);
  std::filesystem::remove(xdmf_path(file));
  const double raw = raw_write_rate(a.dir, std::max(cases[2].bytes, 64e6));
  auto [csv_path, csv] = open_csv(a);
  csv << "bodies,steps,output_every,snapshots,wall_s,slowdown_percent,bytes,writer_MB_per_s,run_MB_per_s,waits,raw_write_MB_per_s\n";
  std::printf("output cost: %d-body chain, %d RK4 steps, HDF5 through the asynchronous writer (fastest of %d runs)\n", n,
              a.steps, a.repeats);
  std::printf("%-14s %9s %9s %10s %10s %12s %12s %7s\n", "output", "snapshots", "wall s", "slowdown", "MB", "writer MB/s",
              "run MB/s", "waits");
  for (const Case& c : cases) {
    const double slowdown = 100.0 * (c.wall / cases[0].wall - 1.0);
    const double writer_rate = c.writer_seconds > 0 ? c.bytes / c.writer_seconds / 1e6 : 0.0;
    const double run_rate = c.bytes / c.wall / 1e6;
    const std::string label = c.every == 0 ? "none" : "every " + std::to_string(c.every);
    std::printf("%-14s %9ld %9.3f %9.1f%% %10.1f %12.1f %12.1f %7ld\n", label.c_str(), c.snapshots, c.wall,
                c.every ? slowdown : 0.0, c.bytes / 1e6, writer_rate, run_rate, c.waits);
    csv << n << ',' << a.steps << ',' << c.every << ',' << c.snapshots << ',' << c.wall << ',' << (c.every ? slowdown : 0.0)
        << ',' << c.bytes << ',' << writer_rate << ',' << run_rate << ',' << c.waits << ',' << raw << '\n';
  }
  std::printf("plain sequential write of the same size to %s (1 MiB blocks + fdatasync, like dd): %.1f MB/s\n",
              a.dir.c_str(), raw);
  std::printf("written to %s\n", csv_path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
