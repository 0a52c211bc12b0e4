#include "tests/support/near_contact_poses.h"

#include "kernel/query/mesh_distance.h"
#include "tests/support/random_meshes.h"

#include <random>

namespace gk::testing {

std::vector<RigidTransform> near_contact_poses(const MeshBvh& a, const MeshBvh& b, unsigned seed, int count) {
  Rng rng(seed);
  std::uniform_real_distribution<double> gap(-1.0, 3.0);
  std::vector<RigidTransform> poses;
  const Vec3 ca = a.root_bounds().center();
  const Vec3 cb = b.root_bounds().center();
  const double reach = a.root_bounds().diagonal().norm() + b.root_bounds().diagonal().norm();
  while (static_cast<int>(poses.size()) < count) {
    RigidTransform pose = random_pose(rng, 0.0);
    const Vec3 dir = Vec3::Random().normalized();
    pose.translation = ca + dir * reach - pose.rotation * cb;
    const auto d = distance(a, RigidTransform{}, b, pose).value();
    const Vec3 u = (d.point_b - d.point_a).normalized();
    pose.translation -= (d.distance_mm - gap(rng)) * u;
    poses.push_back(pose);
  }
  return poses;
}

}  // namespace gk::testing
