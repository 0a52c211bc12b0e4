// Penetration depth of two posed meshes: how far B must move to be free of A.
//  - along a direction: exact to the contact resolution. Starting from a translation that
//    separates their boxes, B is moved back along the direction by conservative advancement (each
//    step is the current distance, since a translation moves every point by its length), so the
//    first contact met is the largest translation at which they still touch;
//  - as a vector: the smallest of those over candidate directions. The candidates are the
//    separating axes of the overlapping pieces of an approximate convex decomposition of both
//    meshes (kernel/mesh/convex_decomposition: for convex pieces that axis is their exact penetration
//    direction), the six axis directions of each part's own frame, and a Fibonacci lattice over
//    the sphere. Every candidate's depth is measured on
//    the meshes themselves, so the answer is a certified upper bound: B moved by it is free of A.
//    For two convex closed meshes the decomposition is one piece each and the answer is the exact
//    penetration depth; for non-convex parts it can exceed the true minimum when no candidate
//    points at it (between lattice samples 'angle_deg' apart, by up to 1 / cos(angle_deg / 2) for
//    locally convex contact).
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "kernel/core/stop_token.h"
#include "kernel/core/tolerances.h"

namespace gk {

struct DepthAlong {
  // The first translation along the direction at which B is free of A (touching at most, checked
  // by the exact verdict); 0 when B is already free.
  double depth_mm = 0.0;
  double last_exit_mm = 0.0;  // beyond this B stays free (equal to depth_mm unless B leaves through a cavity)
  int steps = 0;
};

// direction: unit-length not required (normalised); tolerance_mm: contact resolution.
Result<DepthAlong> penetration_along(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                     const RigidTransform& pose_b, const Vec3& direction, double tolerance_mm = tolerances::kDepthResolutionMm,
                                     const StopToken& stop = {});

struct DepthVector {
  Vec3 direction = Vec3::Zero();  // unit; the translation of B is depth_mm * direction
  double depth_mm = 0.0;
  int directions_tried = 0;
  int piece_directions = 0;       // of which from the pieces' separating axes and the parts' frames
  bool from_piece_axis = false;   // the best direction is one of those (not a lattice direction)
  int pieces_a = 0, pieces_b = 0;
  double max_concavity_mm = 0.0;  // the decomposition's deepest piece (either mesh)
  bool exact = false;             // both meshes convex and closed: depth_mm is the true minimum
  double max_angle_between_samples_deg = 0.0;
  bool stopped_early = false;     // asked to stop: not every direction was tried (still an upper bound)
};

// The smallest depth over the convex pieces' axes and `samples` lattice directions.
// Asks `stop` as it goes (the caller gave up): the best found so far (stopped_early), or kStopped
// if no direction was finished. Asks `enough` between directions (a time budget): once one
// direction is finished, the best so far is returned (stopped_early).
Result<DepthVector> penetration_vector(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                       const RigidTransform& pose_b, int samples = 162, double tolerance_mm = tolerances::kDepthResolutionMm,
                                       const StopToken& stop = {}, const StopToken& enough = {});

}  // namespace gk
