// Building shapes: boxes, prisms of YZ profiles, rigid placement, compounds, and the swept solids
// of a motion (BRepPrimAPI_MakeRevol about an axis, BRepPrimAPI_MakePrism along a vector).
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "occt_adapters/shape.h"

#include <vector>

namespace gk::occt {

Result<Shape> make_box(const Vec3& min, const Vec3& max);
// A flat rectangular face: corner, then its two edges (perpendicular, non-zero).
Result<Shape> make_rectangle(const Vec3& corner, const Vec3& edge_u, const Vec3& edge_v);
// A prism over a convex polygon in the YZ plane, from x_min to x_max.
Result<Shape> make_prism_yz(const std::vector<Eigen::Vector2d>& profile_yz, double x_min, double x_max);
Result<Shape> place(const Shape& shape, const RigidTransform& pose);
Result<Shape> make_compound(const std::vector<Shape>& shapes);

// A solid is swept through its boundary (OCCT sweeps no solids); the result then bounds the swept
// region but is not itself one closed solid, so measure its extent, not its volume.
// The solid swept by shape turning angle_deg about the axis through axis_point along axis_direction.
// The angle must be finite, non-zero and at most 360 degrees in magnitude: OCCT silently takes larger
// angles modulo 2 pi. An axis through the shape's interior is an error (OCCT cannot build it).
Result<Shape> revolve(const Shape& shape, const Vec3& axis_point, const Vec3& axis_direction, double angle_deg);

// The solid swept by shape travelling along travel (non-zero, finite).
Result<Shape> extrude(const Shape& shape, const Vec3& travel);

}  // namespace gk::occt
