// Penetration depth of two posed meshes: how far B must move to be free of A.
//  - along a direction: exact to the contact resolution. Starting from a translation that
//    separates their boxes, B is moved back along the direction by conservative advancement (each
//    step is the current distance, since a translation moves every point by its length), so the
//    first contact met is the largest translation at which they still touch;
//  - as a vector: the smallest of those over sampled directions. That is an upper bound of the
//    true (minimum-translation) depth; between samples 'angle_deg' apart the true direction can
//    make it larger by the factor 1 / cos(angle_deg / 2) for convex shapes.
#pragma once

#include "kernel/mesh_bvh.h"
#include "kernel/rigid_transform.h"
#include "kernel/status.h"

namespace gk {

struct DepthAlong {
  double depth_mm = 0.0;  // 0 when B is already free of A
  int steps = 0;
};

// direction: unit-length not required (normalised); tolerance_mm: contact resolution.
Result<DepthAlong> penetration_along(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                     const RigidTransform& pose_b, const Vec3& direction, double tolerance_mm = 1e-6);

struct DepthVector {
  Vec3 direction = Vec3::Zero();  // unit; the translation of B is depth_mm * direction
  double depth_mm = 0.0;
  int directions_tried = 0;
  double max_angle_between_samples_deg = 0.0;
};

// The smallest depth over `samples` directions spread over the sphere (a Fibonacci lattice).
Result<DepthVector> penetration_vector(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                       const RigidTransform& pose_b, int samples = 162, double tolerance_mm = 1e-6);

}  // namespace gk
