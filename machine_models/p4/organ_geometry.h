// Closed meshes of machine organs: convex YZ profiles extruded along X.
#pragma once

#include "kernel/mesh/triangle_mesh.h"
#include "machine_models/p4/machine_model.h"

namespace gk::p4 {

// The prism over a convex counter-clockwise YZ profile from x_min to x_max, wound outward.
TriangleMesh prism_mesh(const std::vector<Vec2>& profile_yz, double x_min, double x_max);

// Depth of a point inside the convex prism (smallest distance to its faces), <= 0 when outside.
double depth_inside_prism(const std::vector<Vec2>& profile_yz, double x_min, double x_max, const Vec3& p);

}  // namespace gk::p4
