#include "mbsflow/io/modes_file.hpp"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "hdf5_handle.hpp"
#include "mbsflow/io/hdf5_sink.hpp"
#include "modes_xdmf.hpp"
#include "part_file.hpp"
#include "mbsflow/version.hpp"

namespace mbsflow {
namespace {


ModesXdmf write_file(const std::string& path, const std::string& h5_name, const LinearModel& lm, const Modes& modes,
                     const ModesFileInfo& info) {
  const Model& model = *lm.model;
  const h5::Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, "create " + path);
  const hid_t root = file.get();
  h5::write_string_attribute(root, "mbsflow_version", MBSFLOW_VERSION);
  h5::write_string_attribute(root, "command_line", info.command_line);
  h5::write_string_attribute(root, "linearised_at", info.linearised_at);
  h5::write_string_attribute(root, "solver", modes.solver);
  h5::write_string_attribute(root, "model_name", model.name);
  h5::write_number_attribute(root, "free_coordinates", static_cast<double>(modes.free_coordinates));
  h5::write_text_dataset(root, "model", info.model_json);
  const auto k = static_cast<hsize_t>(modes.frequency.size());
  const auto n = static_cast<hsize_t>(model.bodies.size());
  for (const char* g : {"/modes", "/bodies", "/equilibrium"})
    h5::Handle(H5Gcreate2(root, g, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, std::string("create ") + g);
  std::vector<double> eigenvalue, rigid;
  for (std::size_t j = 0; j < k; ++j) {
    eigenvalue.insert(eigenvalue.end(), {modes.eigenvalue[j].real(), modes.eigenvalue[j].imag()});
    rigid.push_back(modes.rigid_body[j] ? 1.0 : 0.0);
  }
  // Shapes over every body of the model (driven ones zero, a flexible body's nodes moved by
  // its frame and modes); energy shares of the free bodies (a flexible body's with its
  // frame, its modes' included).
  std::vector<double> re(k * n * 6, 0.0), im(k * n * 6, 0.0), share(k * n * 2, 0.0);
  const Eigen::SparseMatrix<double> motion = body_motion(lm);
  for (std::size_t j = 0; j < k; ++j) {
    const Eigen::VectorXd r = motion * modes.shape.col(static_cast<Eigen::Index>(j)).real();
    const Eigen::VectorXd i = motion * modes.shape.col(static_cast<Eigen::Index>(j)).imag();
    std::copy(r.data(), r.data() + 6 * n, re.begin() + static_cast<std::ptrdiff_t>(j * n * 6));
    std::copy(i.data(), i.data() + 6 * n, im.begin() + static_cast<std::ptrdiff_t>(j * n * 6));
    for (std::size_t b = 0; b < lm.coords.bodies.size(); ++b) {
      const auto body = static_cast<std::size_t>(lm.coords.bodies[b]);
      share[(j * n + body) * 2] = modes.kinetic_share(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(j));
      share[(j * n + body) * 2 + 1] = modes.strain_share(static_cast<Eigen::Index>(b), static_cast<Eigen::Index>(j));
    }
  }
  h5::write_array(root, "/modes/frequency", H5T_NATIVE_DOUBLE, modes.frequency, {k});
  h5::write_array(root, "/modes/damping_ratio", H5T_NATIVE_DOUBLE, modes.damping_ratio, {k});
  h5::write_array(root, "/modes/eigenvalue", H5T_NATIVE_DOUBLE, eigenvalue, {k, 2});
  h5::write_array(root, "/modes/rigid_body", H5T_NATIVE_DOUBLE, rigid, {k});
  h5::write_array(root, "/modes/residual", H5T_NATIVE_DOUBLE, modes.residual, {k});
  h5::write_array(root, "/modes/shape", H5T_NATIVE_DOUBLE, re, {k, n, 6});
  h5::write_array(root, "/modes/shape_imag", H5T_NATIVE_DOUBLE, im, {k, n, 6});
  h5::write_array(root, "/modes/energy_share", H5T_NATIVE_DOUBLE, share, {k, n, 2});
  std::vector<std::string> names;
  for (const Body& b : model.bodies) names.push_back(b.name);
  h5::write_names(root, "/bodies/names", names);
  const StateLayout l{static_cast<Eigen::Index>(n)};
  std::vector<double> position, orientation;
  for (Eigen::Index b = 0; b < l.bodies; ++b) {
    for (int i = 0; i < 3; ++i) position.push_back(lm.state[l.position(b) + i]);
    for (int i = 0; i < 4; ++i) orientation.push_back(lm.state[l.orientation(b) + i]);
  }
  h5::write_array(root, "/equilibrium/position", H5T_NATIVE_DOUBLE, position, {n, 3});
  h5::write_array(root, "/equilibrium/orientation", H5T_NATIVE_DOUBLE, orientation, {n, 4});
  h5::write_units(root, "/modes/frequency", "Hz");
  h5::write_units(root, "/modes/damping_ratio", "1");
  h5::write_units(root, "/modes/eigenvalue", "1/s");
  h5::write_units(root, "/modes/residual", "1");
  h5::write_units(root, "/modes/shape", "m, m, m, rad, rad, rad (mass-normalised: per square root of kg m^2)");
  h5::write_units(root, "/modes/shape_imag", "m, m, m, rad, rad, rad");
  h5::write_units(root, "/modes/energy_share", "1");
  h5::write_units(root, "/equilibrium/position", "m");
  h5::write_units(root, "/equilibrium/orientation", "1");
  return write_mode_frames(root, lm, modes, re, im, h5_name);
}

}  // namespace

ModesFileWritten write_modes_file(const std::string& path, const LinearModel& lm, const Modes& modes, const ModesFileInfo& info) {
  ModesXdmf xdmf;
  const std::string name = std::filesystem::path(path).filename().string();  // the sidecar lies beside it
  write_through_part(path, [&](const std::string& making) { xdmf = write_file(making, name, lm, modes, info); });
  ModesFileWritten out{xdmf_path(path), xdmf.frames};
  // Written after the modes file is complete, so that it never names a file being made.
  write_through_part(out.xdmf, [&](const std::string& making) {
    std::ofstream o(making);
    o << xdmf.text;
    if (!o.flush()) throw InputError(out.xdmf + ": cannot write the XDMF sidecar");
  });
  return out;
}

}  // namespace mbsflow
