#include "kernel/interference_volume.h"

#include "kernel/bvh_ray.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace gk {
namespace {


// Parameters t where origin + t * dir crosses the mesh (mesh-local ray), through the BVH.
void crossings(const MeshBvh& m, const Vec3& origin, const Vec3& dir, std::vector<double>& out) {
  out.clear();
  const double inf = std::numeric_limits<double>::infinity();
  for_each_leaf_along(m, origin, dir, -inf, inf, 0.0, [&](int first, int last) {
    for (int k = first; k <= last; ++k) {
      // Moller-Trumbore.
      const Triangle& tri = m.ordered_triangle(k);
      const Vec3 e1 = tri[1] - tri[0], e2 = tri[2] - tri[0];
      const Vec3 p = dir.cross(e2);
      const double det = e1.dot(p);
      if (det == 0.0) continue;
      const Vec3 s = origin - tri[0];
      const double u = s.dot(p) / det;
      if (u < 0.0 || u > 1.0) continue;
      const Vec3 q = s.cross(e1);
      const double v = dir.dot(q) / det;
      if (v < 0.0 || u + v > 1.0) continue;
      out.push_back(e2.dot(q) / det);
    }
    return true;
  });
  std::sort(out.begin(), out.end());
}

// Inside intervals of a closed surface along a ray: between crossings 0-1, 2-3, ...
std::vector<std::array<double, 2>> inside(const std::vector<double>& t) {
  std::vector<std::array<double, 2>> out;
  for (std::size_t i = 0; i + 1 < t.size(); i += 2) out.push_back({t[i], t[i + 1]});
  return out;
}

}  // namespace

Result<VolumeEstimate> interference_volume(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                           const RigidTransform& pose_b, int cells_per_axis) {
  if (!a.mesh().is_closed_oriented()) return invalid_argument("a", "volume needs a closed, consistently oriented mesh");
  if (!b.mesh().is_closed_oriented()) return invalid_argument("b", "volume needs a closed, consistently oriented mesh");
  if (cells_per_axis < 4 || cells_per_axis > 4096) return invalid_argument("cells_per_axis", "must be in [4, 4096]");
  if (!pose_a.is_rigid()) return invalid_argument("pose_a", "not a finite rigid transform");
  if (!pose_b.is_rigid()) return invalid_argument("pose_b", "not a finite rigid transform");
  VolumeEstimate out;
  const Aabb ba = transformed_box(a.root_bounds(), pose_a), bb = transformed_box(b.root_bounds(), pose_b);
  const Vec3 lo = ba.min.cwiseMax(bb.min), hi = ba.max.cwiseMin(bb.max);
  if (!((hi - lo).array() > 0.0).all()) return out;
  const double dx = (hi.x() - lo.x()) / cells_per_axis, dy = (hi.y() - lo.y()) / cells_per_axis;
  out.cell_mm = std::max(dx, dy);
  // Rays along world +Z, expressed in each mesh's frame. A tiny irrational offset keeps the rays
  // off the edges and vertices of meshes laid out on round coordinates.
  const Vec3 up(0, 0, 1);
  const RigidTransform to_a = pose_a.inverse(), to_b = pose_b.inverse();
  const Vec3 dir_a = to_a.apply_direction(up), dir_b = to_b.apply_direction(up);
  std::vector<double> ta, tb;
  double total = 0.0;
  for (int i = 0; i < cells_per_axis; ++i) {
    for (int j = 0; j < cells_per_axis; ++j) {
      const Vec3 start(lo.x() + (i + 0.5 + 1.3e-7) * dx, lo.y() + (j + 0.5 + 2.9e-7) * dy, lo.z() - 1.0);
      crossings(a, to_a.apply(start), dir_a, ta);
      if (ta.size() < 2) continue;
      crossings(b, to_b.apply(start), dir_b, tb);
      if (tb.size() < 2) continue;
      ++out.rays;
      for (const auto& x : inside(ta))
        for (const auto& y : inside(tb)) total += std::max(0.0, std::min(x[1], y[1]) - std::max(x[0], y[0]));
    }
  }
  out.volume_mm3 = total * dx * dy;
  return out;
}

}  // namespace gk
