// The first contact of a mesh moving between two poses with a static mesh, found by conservative
// advancement: at motion parameter s the exact mesh distance d bounds how far the motion may go
// before anything can touch, because no point of the moving mesh travels faster than the motion's
// rate. Each step keeps the meshes at least half the contact distance apart, so the search never
// steps over a crossing, however thin the static mesh or fast the motion: what checking at the two
// poses alone misses (a hand passing through a 1 mm plate between frames). A motion whose closest
// approach lies between half the contact distance and the contact distance may be stepped over.
//
// The motion between the poses is the screw motion (Chasles): a constant-rate turn about one fixed
// axis in space (the shortest way from the first rotation to the second) with a constant-rate
// slide along it. A part tipped over about an edge it rests on turns about that edge, and that
// edge stays where it is all along (a turn about the part's own origin with its origin moving
// straight would dip the edge into what it rests on). Its rate, in mm per unit s: the length of
// the path of the centre of the mesh's box (a helix arc) + angle × half the box's diagonal.
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "kernel/core/stop_token.h"
#include "kernel/query/mesh_pair_frame.h"

namespace gk {

// The pose at parameter s in [0, 1] of the motion from `from` to `to`.
RigidTransform pose_between(const RigidTransform& from, const RigidTransform& to, double s);

// What bounds how fast the mesh's points move in that motion: the length of the path of its box's
// centre [mm], the angle turned [rad], and the largest distance of a vertex from that centre (half
// the box's diagonal) [mm].
struct MotionBound {
  double travel_mm = 0.0;
  double angle_rad = 0.0;
  double reach_mm = 0.0;
  // How far any point's path strays from the straight line between its two places: the sagitta
  // of its arc about the screw axis. [mm]
  double sagitta_mm = 0.0;
  // No point moves faster than this, in mm per unit s.
  double rate() const { return travel_mm + angle_rad * reach_mm; }
};
MotionBound motion_bound(const MeshBvh& moving, const RigidTransform& from, const RigidTransform& to);

struct SweepContact {
  bool found = false;     // the meshes come within the contact distance somewhere along the motion
  double s = 1.0;         // the first such parameter (found) [0, 1]
  double distance_mm = 0.0;  // their distance there (at most the contact distance when found)
  Vec3 point = Vec3::Zero();  // where they meet (found): the moving mesh's nearest point, world
  int steps = 0;          // distance queries made
  QueryStats stats;       // summed over the queries
  // max_steps queries were made without deciding (a motion grazing the other mesh all along):
  // the caller must treat that as undecided, never as clear.
  bool exhausted = false;
};

// The first parameter where moving (from -> to) is found within contact_mm of fixed (every motion
// that comes within contact_mm / 2 is, see above). More than max_steps queries needed (a motion
// grazing the mesh all along): `exhausted`, with the queries' counts.
Result<SweepContact> first_contact_along(const MeshBvh& moving, const RigidTransform& from, const RigidTransform& to,
                                         const MeshBvh& fixed, const RigidTransform& fixed_pose, double contact_mm,
                                         int max_steps = 20000, const StopToken* stop = nullptr);

}  // namespace gk
