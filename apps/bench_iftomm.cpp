// mbsflow bench iftomm: the IFToMM benchmark problems of examples/models, each run as its
// model file says (method, tolerance) on one thread; the error of the benchmark's named
// coordinate against the mechanism's reduced equations in generalised coordinates
// (runtime/src/iftomm_reference.cpp), the drift of a conserved quantity and the wall time,
// beside what published entries of other codes report (docs/joints.md gives the sources).
#include <algorithm>
#include <cstdio>

#include "bench.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/runtime/iftomm_reference.hpp"
#include "mbsflow/runtime/simulation.hpp"

namespace mbsflow::cli {

int bench_iftomm(const BenchArgs& a) {
  BenchCsv csv = open_csv(a);
  csv.out << "problem,method,rtol,steps,error_m,drift,drift_of,wall_s\n";
  std::printf("%-28s %-7s %-8s %8s %11s %11s %-20s %8s   %s\n", "problem", "method", "rtol", "steps", "error m", "drift",
              "of", "wall s", "published");
  for (const IftommInfo& p : iftomm_problems()) {
    const Model m = read_model_file(examples_dir(a) + "/" + p.file);
    double best = 1e300;
    KeptStates keep;
    RunSummary summary;
    for (int r = 0; r < a.repeats; ++r) {
      MultibodySystem sys(m);
      keep = KeptStates{};
      const auto start = BenchClock::now();
      summary = run_simulation(sys, options_from_model(m), &keep);
      best = std::min(best, seconds_since(start));
    }
    MultibodySystem sys(m);
    const IftommCheck c = check_iftomm(p.id, sys, keep.t, keep.y);
    std::printf("%-28s %-7s %-8.2g %8ld %11.3g %11.3g %-20s %8.3f   %s\n", p.title, method_name(m.simulation.method.value_or(Method::rk4)),
                m.simulation.rtol, summary.steps, c.error, c.drift, p.drift_of, best, p.published);
    csv.out << '"' << p.title << "\"," << method_name(m.simulation.method.value_or(Method::rk4)) << ',' << m.simulation.rtol << ','
            << summary.steps << ',' << c.error << ',' << c.drift << ",\"" << p.drift_of << "\"," << best << '\n';
  }
  std::printf("wrote %s\n", csv.path.c_str());
  return 0;
}

}  // namespace mbsflow::cli
