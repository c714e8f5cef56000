// mbsflow partition MODEL.json -k K [--dot FILE] [-o FILE]: how a model is cut.
#include <cstdio>
#include <fstream>
#include <memory>

#include "commands.hpp"
#include "mbsflow/graph/decomposition.hpp"
#include "mbsflow/error.hpp"
#include "mbsflow/io/model_reader.hpp"
#include "mbsflow/io/partition_file.hpp"

namespace mbsflow::cli {
namespace {

struct PartitionArgs {
  std::string model, dot, output;
  int k = 2;
  std::string partitioner = "best";
};

// Bytes a submodel receives per stage: 13 doubles per ghost body.
std::size_t stage_bytes(const Submodel& s) { return s.ghosts.size() * 13 * sizeof(double); }

int partition(const PartitionArgs& a) {
  const Model m = read_model_file(a.model);
  const Decomposition d = decompose(m, a.k, partitioner_named(a.partitioner));
  std::printf("model %s: %zu bodies, %zu joints, %d submodels by %s\n", m.name.c_str(), m.bodies.size(), m.joints.size(),
              a.k, d.partitioner == Partitioner::metis ? "METIS k-way" : "band cuts of the reverse Cuthill-McKee order");
  std::printf("%9s %8s %8s %8s %10s %11s %10s %12s\n", "submodel", "bodies", "joints", "ghosts", "cut joints", "neighbours",
              "cost", "bytes/stage");
  std::size_t bytes = 0;
  for (std::size_t p = 0; p < d.submodels.size(); ++p) {
    const Submodel& s = d.submodels[p];
    std::printf("%9zu %8zu %8zu %8zu %10d %11zu %10.0f %12zu\n", p, s.own.size(), s.joints.size(), s.ghosts.size(),
                s.cut_joints, s.exchanges.size(), s.cost, stage_bytes(s));
    bytes += stage_bytes(s);
  }
  std::printf("cut joints %d, bytes exchanged per stage %zu, load imbalance %.2f %% (max cost / mean cost - 1), "
              "slowest submodel ~%.0f us per stage\n",
              d.cut_joints, bytes, 100.0 * d.imbalance, d.estimated_time() / 1000.0);
  if (!a.dot.empty()) {
    std::ofstream out(a.dot);
    if (!out) throw InputError("--dot: cannot write " + a.dot);
    out << decomposition_dot(m, d);
    std::fprintf(stderr, "mbsflow: wrote %s (render with: dot -Tsvg %s -o graph.svg)\n", a.dot.c_str(), a.dot.c_str());
  }
  if (!a.output.empty()) {
    write_partition_file(m, d, a.output);
    std::fprintf(stderr, "mbsflow: wrote %s (use with: mbsflow run %s --partition-file %s)\n", a.output.c_str(),
                 a.model.c_str(), a.output.c_str());
  }
  return 0;
}

}  // namespace

Action add_partition(CLI::App& app) {
  auto a = std::make_shared<PartitionArgs>();
  CLI::App* sub = app.add_subcommand("partition", "Cut a model into submodels and report balance, cut joints and exchange");
  sub->add_option("model", a->model, "Model file (JSON)")->required();
  sub->add_option("-k,--partitions", a->k, "Number of submodels")->required();
  sub->add_option("--partitioner", a->partitioner,
                  "best: whichever of band and metis gives the faster slowest submodel; band: band cuts of the reverse Cuthill-McKee order; "
                  "metis: METIS k-way")
      ->check(CLI::IsMember({"best", "band", "metis"}))
      ->capture_default_str();
  sub->add_option("--dot", a->dot, "Write the partitioned body/joint graph as Graphviz dot");
  sub->add_option("-o,--output", a->output, "Write the assignment as a partition file for mbsflow run --partition-file");
  return [a] { return partition(*a); };
}

}  // namespace mbsflow::cli
