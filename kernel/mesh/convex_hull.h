// 3D convex hull by quickhull (Barber, Dobkin, Huhdanpaa 1996), with every visibility decision made
// by the exact orient3d predicate, so the hull is consistent on any input. OCCT 7.6 has none.
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/status.h"
#include "kernel/mesh/triangle_mesh.h"

#include <array>
#include <cstdint>
#include <vector>

namespace gk {

// The hull of the points as a closed mesh wound counter-clockwise seen from outside. Points on the
// hull's faces but not at its corners are left out. Fewer than four points, non-finite points, or
// all points coplanar are errors (a flat set has no volume to bound a sweep with).
Result<TriangleMesh> convex_hull(const std::vector<Vec3>& points);

// The same hull as bare corners and outward-wound faces (indices into corners), without building
// and validating a TriangleMesh: for hot loops that only need the planes and corners.
struct HullPolytope {
  std::vector<Vec3> corners;
  std::vector<std::array<std::uint32_t, 3>> faces;
};
Result<HullPolytope> convex_hull_polytope(const std::vector<Vec3>& points);

}  // namespace gk
