// Tessellation of B-Rep shapes into kernel meshes, keeping each triangle's B-Rep face.
#pragma once

#include "kernel/core/status.h"
#include "kernel/mesh/triangle_mesh.h"
#include "occt_adapters/shape.h"

#include <vector>

namespace gk::occt {

struct MeshedShape {
  TriangleMesh mesh;
  std::vector<int> face_of_triangle;  // 1-based face index in the shape's face map (TopExp::MapShapes order)
  // How far the triangles may lie from the surface [mm]: the deflection asked, or the deviation
  // measured on the tessellation (mesh_shape) when larger. OCCT does not hold the asked one on
  // every surface (a sphere's triangles lie up to about twice it away).
  double deflection_mm = 0.0;
};

// Meshes a copy of the shape (the input is never modified, so shapes can be shared across threads).
// deflection_mm > 0, angular_deg in (0, 90].
Result<MeshedShape> mesh_shape(const Shape& shape, double deflection_mm, double angular_deg = 20.0);

}  // namespace gk::occt
