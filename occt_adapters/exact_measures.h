// Exact B-Rep measures: the distance between two shapes (BRepExtrema_DistShapeShape) and the volume
// they share (BRepAlgoAPI_Common). They confirm; they do not measure penetration depth.
#pragma once

#include "kernel/geometry_types.h"
#include "kernel/rigid_transform.h"
#include "kernel/status.h"
#include "occt_adapters/shape.h"

namespace gk::occt {

struct ShapeDistance {
  double distance_mm = 0.0;  // 0 when the shapes touch or overlap
  Vec3 point_a = Vec3::Zero();
  Vec3 point_b = Vec3::Zero();
  bool inner = false;  // one shape lies inside the other (OCCT's InnerSolution)
};

Result<ShapeDistance> exact_distance(const Shape& a, const Shape& b);

// The exact distance between face face_a of a (placed at pose_a) and face face_b of b (at pose_b);
// faces are numbered 1.. in the order of the shape's face map (as mesh_shape's face ids).
Result<ShapeDistance> face_distance(const Shape& a, int face_a, const RigidTransform& pose_a, const Shape& b, int face_b,
                                    const RigidTransform& pose_b);

// Volume of the Boolean common of the two shapes [mm^3]; 0 when they are disjoint or only touch.
Result<double> interference_volume(const Shape& a, const Shape& b);

}  // namespace gk::occt
