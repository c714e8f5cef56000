#pragma once
// The flexible bodies' deformed surfaces in a run's XDMF sidecar (xdmf_writer.hpp): per
// snapshot, each body's drawn surface (mbsflow reduce's /display) at its frame's place,
// deformed by its modal coordinates, as a triangle grid with the elastic displacement
// (world frame) as point data. The points are computed from the results file's frame
// position, orientation and modal coordinates and written as datasets of their own (Xdmf3
// reads whole datasets), so they are capped at flexible_surface_limit_bytes in all.
#include <hdf5.h>

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

#include "mbsflow/graph/flexible_body.hpp"

namespace mbsflow {

inline constexpr std::size_t flexible_surface_limit_bytes = std::size_t{256} << 20;

struct FlexibleSurface {
  std::string name;
  int frame = 0;          // its frame body
  std::size_t first = 0;  // its first column of /flexible/modal_coordinates
  const FloatingFrameData* data = nullptr;
};

// Whether the surfaces' points over `snapshots` snapshots stay within the limit.
bool surfaces_fit(const std::vector<FlexibleSurface>& surfaces, std::size_t snapshots);

// The surfaces' triangles, once: /xdmf/surface<k>_triangles.
void write_surface_triangles(hid_t file, const std::vector<FlexibleSurface>& surfaces);

// Snapshot `row`'s surfaces: datasets surface<k> and elastic<k> in the group `step` (its
// path, ending in '/'), and a grid each in the sidecar `o`, which names the results file
// `file_name`.
void write_surfaces_at(hid_t file, hid_t step_group, const std::string& step, hsize_t row,
                       const std::vector<FlexibleSurface>& surfaces, std::ostream& o, const std::string& file_name);

}  // namespace mbsflow
