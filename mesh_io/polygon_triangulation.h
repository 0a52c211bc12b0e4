// A polygon of a mesh file (an OBJ, OFF or PLY face of more than three vertices) as triangles that
// cover exactly the polygon as written. A fan from the first vertex does that only for a convex
// polygon: fanned, a concave one (an L, a U-channel's end cap) gains area outside itself and a
// part reads bigger than it is. So a convex polygon is fanned, a concave one is cut into ears,
// every turn decided by exact predicates on the polygon projected to the axis plane its normal is
// closest to (dropping a coordinate keeps the written values exact). A polygon that crosses itself
// has no triangles that cover it as written and is refused.
#pragma once

#include "kernel/core/status.h"
#include "kernel/mesh/triangle_mesh.h"

#include <cstdint>
#include <vector>

namespace gk::mesh_io {

// Work allowed for the ear cutting of one file's concave polygons (point-in-triangle tests), so
// that a small file cannot buy minutes of it.
struct TriangulationBudget {
  long long tests_left = 50'000'000;
};

// Appends the polygon's triangles (indices into `vertices`, already checked) to `out`. The error
// says what is wrong; the caller names the face.
Result<bool> append_polygon_triangles(const std::vector<Vec3>& vertices, const std::vector<std::uint32_t>& polygon,
                                      std::vector<TriangleMesh::Face>& out, TriangulationBudget& budget);

}  // namespace gk::mesh_io
