#include "mbsflow/io/ode_results.hpp"


#include "hdf5_handle.hpp"
#include "part_file.hpp"

namespace mbsflow {
namespace {

void write_vector(hid_t parent, const char* name, const std::vector<double>& v) {
  h5::write_array(parent, name, H5T_NATIVE_DOUBLE, v, {v.size()});
}

void write_file(const std::string& path, const OdeResults& r) {
  const h5::Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, "create " + path);
  const hid_t root = file.get();
  for (const auto& [k, v] : r.texts) h5::write_string_attribute(root, k.c_str(), v);
  for (const auto& [k, v] : r.numbers) h5::write_number_attribute(root, k.c_str(), v);

  const h5::Handle solution(H5Gcreate2(root, "solution", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
                            "create /solution");
  write_vector(solution.get(), "time", r.time);
  h5::write_array(solution.get(), "components", H5T_NATIVE_LONG, r.components, {r.components.size()});
  h5::write_array(solution.get(), "values", H5T_NATIVE_DOUBLE, r.values, {r.time.size(), r.components.size()});
  if (!r.error.empty()) write_vector(solution.get(), "error", r.error);

  const h5::Handle steps(H5Gcreate2(root, "steps", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create /steps");
  auto column = [&](const char* name, auto get) {
    std::vector<double> v;
    v.reserve(r.steps.size());
    for (const BlockStepRecord& s : r.steps) v.push_back(static_cast<double>(get(s)));
    write_vector(steps.get(), name, v);
  };
  column("t", [](const BlockStepRecord& s) { return s.t; });
  column("tau", [](const BlockStepRecord& s) { return s.tau; });
  column("taken", [](const BlockStepRecord& s) { return s.taken; });
  column("error", [](const BlockStepRecord& s) { return s.error; });
  column("iterations_s", [](const BlockStepRecord& s) { return s.iterations_s; });
  column("iterations_s1", [](const BlockStepRecord& s) { return s.iterations_s1; });
  column("iteration_failed", [](const BlockStepRecord& s) { return s.iteration_failed ? 1 : 0; });
}
}  // namespace

void write_ode_results(const std::string& path, const OdeResults& r) {
  write_through_part(path, [&](const std::string& making) { write_file(making, r); });
}

}  // namespace mbsflow
