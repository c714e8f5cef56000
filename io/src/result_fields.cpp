#include "mbsflow/io/result_fields.hpp"

#include <sstream>

#include "mbsflow/error.hpp"

namespace mbsflow {

FieldSet parse_fields(const std::string& list) {
  FieldSet f;
  f.body.fill(false);
  f.energy = false;
  std::stringstream in(list);
  std::string name;
  bool any = false;
  while (std::getline(in, name, ',')) {
    if (name.empty()) continue;
    any = true;
    bool known = false;
    for (std::size_t i = 0; i < body_fields.size(); ++i)
      if (name == body_fields[i].name || name == "all") f.body[i] = known = true;
    if (name == "energy" || name == "all") f.energy = known = true;
    if (name == "joint_force" || name == "all") f.joint_force = known = true;
    if (!known)
      throw InputError("{fields}: unknown field '" + name +
                       "' (expected position, orientation, velocity, angular_velocity, energy, joint_force or all)");
  }
  if (!any) throw InputError("{fields}: name at least one field");
  return f;
}

std::string fields_text(const FieldSet& f) {
  std::string s;
  auto add = [&](const char* n) { s += (s.empty() ? "" : ",") + std::string(n); };
  for (std::size_t i = 0; i < body_fields.size(); ++i)
    if (f.body[i]) add(body_fields[i].name);
  if (f.energy) add("energy");
  if (f.joint_force) add("joint_force");
  return s;
}

std::vector<std::size_t> evenly_spread_rows(std::size_t rows, std::size_t most) {
  if (rows == 0) return {};
  if (most <= 1) return {rows - 1};
  const std::size_t stride = rows <= most ? 1 : (rows - 1 + most - 2) / (most - 1);
  std::vector<std::size_t> out;
  for (std::size_t r = 0; r < rows; r += stride) out.push_back(r);
  if (out.back() != rows - 1) out.push_back(rows - 1);
  return out;
}

}  // namespace mbsflow
