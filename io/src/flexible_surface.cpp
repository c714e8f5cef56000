#include "flexible_surface.hpp"

#include <Eigen/Geometry>

#include "hdf5_handle.hpp"
#include "mbsflow/io/result_fields.hpp"
#include "xdmf_writer.hpp"

namespace mbsflow {
namespace {

// Of row `row` of the series `path`: item `item`'s `width` values (T x N x width), or
// columns [item, item + width) (T x columns).
Eigen::VectorXd read_item(hid_t file, const char* path, hsize_t row, hsize_t item, hsize_t width) {
  const h5::Handle set(H5Dopen2(file, path, H5P_DEFAULT), H5Dclose, std::string("open ") + path);
  const h5::Handle space(H5Dget_space(set.get()), H5Sclose, std::string("get the space of ") + path);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  std::vector<hsize_t> start(static_cast<std::size_t>(rank), 0), count(static_cast<std::size_t>(rank), 1);
  start[0] = row;
  start[1] = item;
  count[static_cast<std::size_t>(rank) - 1] = width;
  h5::check(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, count.data(), nullptr),
            std::string("select in ") + path);
  const hsize_t n = width;
  const h5::Handle memory(H5Screate_simple(1, &n, nullptr), H5Sclose, "create a memory space");
  Eigen::VectorXd out(static_cast<Eigen::Index>(width));
  h5::check(H5Dread(set.get(), H5T_NATIVE_DOUBLE, memory.get(), space.get(), H5P_DEFAULT, out.data()), std::string("read ") + path);
  return out;
}

std::string dims(std::size_t a, std::size_t b) { return std::to_string(a) + ' ' + std::to_string(b); }

}  // namespace

bool surfaces_fit(const std::vector<FlexibleSurface>& surfaces, std::size_t snapshots) {
  std::size_t bytes = 0;
  for (const FlexibleSurface& s : surfaces) bytes += static_cast<std::size_t>(s.data->display_position.cols()) * 48 * snapshots;
  return bytes <= flexible_surface_limit_bytes;
}

void write_surface_triangles(hid_t file, const std::vector<FlexibleSurface>& surfaces) {
  for (std::size_t k = 0; k < surfaces.size(); ++k) {
    const std::vector<int>& t = surfaces[k].data->display_triangle;
    h5::write_array(file, ("/xdmf/surface" + std::to_string(k) + "_triangles").c_str(), H5T_NATIVE_INT, t, {t.size() / 3, 3});
  }
}

void write_surfaces_at(hid_t file, hid_t step_group, const std::string& step, hsize_t row,
                       const std::vector<FlexibleSurface>& surfaces, std::ostream& o, const std::string& file_name) {
  for (std::size_t k = 0; k < surfaces.size(); ++k) {
    const FlexibleSurface& s = surfaces[k];
    const FloatingFrameData& d = *s.data;
    const auto frame = static_cast<hsize_t>(s.frame);
    const auto points = static_cast<std::size_t>(d.display_position.cols());
    const Eigen::VectorXd p = read_item(file, body_fields[0].dataset, row, frame, 3);
    const Eigen::VectorXd q = read_item(file, body_fields[1].dataset, row, frame, 4);
    const Eigen::VectorXd eta = read_item(file, modal_coordinates_dataset, row, s.first, static_cast<hsize_t>(d.modes()));
    const Eigen::Matrix3d r = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
    Eigen::Matrix3Xd elastic;
    const Eigen::Matrix3Xd at = flexible_surface_points(d, p.head<3>(), r, eta, &elastic);
    const std::string name = "surface" + std::to_string(k), shift = "elastic" + std::to_string(k);
    // Column-major 3 x d: the points' x y z in turn, as the d x 3 datasets hold them.
    h5::write_array(step_group, name.c_str(), H5T_NATIVE_DOUBLE, std::vector<double>(at.data(), at.data() + at.size()), {points, 3});
    h5::write_array(step_group, shift.c_str(), H5T_NATIVE_DOUBLE, std::vector<double>(elastic.data(), elastic.data() + elastic.size()),
                    {points, 3});
    const std::size_t triangles = d.display_triangle.size() / 3;
    o << "    <Grid Name=\"" << s.name << "\" GridType=\"Uniform\">\n"
      << "     <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << triangles << "\" NodesPerElement=\"3\">\n";
    xdmf_item(o, file_name, "/xdmf/" + name + "_triangles", dims(triangles, 3), true, "      ");
    o << "     </Topology>\n     <Geometry GeometryType=\"XYZ\">\n";
    xdmf_item(o, file_name, step + name, dims(points, 3), false, "      ");
    o << "     </Geometry>\n";
    xdmf_attribute(o, file_name, "elastic_displacement", "Vector", "Node", step + shift, dims(points, 3));
    o << "    </Grid>\n";
  }
}

}  // namespace mbsflow
