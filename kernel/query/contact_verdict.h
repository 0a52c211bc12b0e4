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

#include "kernel/query/mesh_collision.h"
#include "kernel/query/mesh_distance.h"

#include <limits>
#include <string>

namespace gk {

enum class Verdict { kClear, kTouching, kCollision, kInconclusive };

const char* to_string(Verdict v);

// Why an answer is INCONCLUSIVE (a denial all the same). Each value is what could not be decided:
enum class InconclusiveReason {
  kNone,
  // The only intersecting triangle pairs involve zero-area triangles: touching or crossing has no
  // meaning there. Repair the mesh.
  kDegenerateTriangles,
  // A CAD part closer to a mesh than its tessellation's deflection: its exact faces were measured
  // against the mesh's triangles there, but they meet, and no point of either was found inside the
  // other. Touching or crossing would need the mesh as a solid B-Rep.
  kTessellationUnresolved,
  // Two CAD parts closer than their tessellations' deflections, and the exact-face decision
  // (OCCT's distance, classifier or Boolean common) failed; the reason text says which.
  kBrepUndecided,
  // The pair could not be computed at all (for example a failed query in an audit): see the text.
  kPairFailed,
  // A motion between two poses keeps within the contact distance of the other part for longer than
  // the check's budget of steps: where it first crosses is not known.
  kSweepBudgetExhausted,
  // More triangle pairs within the contact distance than the check may look at one by one.
  kTooManyContacts,
};
const char* to_string(InconclusiveReason r);

// How much a verdict blocks, for taking the worst of several: CLEAR < TOUCHING < INCONCLUSIVE <
// COLLISION (an inconclusive answer is treated as a denial, but a proven collision is worse).
int severity(Verdict v);

struct VerdictOptions {
  double contact_tolerance_mm = tolerances::kContactMm;
  std::size_t max_contacts = 10000;  // contacts reported at most
  // Distances at or beyond this do not matter to the caller (a clearance): the distance query is
  // pruned there (at twice the contact tolerance at least), and a pair at least that far apart
  // comes back CLEAR with distance_mm set to that bound and distance_is_lower_bound. [mm]
  double distance_upper_bound_mm = std::numeric_limits<double>::infinity();
  // A caller that gave up (deadline, cancel) ends the queries (kStopped); not owned.
  const StopToken* stop = nullptr;
  // A second thread the distance query may finish on (DistanceRequest::spare); not owned.
  SpareThread* spare = nullptr;
};

struct VerdictResult {
  Verdict verdict = Verdict::kInconclusive;
  InconclusiveReason inconclusive_reason = InconclusiveReason::kNone;  // set with kInconclusive
  std::string reason;
  double distance_mm = 0.0;  // minimum distance; 0 when in contact
  bool distance_is_lower_bound = false;  // apart by at least distance_mm (VerdictOptions' bound)
  Vec3 point_a = Vec3::Zero();
  Vec3 point_b = Vec3::Zero();
  std::vector<Contact> contacts;
  std::size_t crossing_pairs = 0;
  int first_crossing = -1;  // index in contacts of the first crossing pair (COLLISION by crossing)
  bool contacts_truncated = false;  // max_contacts was reached: the list is incomplete (the verdict is not)
  // A body lying wholly inside a closed mesh (COLLISION without crossing surfaces): a point of it
  // (world coordinates, also point_a/point_b) and how deep that point lies. [mm]
  bool contained = false;
  Vec3 containment_point = Vec3::Zero();
  double containment_depth_mm = 0.0;
  QueryStats stats;
};

Result<VerdictResult> assess(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                             const RigidTransform& pose_b, const VerdictOptions& options = {});

// Do triangle ta of A and triangle tb of B (mesh indices) cross at these poses, in the sense
// above (intersect, and not as a contact from outside when both meshes are closed and oriented)?
// A dragged object's collision found last frame is usually still there: checking its crossing pair
// first answers COLLISION at the cost of one exact triangle test. `point` gets the crossing's midpoint.
bool triangle_pair_crosses(const MeshBvh& a, const RigidTransform& pose_a, std::uint32_t ta, const MeshBvh& b,
                           const RigidTransform& pose_b, std::uint32_t tb, Vec3* point = nullptr);

// Generalised winding number of a closed mesh around a point in the mesh's frame (about 1 inside,
// 0 outside). O(triangles).
double winding_number(const TriangleMesh& mesh, const Vec3& point);

// Is the point (in the mesh's frame) inside the closed mesh? Ray parity through the BVH, O(log n);
// the winding number (O(n)) when every ray was degenerate, or when the mesh has several bodies
// (they may overlap, an assembly of solids: a point in two of them crosses four surfaces and
// parity calls it outside; the winding number counts each body).
bool inside_closed_mesh(const MeshBvh& mesh, const Vec3& point);

}  // namespace gk
