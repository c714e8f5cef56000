#include "mbsflow/io/reduced_part_file.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "hdf5_handle.hpp"
#include "mbsflow/io/hdf5_sink.hpp"
#include "mbsflow/version.hpp"
#include "part_file.hpp"
#include "xdmf_writer.hpp"

namespace mbsflow {
namespace {

constexpr const char* kind = "reduced finite-element part (Craig-Bampton)";

std::vector<double> row_major(const Eigen::MatrixXd& m) {
  std::vector<double> out(static_cast<std::size_t>(m.size()));
  Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(out.data(), m.rows(), m.cols()) = m;
  return out;
}


// A dataset's values (as doubles) and its shape.
std::pair<std::vector<double>, std::vector<hsize_t>> read_all(hid_t file, const std::string& path, const std::string& name) {
  if (H5Lexists(file, path.substr(0, path.find('/', 1)).c_str(), H5P_DEFAULT) <= 0 || H5Lexists(file, path.c_str(), H5P_DEFAULT) <= 0)
    throw InputError(name + ": no " + path + " (not a reduced part: mbsflow reduce writes one)");
  const h5::Handle set(H5Dopen2(file, path.c_str(), H5P_DEFAULT), H5Dclose, "open " + path);
  const h5::Handle space(H5Dget_space(set.get()), H5Sclose, "space of " + path);
  std::vector<hsize_t> dims(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space.get())));
  H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr);
  hsize_t count = 1;
  for (hsize_t d : dims) count *= d;
  std::vector<double> v(count);
  if (count > 0) h5::check(H5Dread(set.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), "read " + path);
  return {std::move(v), std::move(dims)};
}

Eigen::MatrixXd matrix(const std::pair<std::vector<double>, std::vector<hsize_t>>& a, const std::string& what) {
  if (a.second.size() != 2) throw InputError(what + " is not a matrix");
  const auto rows = static_cast<Eigen::Index>(a.second[0]), cols = static_cast<Eigen::Index>(a.second[1]);
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(a.first.data(), rows, cols);
}

