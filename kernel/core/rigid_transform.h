// A rigid motion x -> R x + t in double precision (R orthonormal, det +1).
#pragma once

#include "kernel/core/aabb.h"
#include "kernel/core/geometry_types.h"
#include "kernel/core/tolerances.h"

#include <cmath>

namespace gk {

struct RigidTransform {
  Mat3 rotation = Mat3::Identity();
  Vec3 translation = Vec3::Zero();

  static RigidTransform identity() { return {}; }
  static RigidTransform from_translation(const Vec3& t) { return {Mat3::Identity(), t}; }
  static RigidTransform from_axis_angle(const Vec3& axis, double angle_rad, const Vec3& t = Vec3::Zero()) {
    return {Eigen::AngleAxisd(angle_rad, axis.normalized()).toRotationMatrix(), t};
  }

  Vec3 apply(const Vec3& p) const { return rotation * p + translation; }
  Vec3 apply_direction(const Vec3& d) const { return rotation * d; }

  // The inverse motion. A rotation within kOrthonormalToRounding of orthonormal (every quaternion-
  // or axis-angle-built one) is inverted by its transpose; one accepted farther from it (written
  // with 9 decimals) by its true inverse: its transpose would put a point 1e7 mm from the origin
  // up to 0.01 mm beside where the pose took it from.
  RigidTransform inverse() const {
    if (rotation == Mat3::Identity()) return {rotation, -translation};
    return inverse_given(off_orthonormality());
  }
  // The same, with off_orthonormality() already at hand.
  RigidTransform inverse_given(double off_orthonormality_value) const {
    const Mat3 r = off_orthonormality_value <= tolerances::kOrthonormalToRounding ? Mat3(rotation.transpose())
                                                                                   : Mat3(rotation.inverse());
    return {r, -(r * translation)};
  }

  // (this * other)(x) = this(other(x)).
  RigidTransform operator*(const RigidTransform& other) const {
    return {rotation * other.rotation, rotation * other.translation + translation};
  }

  bool is_finite() const { return rotation.allFinite() && translation.allFinite(); }

  // How far the rotation is from orthonormal: the largest entry of |R^T R - I| (0 for the
  // identity, checked first: many poses have no rotation).
  double off_orthonormality() const {
    if (rotation == Mat3::Identity()) return 0.0;
    return (rotation.transpose() * rotation - Mat3::Identity()).cwiseAbs().maxCoeff();
  }

  bool is_rigid() const {
    if (!is_finite()) return false;
    if (rotation == Mat3::Identity()) return true;
    return is_rigid_given(off_orthonormality());
  }
  // The same, with off_orthonormality() already at hand (finiteness checked by the caller).
  bool is_rigid_given(double off_orthonormality_value) const {
    return off_orthonormality_value <= tolerances::kRotationOrthonormality && rotation.determinant() > 0.0;
  }
};

// The pose of mesh B expressed in mesh A's frame: queries run in A's frame and touch B's vertices
// only where a leaf pair needs them, never all of them.
inline RigidTransform relative_transform(const RigidTransform& pose_a, const RigidTransform& pose_b) {
  return pose_a.inverse() * pose_b;
}

// The axis-aligned box around a box moved by a pose (its eight corners moved).
inline Aabb transformed_box(const Aabb& local, const RigidTransform& pose) {
  Aabb out;
  for (int k = 0; k < 8; ++k)
    out.extend(pose.apply(Vec3((k & 1) ? local.max.x() : local.min.x(), (k & 2) ? local.max.y() : local.min.y(),
                               (k & 4) ? local.max.z() : local.min.z())));
  return out;
}

}  // namespace gk
