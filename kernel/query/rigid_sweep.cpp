#include "kernel/query/rigid_sweep.h"

#include "kernel/query/mesh_distance.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace gk {

namespace {

// The screw motion taking `from` to `to`: the turn (unit axis w, angle in [0, pi]) and the parts of
// the origin's displacement along the axis and across it.
struct Screw {
  Vec3 axis = Vec3::UnitZ();
  double angle = 0.0;
  Vec3 along = Vec3::Zero(), across = Vec3::Zero();
};

Screw screw_of(const RigidTransform& from, const RigidTransform& to) {
  const Eigen::AngleAxisd turn(to.rotation * from.rotation.transpose());
  Screw out;
  out.angle = turn.angle();
  const Vec3 d = to.translation - from.translation;
  if (out.angle > 0.0) out.axis = turn.axis();
  out.along = out.axis * out.axis.dot(d);
  out.across = d - out.along;
  return out;
}

}  // namespace

RigidTransform pose_between(const RigidTransform& from, const RigidTransform& to, double s) {
  const Screw w = screw_of(from, to);
  RigidTransform out;
  const double phi = s * w.angle;
  const Eigen::AngleAxisd part(phi, w.axis);
  out.rotation = part.toRotationMatrix() * from.rotation;
  if (w.angle == 0.0) {
    out.translation = from.translation + s * (to.translation - from.translation);
    return out;
  }
  // The origin turns by phi about the screw axis, which passes through c (across it from the
  // origin's start) with (I - R(angle)) c = across (relative to the start): its displacement across
  // the axis is (I - R(phi)) c = (a across + b w x across) / 2, written without cot(angle / 2) so
  // that small angles lose nothing (a -> 2s, b -> 0).
  const double half = 0.5 * w.angle, sin_half = std::sin(half), sin_half_phi = std::sin(0.5 * phi);
  const double a = 2.0 * sin_half_phi * sin_half_phi + std::cos(half) * std::sin(phi) / sin_half;
  const double b = 2.0 * std::cos(half) * sin_half_phi * sin_half_phi / sin_half - std::sin(phi);
  out.translation = from.translation + 0.5 * (a * w.across + b * w.axis.cross(w.across)) + s * w.along;
  return out;
}

MotionBound motion_bound(const MeshBvh& moving, const RigidTransform& from, const RigidTransform& to) {
  const Screw w = screw_of(from, to);
  MotionBound b;
  b.angle_rad = w.angle;
  // Measured from the centre of the mesh's box, not its origin: a mesh written at factory
  // coordinates has its origin 1e7 mm away, and a turn of 1e-3 rad would otherwise bound its
  // points' speed by 1e4 mm per frame.
  const Aabb box = moving.root_bounds();
  const Vec3 centre = 0.5 * (box.min + box.max);
  b.reach_mm = 0.5 * (box.max - box.min).norm();
  // The centre's path: an arc of angle theta across the axis whose chord is the across part of its
  // displacement (radius chord / (2 sin(theta / 2))), and the along part along it.
  const Vec3 moved = to.apply(centre) - from.apply(centre);
  const Vec3 along = w.axis * w.axis.dot(moved);
  const double chord = (moved - along).norm(), half = 0.5 * w.angle;
  const double arc = half > 0.0 ? chord * half / std::sin(half) : chord;
  b.travel_mm = std::hypot(arc, along.norm());
  // A point's distance from the axis is at most the centre's plus the reach: its arc's sagitta is
  // at most (radius) (1 - cos(theta / 2)); the centre's radius times that is chord tan(theta / 4) / 2.
  b.sagitta_mm = 0.5 * chord * std::tan(0.25 * w.angle) + b.reach_mm * (1.0 - std::cos(half));
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
    if (out.steps >= max_steps) {
      out.exhausted = true;
      return out;
    }
    if (stop && stop->stop_requested()) return stopped("the sweep between two poses");
    ++out.steps;
    DistanceRequest request;
    request.upper_bound_mm = rate * (1.0 - s) + contact_mm;  // farther than the rest of the motion can go: no contact
    request.stop = stop;
    auto d = distance(moving, pose_between(from, to, s), fixed, fixed_pose, request);
    if (!d.ok()) return d.error();
    out.stats += d.value().stats;
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
