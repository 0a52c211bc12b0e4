// A part as the engine decides on it: its triangles in a BVH and, for CAD parts, the exact B-Rep
// they were tessellated from (the triangles then only say where to look).
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/rigid_transform.h"
#include "occt_adapters/shape.h"

#include <memory>
#include <vector>

namespace gk::engine {

struct PartGeometry {
  std::shared_ptr<const TriangleMesh> mesh;
  std::shared_ptr<MeshBvh> bvh;
  // How far the triangles may lie from the part's true surface [mm]: the tessellation's chordal
  // deflection for a CAD part with curved faces or edges; 0 for meshes (the triangles are the part)
  // and for CAD parts bounded by planes and straight edges only (their tessellation is exact).
  double deflection_mm = 0.0;
  occt::Shape shape;                  // CAD parts: the exact B-Rep
  std::vector<int> face_of_triangle;  // CAD parts: each triangle's B-Rep face (1-based)
  bool is_cad() const { return !shape.is_null(); }
};

struct PosedPart {
  const PartGeometry* part = nullptr;
  RigidTransform pose;
};

}  // namespace gk::engine
