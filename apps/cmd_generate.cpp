// mbsflow generate chain|grid|train: benchmark and example models of any size.
#include <cstdio>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "mbsflow/graph/generators.hpp"
#include "mbsflow/io/model_writer.hpp"
#include "mbsflow/io/output_path.hpp"
#include "mbsflow/words.hpp"

namespace mbsflow::cli {
namespace {

struct GenerateArgs {
  std::string kind;
  int bodies = 100, rows = 10, cols = 10, wagons = 3, cycles = 10;
  unsigned seed = 1;
  std::optional<double> t_end, step;
  std::string output;
};

int generate(const GenerateArgs& a) {
  Model m;
  if (a.kind == "chain") {
    ChainParams p;
    p.bodies = a.bodies;
    m = make_chain(p);
  } else if (a.kind == "grid") {
    GridParams p;
    p.rows = a.rows;
    p.cols = a.cols;
    m = make_grid(p);
  } else if (a.kind == "train") {
    TrainParams p;
    p.wagons = a.wagons;
    m = make_train(p);
  } else {
    RandomTreeParams p;
    p.bodies = a.bodies;
    p.cycles = a.cycles;
    p.seed = a.seed;
    m = make_random_tree(p);
  }
  if (a.t_end) m.simulation.t_end = *a.t_end;
  if (a.step) m.simulation.step = *a.step;
  const std::string path = a.output.empty() ? a.kind + ".json" : a.output;
  check_output_path(path, {{}, true});  // a model replaces a file, never a folder or a device
  write_model_file(m, path);
  std::fprintf(stderr, "mbsflow: wrote %s: model %s, %s, %s, %s\n", path.c_str(), m.name.c_str(),
               count_of(static_cast<long long>(m.bodies.size()), "body", "bodies").c_str(),
               count_of(static_cast<long long>(m.joints.size()), "joint").c_str(),
               count_of(static_cast<long long>(m.drivers.size()), "driver").c_str());
  return 0;
}

}  // namespace

Action add_generate(CLI::App& app) {
  auto a = std::make_shared<GenerateArgs>();
  CLI::App* sub = app.add_subcommand("generate", "Write a benchmark model: chain, grid, train or random");
  sub->add_option("kind", a->kind,
                  "chain: hanging chain of N links; grid: R x C plate; train: W wagons on a rough track; "
                  "random: a random tree of N bodies with extra joints closing cycles")
      ->required()
      ->check(CLI::IsMember({"chain", "grid", "train", "random"}));
  sub->add_option("--bodies", a->bodies, "chain, random: number of bodies")->check(CLI::Range(1, 100000000));
  sub->add_option("--cycles", a->cycles, "random: extra joints closing cycles")->check(CLI::Range(0, 100000000));
  sub->add_option("--seed", a->seed, "random: seed");
  sub->add_option("--rows", a->rows, "grid: rows")->check(CLI::Range(1, 100000));
  sub->add_option("--cols", a->cols, "grid: columns")->check(CLI::Range(1, 100000));
  sub->add_option("--wagons", a->wagons, "train: wagons (7 bodies each)")->check(CLI::Range(1, 10000000));
  sub->add_option("--t-end", a->t_end, "simulation.t_end of the model")->check(CLI::PositiveNumber);
  sub->add_option("--step", a->step, "simulation.step of the model")->check(CLI::PositiveNumber);
  sub->add_option("-o,--output", a->output, "Model file to write (default: KIND.json)");
  return [a] { return generate(*a); };
}

}  // namespace mbsflow::cli
