#include "kernel/penetration_depth.h"

#include "kernel/mesh_collision.h"
#include "kernel/mesh_distance.h"

#include <cmath>

namespace gk {
namespace {

constexpr double kPi = 3.14159265358979323846;


}  // namespace

Result<DepthAlong> penetration_along(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                     const RigidTransform& pose_b, const Vec3& direction, double tolerance_mm) {
  if (!direction.allFinite() || !(direction.norm() > 0.0)) return invalid_argument("direction", "must be a non-zero vector");
  if (!(tolerance_mm > 0.0)) return invalid_argument("tolerance_mm", "must be positive");
  const Vec3 u = direction.normalized();
  DepthAlong out;
  // Is B free already? (No surface contact, and for closed meshes neither inside the other: the
  // distance query alone cannot tell containment, so the collide + box test decide it.)
  auto touching = collide(a, pose_a, b, pose_b);
  if (!touching.ok()) return touching.error();
  const Aabb box_a = transformed_box(a.root_bounds(), pose_a), box_b = transformed_box(b.root_bounds(), pose_b);
  if (!touching.value().colliding && !box_a.overlaps(box_b)) return out;
  // A translation along u that surely separates the boxes.
  double lo_a = std::numeric_limits<double>::infinity(), hi_a = -lo_a, lo_b = lo_a, hi_b = -lo_a;
  for (int k = 0; k < 8; ++k) {
    const Vec3 ca((k & 1) ? box_a.max.x() : box_a.min.x(), (k & 2) ? box_a.max.y() : box_a.min.y(), (k & 4) ? box_a.max.z() : box_a.min.z());
    const Vec3 cb((k & 1) ? box_b.max.x() : box_b.min.x(), (k & 2) ? box_b.max.y() : box_b.min.y(), (k & 4) ? box_b.max.z() : box_b.min.z());
    lo_a = std::min(lo_a, u.dot(ca));
    hi_a = std::max(hi_a, u.dot(ca));
    lo_b = std::min(lo_b, u.dot(cb));
    hi_b = std::max(hi_b, u.dot(cb));
  }
  double t = std::max(0.0, hi_a - lo_b) + 1.0;
  // Back along -u by conservative advancement until the surfaces meet.
  for (out.steps = 0; out.steps < 100000; ++out.steps) {
    RigidTransform moved = pose_b;
    moved.translation += t * u;
    auto d = distance(a, pose_a, b, moved);
    if (!d.ok()) return d.error();
    const double gap = d.value().distance_mm;
    if (gap <= tolerance_mm) {
      out.depth_mm = t;
      return out;
    }
    t -= gap;
    if (t <= 0.0) return out;  // back at the start without meeting a surface: B was free
  }
  return Error{ErrorCode::kInternal, "direction", "advancement did not converge"};
}

Result<DepthVector> penetration_vector(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                       const RigidTransform& pose_b, int samples, double tolerance_mm) {
  if (samples < 6 || samples > 100000) return invalid_argument("samples", "must be in [6, 100000]");
  DepthVector best;
  best.depth_mm = std::numeric_limits<double>::infinity();
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < samples; ++i) {
    const double z = 1.0 - 2.0 * (static_cast<double>(i) + 0.5) / samples;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const Vec3 u(r * std::cos(golden * i), r * std::sin(golden * i), z);
    auto d = penetration_along(a, pose_a, b, pose_b, u, tolerance_mm);
    if (!d.ok()) return d.error();
    ++best.directions_tried;
    if (d.value().depth_mm < best.depth_mm) {
      best.depth_mm = d.value().depth_mm;
      best.direction = u;
    }
    if (best.depth_mm == 0.0) break;
  }
  // A Fibonacci lattice of n points leaves every direction within about sqrt(4 pi / n) radians
  // (times a small constant) of a sample.
  best.max_angle_between_samples_deg = 180.0 / kPi * 2.0 * std::sqrt(4.0 * kPi / samples);
  return best;
}

}  // namespace gk
