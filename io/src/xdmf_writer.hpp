#pragma once
// XDMF sidecar of a results file: the bodies as points over time, so ParaView opens a run.
#include <string>
#include <vector>

namespace mbsflow {

// attributes: names of body fields besides position to attach (velocity, ...).
void write_xdmf(const std::string& xdmf_path, const std::string& h5_path, const std::vector<double>& times,
                std::size_t bodies, const std::vector<std::string>& attributes);

}  // namespace mbsflow
