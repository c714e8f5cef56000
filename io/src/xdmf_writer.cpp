#include "xdmf_writer.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "mbsflow/error.hpp"
#include "mbsflow/io/result_fields.hpp"

namespace mbsflow {
namespace {

// Row t of the T x N x k dataset `path`, as an XDMF hyperslab.
void slab(std::ostream& o, const std::string& file, const char* path, std::size_t t, std::size_t rows, std::size_t n,
          int k, const char* indent) {
  o << indent << "<DataItem ItemType=\"HyperSlab\" Dimensions=\"" << n << ' ' << k << "\" Type=\"HyperSlab\">\n"
    << indent << "  <DataItem Dimensions=\"3 3\" Format=\"XML\">" << t << " 0 0 1 1 1 1 " << n << ' ' << k
    << "</DataItem>\n"
    << indent << "  <DataItem Dimensions=\"" << rows << ' ' << n << ' ' << k
    << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << file << ':' << path << "</DataItem>\n"
    << indent << "</DataItem>\n";
}

}  // namespace

void write_xdmf(const std::string& xdmf_path, const std::string& h5_path, const std::vector<double>& times,
                std::size_t bodies, const std::vector<std::string>& attributes) {
  std::ofstream o(xdmf_path);
  if (!o) throw Error(xdmf_path + ": cannot write the XDMF sidecar");
  const std::string file = std::filesystem::path(h5_path).filename().string();  // side by side
  const std::size_t rows = times.size();
  o << "<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"bodies\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  char time[32];
  for (std::size_t t = 0; t < rows; ++t) {
    std::snprintf(time, sizeof time, "%.17g", times[t]);
    o << "   <Grid Name=\"t" << t << "\" GridType=\"Uniform\">\n    <Time Value=\"" << time << "\"/>\n"
      << "    <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << bodies << "\" NodesPerElement=\"1\"/>\n"
      << "    <Geometry GeometryType=\"XYZ\">\n";
    slab(o, file, body_fields[0].dataset, t, rows, bodies, 3, "     ");
    o << "    </Geometry>\n";
    for (const BodyField& f : body_fields) {
      bool wanted = false;
      for (const auto& a : attributes) wanted = wanted || a == f.name;
      if (!wanted) continue;
      o << "    <Attribute Name=\"" << f.name << "\" AttributeType=\"" << (f.components == 3 ? "Vector" : "Matrix")
        << "\" Center=\"Node\">\n";
      slab(o, file, f.dataset, t, rows, bodies, f.components, "     ");
      o << "    </Attribute>\n";
    }
    o << "   </Grid>\n";
  }
  o << "  </Grid>\n </Domain>\n</Xdmf>\n";
  if (!o) throw Error(xdmf_path + ": error while writing the XDMF sidecar");
}

}  // namespace mbsflow
