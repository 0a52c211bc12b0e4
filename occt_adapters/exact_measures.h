// Exact B-Rep measures: the distance between two shapes (BRepExtrema_DistShapeShape) and the volume
// they share (BRepAlgoAPI_Common). They confirm; they do not measure penetration depth.
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "occt_adapters/shape.h"

#include <utility>
#include <vector>

namespace gk::occt {

struct ShapeDistance {
  double distance_mm = 0.0;  // 0 when the shapes touch or overlap
  Vec3 point_a = Vec3::Zero();
  Vec3 point_b = Vec3::Zero();
  bool inner = false;  // one shape lies inside the other (OCCT's InnerSolution)
};

Result<ShapeDistance> exact_distance(const Shape& a, const Shape& b);

// The closest of the given face pairs (1-based ids, a's face then b's), each measured exactly with
// the shapes placed at their poses; the face maps are built once for all pairs.
struct ClosestFacePair {
  ShapeDistance distance;
  int face_a = 0, face_b = 0;
};
Result<ClosestFacePair> closest_face_pair(const Shape& a, const RigidTransform& pose_a, const Shape& b,
                                          const RigidTransform& pose_b, const std::vector<std::pair<int, int>>& face_pairs);

// Volume of the Boolean common of the two shapes [mm^3]; 0 when they are disjoint or only touch.
Result<double> interference_volume(const Shape& a, const Shape& b);

}  // namespace gk::occt
