#include "mbsflow/io/partition_file.hpp"
#include "mbsflow/runtime/run_request.hpp"

#include <algorithm>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "json_node.hpp"
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
  const std::string text = read_input_file(path, "partition file", std::size_t{256} << 20);
  const nlohmann::json j = parse_json_document(text, path);
  const JsonSource src{path, JsonLocations(text)};
  const JsonNode root(j, "", src);
  root.expect_object();
  const std::string name = root["model"].string();
  const long bodies = root["bodies"].integer(0);
  const long k = root["partitions"].integer(1, std::max<long>(1, static_cast<long>(model.bodies.size())));
  if (name != model.name || bodies != static_cast<long>(model.bodies.size()))
    throw InputError(path + ": the partition is for model '" + name + "' with " + std::to_string(bodies) +
                     " bodies, not for '" + model.name + "' with " + std::to_string(model.bodies.size()));
  const JsonNode list = root["part_of_body"];
  std::vector<int> part(list.array_size());
  for (std::size_t i = 0; i < part.size(); ++i) part[i] = static_cast<int>(list.item(i).integer(0, k - 1));
  try {
    return decompose(model, part, static_cast<int>(k));
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
}

std::optional<Decomposition> cut_of_request(const Model& m, const RunRequest& r, int default_k, bool plain_if_one) {
  if (!r.partition_file.empty()) return read_partition_file(m, r.partition_file);
  return cut_for_run(m, r.partitions, default_k, partitioner_named(r.partitioner), plain_if_one);
}

}  // namespace mbsflow
