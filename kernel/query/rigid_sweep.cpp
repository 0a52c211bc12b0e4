#include "kernel/query/rigid_sweep.h"

#include "kernel/query/mesh_distance.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace gk {

RigidTransform pose_between(const RigidTransform& from, const RigidTransform& to, double s) {
  const Eigen::AngleAxisd turn(to.rotation * from.rotation.transpose());
  RigidTransform out;
  out.rotation = Eigen::AngleAxisd(s * turn.angle(), turn.axis()).toRotationMatrix() * from.rotation;
  out.translation = from.translation + s * (to.translation - from.translation);
  return out;
}

MotionBound motion_bound(const MeshBvh& moving, const RigidTransform& from, const RigidTransform& to) {
  MotionBound b;
  b.travel_mm = (to.translation - from.translation).norm();
  b.angle_rad = Eigen::AngleAxisd(to.rotation * from.rotation.transpose()).angle();
  const Aabb box = moving.root_bounds();
  for (int k = 0; k < 8; ++k) {
    const Vec3 corner((k & 1) ? box.max.x() : box.min.x(), (k & 2) ? box.max.y() : box.min.y(), (k & 4) ? box.max.z() : box.min.z());
    b.reach_mm = std::max(b.reach_mm, corner.norm());
  }
  return b;
}

Result<SweepContact> first_contact_along(const MeshBvh& moving, const RigidTransform& from, const RigidTransform& to,
                                         const MeshBvh& fixed, const RigidTransform& fixed_pose, double contact_mm,
                                         int max_steps, const StopToken* stop) {
  if (!(contact_mm > 0.0) || !std::isfinite(contact_mm)) return invalid_argument("contact_mm", "must be a positive distance");
  // Rounded up a little: the bound must not be below the true rate.
  const double rate = motion_bound(moving, from, to).rate() * (1.0 + 1e-12);

  SweepContact out;
  double s = 0.0;
  while (true) {
    if (out.steps >= max_steps)
      return Error{ErrorCode::kResourceExhausted, "motion",
                   "the motion grazes the other mesh all along: no first contact decided in " + std::to_string(max_steps) + " steps"};
    if (stop && stop->stop_requested()) return stopped("the sweep between two poses");
    ++out.steps;
    DistanceRequest request;
    request.upper_bound_mm = rate * (1.0 - s) + contact_mm;  // farther than the rest of the motion can go: no contact
    request.stop = stop;
    auto d = distance(moving, pose_between(from, to, s), fixed, fixed_pose, request);
    if (!d.ok()) return d.error();
    out.stats.node_pairs_tested += d.value().stats.node_pairs_tested;
    out.stats.triangle_pairs_tested += d.value().stats.triangle_pairs_tested;
    if (!d.value().found) return out;
    out.distance_mm = d.value().distance_mm;
    if (out.distance_mm <= contact_mm) {
      out.found = true;
      out.point = d.value().point_a;
      out.s = s;
      return out;
    }
    if (!(rate > 0.0)) return out;  // not moving, and apart
    // Advance so that the meshes stay at least half the contact distance apart.
    s += (out.distance_mm - 0.5 * contact_mm) / rate;
    if (s >= 1.0) return out;
  }
}

}  // namespace gk
