// A mesh thinned for drawing (a report page's 3D view), never for a decision: vertices clustered
// on a grid over the mesh's box, each cell's vertices replaced by their mean, triangles whose
// corners fall in fewer than three cells dropped. The grid is made coarser until the mesh holds
// at most the asked number of triangles, so a 70k-triangle robot base costs a page a few
// thousand.
#pragma once

#include "kernel/mesh/triangle_mesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace gk {

struct DisplayMesh {
  std::vector<Vec3> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
};

// At most max_triangles (at least 1) triangles; a mesh already that small comes back as it is.
DisplayMesh decimate_for_display(const TriangleMesh& mesh, std::size_t max_triangles);

}  // namespace gk
