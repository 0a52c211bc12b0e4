// Convex polytopes of the P4 model (organ prisms, plates of parts and of the manipulator) as the
// separating-axis theorem sees them: vertices, face normals and edge directions. For two convex
// polytopes the smallest overlap over those axes (face normals of both and cross products of
// their edges) is the exact penetration depth: the shortest translation that separates them.
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/rigid_transform.h"
#include "machine_models/p4/sheet_part.h"

#include <utility>
#include <vector>

namespace gk::p4 {

struct ConvexPolytope {
  std::vector<Vec3> vertices;
  std::vector<Vec3> face_normals;     // unit
  std::vector<Vec3> edge_directions;  // unit

  static ConvexPolytope prism(const std::vector<Vec2>& profile_yz, double x_min, double x_max);
  static ConvexPolytope plate(const Plate& plate);
  ConvexPolytope transformed(const RigidTransform& pose) const;
};

// The interval [min, max] of the points' projections on an axis.
std::pair<double, double> projection(const std::vector<Vec3>& points, const Vec3& axis);

// The penetration depth of two convex polytopes: 0 when they are apart or only touch, otherwise
// the length of the shortest translation that separates them. [mm]
double penetration_depth(const ConvexPolytope& a, const ConvexPolytope& b);

// A lower bound of the distance between two convex polytopes: the largest gap along any of the
// separating-axis candidates (0 when they overlap). Exact when a face normal separates them. [mm]
double separation_lower_bound(const ConvexPolytope& a, const ConvexPolytope& b);

}  // namespace gk::p4
