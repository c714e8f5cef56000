#include "mbsflow/io/partition_file.hpp"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "mbsflow/error.hpp"

namespace mbsflow {

void write_partition_file(const Model& model, const Decomposition& d, const std::string& path) {
  const nlohmann::ordered_json j = {{"model", model.name},
                                    {"bodies", model.bodies.size()},
                                    {"partitions", d.submodels.size()},
                                    {"part_of_body", d.part_of_body}};
  std::ofstream out(path);
  if (!out) throw InputError(path + ": cannot write the partition file");
  out << j.dump() << '\n';
}

Decomposition read_partition_file(const Model& model, const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open the partition file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not a partition file (" + std::string(e.what()) + ")");
  }
  try {
    const std::string name = j.at("model").get<std::string>();
    const auto bodies = j.at("bodies").get<std::size_t>();
    const int k = j.at("partitions").get<int>();
    const auto part = j.at("part_of_body").get<std::vector<int>>();
    if (name != model.name || bodies != model.bodies.size())
      throw InputError(path + ": the partition is for model '" + name + "' with " + std::to_string(bodies) +
                       " bodies, not for '" + model.name + "' with " + std::to_string(model.bodies.size()));
    try {
      return decompose(model, part, k);
    } catch (const InputError& e) {
      throw InputError(path + ": " + e.what());
    }
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": not a partition file (" + std::string(e.what()) + ")");
  }
}

}  // namespace mbsflow
