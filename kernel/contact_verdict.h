// The gatekeeper's verdict on two posed meshes: CLEAR, TOUCHING, COLLISION or INCONCLUSIVE.
//
//  CLEAR        no triangle pair intersects, the meshes are farther apart than the contact tolerance,
//               and (for closed meshes) neither lies inside the other.
//  TOUCHING     the meshes are within the contact tolerance without interpenetrating: either apart
//               by at most tolerances::kContactMm, or in contact where every intersecting pair is a
//               contact from outside (closed, consistently oriented meshes only; see below).
//  COLLISION    some pair of triangles crosses, or one closed mesh lies inside the other, or open
//               meshes (whose inside is undefined) have any intersecting pair.
//  INCONCLUSIVE the decision rests on zero-area triangles; a gate must treat it as a denial.
//
// An intersecting pair (a from A, b from B) is a contact from outside when a's corners all lie on
// the closed outer side of b's plane, or b's on the outer side of a's, or the two are coplanar with
// opposite normals, or they meet in a single point; any other intersecting pair crosses.
#pragma once

#include "kernel/mesh_collision.h"
#include "kernel/mesh_distance.h"

#include <string>

namespace gk {

enum class Verdict { kClear, kTouching, kCollision, kInconclusive };

const char* to_string(Verdict v);

struct VerdictOptions {
  double contact_tolerance_mm = tolerances::kContactMm;
  std::size_t max_contacts = 10000;  // contacts reported at most
};

struct VerdictResult {
  Verdict verdict = Verdict::kInconclusive;
  std::string reason;
  double distance_mm = 0.0;  // minimum distance; 0 when in contact
  Vec3 point_a = Vec3::Zero();
  Vec3 point_b = Vec3::Zero();
  std::vector<Contact> contacts;
  std::size_t crossing_pairs = 0;
  QueryStats stats;
};

Result<VerdictResult> assess(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                             const RigidTransform& pose_b, const VerdictOptions& options = {});

// Generalised winding number of a closed mesh around a point in the mesh's frame (about 1 inside,
// 0 outside). O(triangles).
double winding_number(const TriangleMesh& mesh, const Vec3& point);

}  // namespace gk
