// Two posed B-Rep solids decided on their exact faces: apart (by how much), touching, or
// overlapping. The tessellation only says where to look; this is the answer when the mesh is too
// coarse to tell (its distance within the deflections).
//
// Everything runs in a local frame: both shapes are moved so that `frame_origin` (a world point near
// the contact) becomes the origin. OCCT's Booleans and classifiers use absolute tolerances
// (1e-7 mm) that lose their meaning on coordinates of 5e4 mm, where a double's spacing is 7e-12 mm
// and the algorithms' internal arithmetic far coarser: a Boolean common that is right at the origin
// comes back empty at factory coordinates.
#pragma once

#include "kernel/core/geometry_types.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "occt_adapters/shape.h"

#include <utility>
#include <vector>

namespace gk::occt {

enum class BrepRelation { kApart, kTouching, kOverlapping };

struct BrepContact {
  BrepRelation relation = BrepRelation::kApart;
  double distance_mm = 0.0;         // between the boundaries; 0 unless apart
  Vec3 point_a = Vec3::Zero();      // world witnesses (apart), or a point of the contact or overlap
  Vec3 point_b = Vec3::Zero();
  int face_a = 0, face_b = 0;       // 1-based faces of the witnesses (0: not a face pair)
  double shared_volume_mm3 = 0.0;   // the Boolean common's volume, when it ran
  bool nested = false;              // overlapping with boundaries apart: one lies inside the other
  bool used_boolean = false;
};

// The volume two solids share (Boolean common, solid by solid) [mm^3], a bound on its error
// (checked against the common's fine tessellation), and how thick the common is on average (the largest of its solids' 2 V / A).
// When that does not show a crossing, the boundaries' section is examined: a point of either
// surface found inside the other solid (beyond the contact tolerance) where they cross.
struct SharedVolume {
  double volume_mm3 = 0.0;
  double error_bound_mm3 = 0.0;   // |true - volume_mm3| at most this (occt_adapters/solid_volume)
  double thickness_mm = 0.0;
  bool surface_point_inside = false;
  Vec3 point_inside = Vec3::Zero();  // that point, in the frame the shapes were placed in
  // Crossing rather than touching: more volume than tolerances::kBrepOverlapVolumeMm3, a common
  // thicker than tolerances::kBrepCrossingThicknessMm, or a surface point inside the other solid.
  bool crossing() const;
};

// The two shapes at their poses. `face_pairs` (1-based, a's then b's) restricts the distance to the
// pairs that can hold the minimum; empty: all faces. Boundaries closer than touch_mm are touching or
// crossing, told apart by a Boolean common (solid by solid, SharedVolume::crossing).
Result<BrepContact> decide_brep_contact(const Shape& a, const RigidTransform& pose_a, const Shape& b,
                                        const RigidTransform& pose_b, const Vec3& frame_origin,
                                        const std::vector<std::pair<int, int>>& face_pairs, double touch_mm);

// The volume the two solids share at their poses (Boolean common in the local frame). With
// bound_error, error_bound_mm3 is a bound that holds (the common checked against its tessellation,
// occt_adapters/solid_volume); without, only the crossing matters and it is infinity.
Result<SharedVolume> shared_volume(const Shape& a, const RigidTransform& pose_a, const Shape& b, const RigidTransform& pose_b,
                                   const Vec3& frame_origin, bool bound_error = false);

// A second search for the closest points, independent of BRepExtrema's face-pair extrema (which
// can stop in a local minimum): the mesh witnesses projected onto the exact shapes, then projected
// alternately onto each other until the distance stops falling. Real surface points: the distance
// is an upper bound of the true one, and near the tessellation's minimum.
struct ProjectedPair {
  double distance_mm = 0.0;
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();  // world
};
Result<ProjectedPair> closest_by_projection(const Shape& a, const RigidTransform& pose_a, const Shape& b,
                                            const RigidTransform& pose_b, const Vec3& frame_origin, const Vec3& start_a,
                                            const Vec3& start_b, int iterations);

// The first of the world points lying strictly inside a solid of the shape at its pose (farther in
// than tolerance_mm), or -1. A point on a body's exact surface found inside the other solid proves
// the two overlap.
Result<int> first_point_inside(const Shape& shape, const RigidTransform& pose, const std::vector<Vec3>& points,
                               const Vec3& frame_origin, double tolerance_mm);

// The distance from the shape at its pose to a set of world triangles (a mesh's patch near it),
// measured on the exact faces; witnesses in world coordinates.
struct TriangleSetDistance {
  double distance_mm = 0.0;
  Vec3 point_shape = Vec3::Zero(), point_triangles = Vec3::Zero();
  int face = 0;  // 1-based face of the shape's witness
};
Result<TriangleSetDistance> distance_to_triangles(const Shape& shape, const RigidTransform& pose,
                                                  const std::vector<Triangle>& triangles, const Vec3& frame_origin);

// Whether world triangles (a mesh's patch) enter the shape's solids at its pose: the Boolean
// common of each solid with the triangles as planar faces, one interior point of each piece of
// the common classified. kEntering: a point of the triangles lies inside a solid farther than
// tolerance_mm from its boundary (a crossing, proven by that point). kNotEntering: the common is
// empty or lies on the solid's boundary (touching, or apart). kUndecided: a piece could not be
// classified.
enum class TrianglesRelation { kNotEntering, kEntering, kUndecided };
struct TrianglesAgainstSolid {
  TrianglesRelation relation = TrianglesRelation::kUndecided;
  Vec3 point_inside = Vec3::Zero();  // with kEntering: a point of the triangles inside the solid (world)
};
Result<TrianglesAgainstSolid> triangles_against_solid(const Shape& shape, const RigidTransform& pose,
                                                     const std::vector<Triangle>& triangles, const Vec3& frame_origin,
                                                     double tolerance_mm);

// A point strictly inside each solid of the shape at its pose (world; farther in than tolerance_mm,
// as OCCT's classifier says): a point of a face moved inward along its normal. A solid too thin
// for that gives none.
Result<std::vector<Vec3>> points_inside_solids(const Shape& shape, const RigidTransform& pose, const Vec3& frame_origin,
                                               double tolerance_mm);

}  // namespace gk::occt