// The floating frame's data (/floating, flexible_body.hpp), where the part has one.
void write_floating(hid_t root, const FloatingFrameData& f) {
  const auto ne = static_cast<hsize_t>(f.modes());
  if (ne == 0) return;
  h5::Handle(H5Gcreate2(root, "/floating", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create /floating");
  std::vector<double> a, c, e, position, shape;
  const auto append = [](std::vector<double>& to, const Eigen::MatrixXd& m) {
    const std::vector<double> values = row_major(m);
    to.insert(to.end(), values.begin(), values.end());
  };
  for (const auto& m : f.a) append(a, m);
  for (const auto& m : f.c) append(c, m);
  for (const auto& m : f.e) append(e, m);
  for (const auto& x : f.node_position) position.insert(position.end(), {x.x(), x.y(), x.z()});
  for (const auto& m : f.node_shape) append(shape, m);
  const hsize_t nodes = f.node_id.size();
  h5::write_array(root, "/floating/omega_squared", H5T_NATIVE_DOUBLE, std::vector<double>(f.omega2.data(), f.omega2.data() + ne), {ne});
  h5::write_array(root, "/floating/mass0", H5T_NATIVE_DOUBLE, row_major(f.mass0), {6 + ne, 6 + ne});
  h5::write_array(root, "/floating/a", H5T_NATIVE_DOUBLE, a, {ne, 3, 6});
  h5::write_array(root, "/floating/c", H5T_NATIVE_DOUBLE, c, {ne, ne, 3, 3});
  h5::write_array(root, "/floating/e", H5T_NATIVE_DOUBLE, e, {ne, 3, ne});
  h5::write_array(root, "/floating/node_id", H5T_NATIVE_LONG, f.node_id, {nodes});
  h5::write_array(root, "/floating/node_position", H5T_NATIVE_DOUBLE, position, {nodes, 3});
  h5::write_array(root, "/floating/node_shape", H5T_NATIVE_DOUBLE, shape, {nodes, 6, ne});
  h5::write_units(root, "/floating/omega_squared", "(rad/s)^2: the free part's elastic modes");
  h5::write_units(root, "/floating/node_position", "m, from the centre of mass");
}

// The drawn surface and its displacement per elastic mode (FloatingFrameData::display_*).
void read_display(hid_t file, const std::string& path, FloatingFrameData& f) {
  const auto position = read_all(file, "/display/position", path).first;
  const auto shape = read_all(file, "/floating/display_shape", path).first;
  const auto triangle = read_all(file, "/display/triangle", path).first;
  const auto points = static_cast<Eigen::Index>(position.size() / 3), ne = static_cast<Eigen::Index>(f.modes());
  if (shape.size() != static_cast<std::size_t>(3 * points * ne) || triangle.size() % 3 != 0)
    throw InputError(path + ": the display's points and shapes disagree in size");
  for (double v : triangle)
    if (v < 0 || v >= static_cast<double>(points)) throw InputError(path + ": a display triangle names a point it does not have");
  f.display_position = Eigen::Map<const Eigen::Matrix3Xd>(position.data(), 3, points).colwise() - f.centre;
  f.display_shape = Eigen::Map<const Eigen::MatrixXd>(shape.data(), 3 * points, ne);  // mode k: its 3 d values in order
  f.display_triangle.assign(triangle.begin(), triangle.end());
}

void read_floating(hid_t file, const std::string& path, FloatingFrameData& f) {
  const auto omega2 = read_all(file, "/floating/omega_squared", path).first;
  const auto ne = static_cast<Eigen::Index>(omega2.size());
  f.omega2 = Eigen::Map<const Eigen::VectorXd>(omega2.data(), ne);
  f.mass0 = matrix(read_all(file, "/floating/mass0", path), path + ":/floating/mass0");
  const auto a = read_all(file, "/floating/a", path).first, c = read_all(file, "/floating/c", path).first,
             e = read_all(file, "/floating/e", path).first;
  const auto ids = read_all(file, "/floating/node_id", path).first, position = read_all(file, "/floating/node_position", path).first,
             shape = read_all(file, "/floating/node_shape", path).first;
  const auto un = static_cast<std::size_t>(ne), nodes = ids.size();
  if (f.mass0.rows() != 6 + ne || a.size() != 18 * un || c.size() != 9 * un * un || e.size() != 3 * un * un ||
      position.size() != 3 * nodes || shape.size() != 6 * un * nodes)
    throw InputError(path + ": the floating frame's data disagree in size");
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  for (std::size_t k = 0; k < un; ++k) {
    f.a.emplace_back(Eigen::Map<const RowMajor>(a.data() + 18 * k, 3, 6));
    f.e.emplace_back(Eigen::Map<const RowMajor>(e.data() + 3 * un * k, 3, ne));
  }
  for (std::size_t k = 0; k < un * un; ++k) f.c.emplace_back(Eigen::Map<const RowMajor>(c.data() + 9 * k, 3, 3));
  for (std::size_t k = 0; k < nodes; ++k) {
    f.node_id.push_back(static_cast<long>(ids[k]));
    f.node_position.emplace_back(position[3 * k], position[3 * k + 1], position[3 * k + 2]);
    f.node_shape.emplace_back(Eigen::Map<const RowMajor>(shape.data() + 6 * un * k, 6, ne));
  }
}

// The XDMF sidecar's views (/xdmf/shape<q>: coordinate q's displacement of the display
// nodes) and its text: time q + 1 is coordinate q, the surface with its shape as a vector
// to warp by.
std::string write_views(hid_t root, const std::string& h5_name, hsize_t coordinates, hsize_t nodes, hsize_t triangles) {
  const Source shapes(root, "/display/shape");
  const h5::Handle group(H5Gcreate2(root, "/xdmf", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, "create /xdmf");
  std::ostringstream o;
  o << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"part\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  const std::string n3 = std::to_string(nodes) + " 3";
  for (hsize_t q = 0; q < coordinates; ++q) {
    const std::string name = "shape" + std::to_string(q);
    make_view(group.get(), name.c_str(), {nodes, 3}, shapes, q, 0, 3);
    o << "   <Grid Name=\"coordinate" << q + 1 << "\" GridType=\"Uniform\">\n    <Time Value=\"" << q + 1 << "\"/>\n"
      << "     <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << triangles << "\">\n";
    xdmf_item(o, h5_name, "/display/triangle", std::to_string(triangles) + " 3", true, "      ");
    o << "     </Topology>\n     <Geometry GeometryType=\"XYZ\">\n";
    xdmf_item(o, h5_name, "/display/position", n3, false, "      ");
    o << "     </Geometry>\n";
    xdmf_attribute(o, h5_name, "shape", "Vector", "Node", "/xdmf/" + name, n3);
    o << "   </Grid>\n";
  }
  o << "  </Grid>\n </Domain>\n</Xdmf>\n";
  return o.str();
}

std::string write_file(const std::string& path, const std::string& h5_name, const ReducedPart& part, const std::vector<FeDof>& dofs,
                       const FeMesh& mesh, const ReducedPartInfo& info) {
  const h5::Handle file(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose, "create " + path);
  const hid_t root = file.get();
  h5::write_string_attribute(root, "mbsflow_version", MBSFLOW_VERSION);
  h5::write_string_attribute(root, "kind", kind);
  h5::write_string_attribute(root, "source", info.source);
  h5::write_string_attribute(root, "command_line", info.command_line);
  for (const char* g : {"/reduced", "/modes", "/mass", "/invariants", "/nodes", "/interface", "/display"})
    h5::Handle(H5Gcreate2(root, g, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose, std::string("create ") + g);
  const auto r = static_cast<hsize_t>(part.mass.rows());
  h5::write_array(root, "/reduced/mass", H5T_NATIVE_DOUBLE, row_major(part.mass), {r, r});
  h5::write_array(root, "/reduced/stiffness", H5T_NATIVE_DOUBLE, row_major(part.stiffness), {r, r});
  std::vector<long> coordinate_dof;
  for (const FeDof& d : part.interface_dofs) coordinate_dof.insert(coordinate_dof.end(), {d.node, d.direction});
  for (int k = 0; k < part.modes; ++k) coordinate_dof.insert(coordinate_dof.end(), {0L, 0L});
  h5::write_array(root, "/reduced/coordinate_dof", H5T_NATIVE_LONG, coordinate_dof, {r, 2});
  const std::vector<double> frequency(part.fixed_frequency.data(), part.fixed_frequency.data() + part.fixed_frequency.size());
  h5::write_array(root, "/modes/frequency", H5T_NATIVE_DOUBLE, frequency, {frequency.size()});
  h5::write_array(root, "/mass/mass", H5T_NATIVE_DOUBLE, std::vector<double>{part.properties.mass}, {1});
  const Eigen::Vector3d& c = part.properties.centre;
  h5::write_array(root, "/mass/centre", H5T_NATIVE_DOUBLE, std::vector<double>{c.x(), c.y(), c.z()}, {3});
  h5::write_array(root, "/mass/inertia", H5T_NATIVE_DOUBLE, row_major(part.properties.inertia), {3, 3});
  h5::write_array(root, "/invariants/rigid_coupling", H5T_NATIVE_DOUBLE, row_major(part.rigid_coupling), {6, r});

  const hsize_t n = mesh.node_id.size();
  std::vector<double> position;
  for (const Eigen::Vector3d& x : mesh.node_position) position.insert(position.end(), {x.x(), x.y(), x.z()});
  h5::write_array(root, "/nodes/id", H5T_NATIVE_LONG, mesh.node_id, {n});
  h5::write_array(root, "/nodes/position", H5T_NATIVE_DOUBLE, position, {n, 3});
  std::vector<long> interface_nodes;
  for (const FeDof& d : part.interface_dofs)
    if (interface_nodes.empty() || interface_nodes.back() != d.node) interface_nodes.push_back(d.node);
  h5::write_array(root, "/interface/node", H5T_NATIVE_LONG, interface_nodes, {interface_nodes.size()});

  // The display: the outer faces' corner nodes and each one's translation per coordinate.
  const std::vector<std::array<long, 3>> faces = outer_triangles(mesh);
  std::unordered_map<long, long> display_index;
  std::vector<long> display_node;
  std::vector<int> triangle;
  for (const auto& f : faces)
    for (long node : f) {
      const auto [at, added] = display_index.emplace(node, static_cast<long>(display_node.size()));
      if (added) display_node.push_back(static_cast<long>(mesh.node_index.at(node)));
      triangle.push_back(static_cast<int>(at->second));
    }
  const auto translation_row = dof_rows_by_node(dofs);  // node -> rows of its x, y, z (and rotation) DOFs
  const hsize_t d = display_node.size();
  std::vector<double> shape(r * d * 3, 0.0);
  for (hsize_t j = 0; j < d; ++j) {
    const auto at = translation_row.find(mesh.node_id[static_cast<std::size_t>(display_node[j])]);
    if (at == translation_row.end()) continue;  // a node with no DOF (held by the deck): it stays
    for (std::size_t e = 0; e < 3; ++e)
      if (at->second[e] >= 0)
        for (hsize_t q = 0; q < r; ++q)
          shape[(q * d + j) * 3 + e] = part.shapes(at->second[e], static_cast<Eigen::Index>(q));
  }
  h5::write_array(root, "/display/node", H5T_NATIVE_LONG, display_node, {d});
  std::vector<double> display_position;
  for (long k : display_node) {
    const Eigen::Vector3d& x = mesh.node_position[static_cast<std::size_t>(k)];
    display_position.insert(display_position.end(), {x.x(), x.y(), x.z()});
  }
  h5::write_array(root, "/display/position", H5T_NATIVE_DOUBLE, display_position, {d, 3});
  h5::write_array(root, "/display/triangle", H5T_NATIVE_INT, triangle, {faces.size(), 3});
  h5::write_array(root, "/display/shape", H5T_NATIVE_DOUBLE, shape, {r, d, 3});
  write_floating(root, part.floating);
  if (const Eigen::MatrixXd& phi = part.floating.reduced_modes; phi.size() > 0) {
    // Each elastic mode's displacement of the display points: the floating frame's drawn
    // deformation in a run's results.
    // shape (r x d x 3) is, column-major, 3 d x r: times phi, 3 d x ne, that is ne x d x 3.
    const auto rows = static_cast<Eigen::Index>(3 * d);
    const Eigen::MatrixXd elastic = Eigen::Map<const Eigen::MatrixXd>(shape.data(), rows, static_cast<Eigen::Index>(r)) * phi;
    h5::write_array(root, "/floating/display_shape", H5T_NATIVE_DOUBLE, std::vector<double>(elastic.data(), elastic.data() + elastic.size()),
                    {static_cast<hsize_t>(phi.cols()), d, 3});
    h5::write_units(root, "/floating/display_shape", "m per unit modal coordinate (part axes)");
  }
  h5::write_units(root, "/reduced/mass", "kg, kg m, kg m^2 (by the coordinates' kinds; modal coordinates mass-normalised)");
  h5::write_units(root, "/reduced/stiffness", "N/m, N, N m (by the coordinates' kinds)");
  h5::write_units(root, "/modes/frequency", "Hz");
  h5::write_units(root, "/mass/mass", "kg");
  h5::write_units(root, "/mass/centre", "m");
  h5::write_units(root, "/mass/inertia", "kg m^2");
  h5::write_units(root, "/nodes/position", "m");
  h5::write_units(root, "/display/shape", "m per unit coordinate");
  h5::write_units(root, "/display/position", "m");
  return write_views(root, h5_name, r, d, faces.size());
}

}  // namespace

void write_reduced_part(const std::string& path, const ReducedPart& part, const std::vector<FeDof>& dofs, const FeMesh& mesh,
                        const ReducedPartInfo& info) {
  std::string xdmf;
  const std::string name = std::filesystem::path(path).filename().string();  // the sidecar lies beside it
  write_through_part(path, [&](const std::string& making) { xdmf = write_file(making, name, part, dofs, mesh, info); });
  // Written after the part's file is complete, so that it never names a file being made.
  const std::string sidecar = xdmf_path(path);
  write_through_part(sidecar, [&](const std::string& making) {
    std::ofstream o(making);
    o << xdmf;
    if (!o.flush()) throw InputError(sidecar + ": cannot write the XDMF sidecar");
  });
}

std::string free_frequencies_text(const ReducedPart& part) {
  const Eigen::VectorXd free = reduced_frequencies(part, false);
  std::string rigid, lowest;
  for (Eigen::Index k = 0; k < std::min<Eigen::Index>(free.size(), 12); ++k) {
    char text[32];
    std::snprintf(text, sizeof text, "%s%.6g", k == 0 || k == 6 ? "" : ", ", free[k]);
    (k < 6 ? rigid : lowest) += text;
  }
  return "rigid-body motions at " + rigid + " Hz, then " + lowest + " Hz";
}

bool is_reduced_part(const std::string& path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  if (H5Fis_hdf5(path.c_str()) <= 0) return false;
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0) return false;
  const h5::Handle closing(file, H5Fclose, "open " + path);
  return h5::read_string_attribute(file, "kind") == std::string(kind);
}

ReducedPart read_reduced_part(const std::string& path, ReducedPartInfo* info) {
  std::error_code missing;
  if (!std::filesystem::exists(path, missing)) throw InputError(path + ": no such file");
  if (!is_reduced_part(path)) throw InputError(path + ": not a reduced part (mbsflow reduce writes one)");
  const h5::Handle file(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose, "open " + path);
  if (info) {
    info->source = h5::read_string_attribute(file.get(), "source").value_or("?");
    info->command_line = h5::read_string_attribute(file.get(), "command_line").value_or("?");
  }
  ReducedPart p;
  p.mass = matrix(read_all(file.get(), "/reduced/mass", path), path + ":/reduced/mass");
  p.stiffness = matrix(read_all(file.get(), "/reduced/stiffness", path), path + ":/reduced/stiffness");
  const Eigen::MatrixXd dof = matrix(read_all(file.get(), "/reduced/coordinate_dof", path), path + ":/reduced/coordinate_dof");
  for (Eigen::Index k = 0; k < dof.rows(); ++k)
    if (dof(k, 1) > 0)
      p.interface_dofs.push_back({static_cast<long>(dof(k, 0)), static_cast<int>(dof(k, 1))});
    else
      ++p.modes;
  const auto frequency = read_all(file.get(), "/modes/frequency", path).first;
  p.fixed_frequency = Eigen::Map<const Eigen::VectorXd>(frequency.data(), static_cast<Eigen::Index>(frequency.size()));
  p.properties.mass = read_all(file.get(), "/mass/mass", path).first.at(0);
  const auto centre = read_all(file.get(), "/mass/centre", path).first;
  p.properties.centre = Eigen::Vector3d(centre.at(0), centre.at(1), centre.at(2));
  p.properties.inertia = matrix(read_all(file.get(), "/mass/inertia", path), path + ":/mass/inertia");
  p.rigid_coupling = matrix(read_all(file.get(), "/invariants/rigid_coupling", path), path + ":/invariants/rigid_coupling");
  if (p.mass.rows() != dof.rows() || p.stiffness.rows() != dof.rows() || p.mass.cols() != p.mass.rows())
    throw InputError(path + ": the reduced matrices and coordinates disagree in size");
  p.floating.mass = p.properties.mass;
  p.floating.inertia = p.properties.inertia;
  p.floating.centre = p.properties.centre;
  if (H5Lexists(file.get(), "/floating", H5P_DEFAULT) > 0) {
    read_floating(file.get(), path, p.floating);
    if (H5Lexists(file.get(), "/floating/display_shape", H5P_DEFAULT) > 0) read_display(file.get(), path, p.floating);
  }
  return p;
}

}  // namespace mbsflow
