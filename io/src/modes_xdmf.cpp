#include "modes_xdmf.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>
#include <sstream>
#include <vector>

#include "hdf5_handle.hpp"
#include "xdmf_writer.hpp"
#include "mbsflow/io/mode_frames.hpp"

namespace mbsflow {
namespace {

void make_group(hid_t file, const std::string& path) {
  h5::Handle(H5Gcreate2(file, path.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create " + path);
}

}  // namespace

ModesXdmf write_mode_frames(hid_t file, const LinearModel& lm, const Modes& modes, const std::vector<double>& shape_re,
                            const std::vector<double>& shape_im, const std::string& h5_name) {
  const Model& model = *lm.model;
  const auto n = static_cast<Eigen::Index>(model.bodies.size());
  const StateLayout l{n};
  const auto k = static_cast<Eigen::Index>(modes.frequency.size());
  ModesXdmf out;
  const std::size_t per_frame = static_cast<std::size_t>(n) * 7 * sizeof(double);
  const std::size_t fit = per_frame * static_cast<std::size_t>(std::max<Eigen::Index>(k, 1)) > 0
                              ? modes_xdmf_frame_limit_bytes / (per_frame * static_cast<std::size_t>(std::max<Eigen::Index>(k, 1)))
                              : 0;
  out.frames = static_cast<int>(std::min<std::size_t>(modes_xdmf_frames, fit));
  if (out.frames < 4) out.frames = 0;

  std::vector<int> index(static_cast<std::size_t>(n));
  for (Eigen::Index b = 0; b < n; ++b) index[static_cast<std::size_t>(b)] = static_cast<int>(b);
  make_group(file, "/xdmf");
  h5::write_array(file, "/xdmf/body_index", H5T_NATIVE_INT, index, {static_cast<hsize_t>(n)});
  std::vector<double> rest(static_cast<std::size_t>(3 * n)), rest_q(static_cast<std::size_t>(4 * n));
  for (Eigen::Index b = 0; b < n; ++b) {
    for (int i = 0; i < 3; ++i) rest[static_cast<std::size_t>(3 * b + i)] = lm.state[l.position(b) + i];
    for (int i = 0; i < 4; ++i) rest_q[static_cast<std::size_t>(4 * b + i)] = lm.state[l.orientation(b) + i];
  }
  const double size = model_size(rest);
  out.amplitude = 0.05 * size;
  h5::write_array(file, "/xdmf/equilibrium_position", H5T_NATIVE_DOUBLE, rest, {static_cast<hsize_t>(n), 3});
  h5::write_array(file, "/xdmf/equilibrium_orientation", H5T_NATIVE_DOUBLE, rest_q, {static_cast<hsize_t>(n), 4});

  std::ostringstream o;
  o.precision(17);
  o << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"modes\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  const std::string n1 = std::to_string(n) + " 1", n3 = std::to_string(n) + " 3", n4 = std::to_string(n) + " 4";
  std::vector<int> slot_of(static_cast<std::size_t>(n), -1);  // body -> its index among the free bodies
  for (std::size_t s = 0; s < lm.coords.bodies.size(); ++s) slot_of[static_cast<std::size_t>(lm.coords.bodies[s])] = static_cast<int>(s);
  for (Eigen::Index j = 0; j < k; ++j) {
    const std::string group = "/xdmf/mode" + std::to_string(j + 1);
    make_group(file, group);
    const auto shape_of = [&](std::size_t b, int e) {
      const std::size_t at = (static_cast<std::size_t>(j * n) + b) * 6 + static_cast<std::size_t>(e);
      return std::complex<double>(shape_re[at], shape_im[at]);
    };
    const double scale = mode_scale(shape_of, static_cast<std::size_t>(n), size);
    std::vector<double> shape(static_cast<std::size_t>(3 * n), 0.0), share(static_cast<std::size_t>(n), 0.0);
    for (Eigen::Index b = 0; b < n; ++b) {
      for (int i = 0; i < 3; ++i) shape[static_cast<std::size_t>(3 * b + i)] = scale * shape_of(static_cast<std::size_t>(b), i).real();
      if (const int s = slot_of[static_cast<std::size_t>(b)]; s >= 0) share[static_cast<std::size_t>(b)] = modes.kinetic_share(s, j);
    }
    h5::write_array(file, (group + "/shape").c_str(), H5T_NATIVE_DOUBLE, shape, {static_cast<hsize_t>(n), 3});
    h5::write_array(file, (group + "/kinetic_share").c_str(), H5T_NATIVE_DOUBLE, share, {static_cast<hsize_t>(n)});
    h5::write_array(file, (group + "/mode").c_str(), H5T_NATIVE_DOUBLE, std::vector<double>{double(j + 1), modes.frequency[static_cast<std::size_t>(j)]}, {2});
    const int frames = std::max(out.frames, 1);
    for (int f = 0; f < frames; ++f) {
      const double phase = 2.0 * std::numbers::pi * f / frames;
      std::vector<double> position = rest, orientation = rest_q;
      const std::string frame = group + '/' + std::to_string(f);
      if (out.frames > 0) {
        for (Eigen::Index b = 0; b < n; ++b) {
          const auto i = static_cast<std::size_t>(b);
          mode_frame_body(shape_of, i, scale, phase, &rest[3 * i], &rest_q[4 * i], &position[3 * i], &orientation[4 * i]);
        }
        make_group(file, frame);
        h5::write_array(file, (frame + "/position").c_str(), H5T_NATIVE_DOUBLE, position, {static_cast<hsize_t>(n), 3});
        h5::write_array(file, (frame + "/orientation").c_str(), H5T_NATIVE_DOUBLE, orientation, {static_cast<hsize_t>(n), 4});
      }
      const std::string at = out.frames > 0 ? frame : "/xdmf/equilibrium";
      o << "   <Grid Name=\"mode" << j + 1 << "_" << f << "\" GridType=\"Uniform\">\n    <Time Value=\""
        << double(j + 1) + double(f) / frames << "\"/>\n"
        << "     <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n << "\" NodesPerElement=\"1\">\n";
      xdmf_item(o, h5_name, "/xdmf/body_index", n1, true, "      ");
      o << "     </Topology>\n     <Geometry GeometryType=\"XYZ\">\n";
      xdmf_item(o, h5_name, at + (out.frames > 0 ? "/position" : "_position"), n3, false, "      ");
      o << "     </Geometry>\n";
      xdmf_attribute(o, h5_name, "orientation", "Matrix", "Node", at + (out.frames > 0 ? "/orientation" : "_orientation"), n4);
      xdmf_attribute(o, h5_name, "shape", "Vector", "Node", group + "/shape", n3);
      xdmf_attribute(o, h5_name, "kinetic_share", "Scalar", "Node", group + "/kinetic_share", std::to_string(n));
      xdmf_attribute(o, h5_name, "body_index", "Scalar", "Node", "/xdmf/body_index", std::to_string(n), true);
      xdmf_attribute(o, h5_name, "mode_frequency_hz", "Vector", "Grid", group + "/mode", "1 2");
      o << "   </Grid>\n";
    }
  }
  o << "  </Grid>\n </Domain>\n</Xdmf>\n";
  out.text = o.str();
  return out;
}

}  // namespace mbsflow
