#include "kernel/interference_volume.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace gk {
namespace {


// Parameters t where origin + t * dir crosses the mesh (mesh-local ray), through the BVH.
void crossings(const MeshBvh& m, const Vec3& origin, const Vec3& dir, std::vector<double>& out) {
  out.clear();
  const MeshBvh::NodeView nodes = m.nodes();
  const Vec3 inv(1.0 / dir.x(), 1.0 / dir.y(), 1.0 / dir.z());
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const int n = stack[--top];
    const auto& lo = nodes.min_point[n];
    const auto& hi = nodes.max_point[n];
    double t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
    const double los[3] = {lo.x(), lo.y(), lo.z()}, his[3] = {hi.x(), hi.y(), hi.z()};
    bool miss = false;
    for (int k = 0; k < 3 && !miss; ++k) {
      if (dir[k] == 0.0) {
        miss = origin[k] < los[k] || origin[k] > his[k];
        continue;
      }
      double a = (los[k] - origin[k]) * inv[k], b = (his[k] - origin[k]) * inv[k];
      if (a > b) std::swap(a, b);
      t0 = std::max(t0, a);
      t1 = std::min(t1, b);
      miss = t0 > t1;
    }
    if (miss) continue;
    if (nodes.info[n].x() == 0) {
      stack[top++] = nodes.info[n].y();
      stack[top++] = nodes.info[n].z();
      continue;
    }
    for (int k = nodes.info[n].y(); k <= nodes.info[n].z(); ++k) {
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
  }
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
