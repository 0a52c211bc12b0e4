// Is a mesh the boundary of one convex solid? Decided exactly, not on vertices alone (a V-groove
// block or a U-channel has every vertex on its hull and is not convex).
#pragma once

#include "kernel/mesh/triangle_mesh.h"

namespace gk {

// True when the mesh is closed, consistently oriented outward, one connected body, every edge is
// convex (the far corner of each neighbouring triangle lies on or below the triangle's plane, by
// the exact orient3d), and its volume equals its convex hull's (to 1e-9 relative): together these
// make the solid equal to its hull.
bool is_convex_solid(const TriangleMesh& mesh);

}  // namespace gk
