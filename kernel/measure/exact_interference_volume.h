// The volume two closed meshes share, exactly: both posed meshes in exact rational arithmetic
// (CGAL's lazy exact kernel: the pose's products and sums carried exactly), corefined, their
// intersection solid built and its volume summed by the divergence theorem — no rounding until the
// final figure, whose interval is the error bound.
//
// The fallback of the ray cast (kernel/measure/interference_volume.h) where its grid cannot resolve the
// overlap. Its cost grows with the triangles near the overlap and their crossings, not with a grid,
// and it cannot be interrupted inside CGAL: callers bound the triangle count it is given.
#pragma once

#include "kernel/mesh/triangle_mesh.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "kernel/core/stop_token.h"

namespace gk {

struct ExactVolume {
  double volume_mm3 = 0.0;
  double error_bound_mm3 = 0.0;  // the exact figure's distance to the nearest double, at most
};

// Whether a closed mesh bounds a volume, so that its inside is well defined: closed, free of
// self-intersections (its shells crossing each other included), its shells nested with alternating
// orientation (checked on exact predicates). Wound inward as a whole is accepted. Errors name
// `side`: not closed, non-manifold.
Result<bool> bounds_a_volume(const TriangleMesh& mesh, const char* side);

// Both meshes closed, consistently oriented, free of self-intersections near the overlap and
// without non-manifold vertices; kFailedPrecondition (naming the side) when they are not: such a
// mesh has no well-defined inside for a Boolean.
// `stop` is asked at each step of the corefinement (kStopped when it says so).
Result<ExactVolume> exact_interference_volume(const TriangleMesh& a, const RigidTransform& pose_a, const TriangleMesh& b,
                                              const RigidTransform& pose_b, const StopToken& stop = {});

}  // namespace gk
