#include "kernel/measure/interference_volume.h"

#include "kernel/internal/bvh_ray.h"
#include "kernel/measure/exact_interference_volume.h"
#include "kernel/core/units.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace gk {
namespace {

// The grid is refined until the error bound is within this fraction of the volume... [1]
constexpr double kTargetRelativeError = 0.01;
// ...or this many rays are cast... [rays]
constexpr double kMaxRays = 1.1e6;
// ...while fewer than this many rays cross the overlap (beyond, the grid resolves it). [rays]
constexpr int kResolvedRays = 4096;
// The exact fallback runs on meshes of at most this many triangles together: CGAL cannot be
// interrupted, and this keeps it within about a second on one core (docs/PERFORMANCE.md). [triangles]
constexpr std::size_t kMaxExactTriangles = 200000;


// Parameters t where origin + t * dir crosses the mesh (mesh-local ray), through the BVH.
void crossings(const MeshBvh& m, const Vec3& origin, const Vec3& dir, std::vector<double>& out) {
  out.clear();
  const double inf = std::numeric_limits<double>::infinity();
  for_each_leaf_along(m, origin, dir, -inf, inf, 0.0, [&](int first, int last) {
    for (int k = first; k <= last; ++k) {
      // Moller-Trumbore.
      const Triangle tri = m.ordered_triangle(k);
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

// Cells of the grid crossed by the projection (on x, y) of an edge of any triangle that reaches
// into the box: only there can the midpoint rule err. Elsewhere the same triangles are hit across
// the cell, every crossing's height is linear in (x, y), and so is the overlap length: the
// midpoint rule is exact there.
std::vector<char> cells_crossed_by_edges(const MeshBvh& m, const RigidTransform& pose, const Vec3& lo, const Vec3& hi, int n,
                                         double dx, double dy, std::vector<char> marked) {
  const double step = 0.5 * std::min(dx, dy);
  // The cell of a coordinate, clamped in double before it becomes an int: an edge far outside a
  // tiny overlap is billions of cells away.
  auto cell_of = [n](double offset, double size) {
    return static_cast<int>(std::clamp(std::floor(offset / size), -2.0, static_cast<double>(n) + 1.0));
  };
  auto mark_box = [&](double x0, double x1, double y0, double y1) {
    const int i0 = std::max(0, cell_of(x0 - lo.x(), dx) - 1);
    const int i1 = std::min(n - 1, cell_of(x1 - lo.x(), dx) + 1);
    const int j0 = std::max(0, cell_of(y0 - lo.y(), dy) - 1);
    const int j1 = std::min(n - 1, cell_of(y1 - lo.y(), dy) + 1);
    for (int i = i0; i <= i1; ++i)
      for (int j = j0; j <= j1; ++j) marked[static_cast<std::size_t>(i) * n + j] = 1;
  };
  const Aabb box{lo, hi};
  for (std::size_t t = 0; t < m.mesh().triangle_count(); ++t) {
    const Triangle local = m.mesh().triangle(t);
    const Triangle w = {pose.apply(local[0]), pose.apply(local[1]), pose.apply(local[2])};
    Aabb tb;
    for (const Vec3& p : w) tb.extend(p);
    if (!tb.overlaps(box)) continue;
    for (int e = 0; e < 3; ++e) {
      const Vec3& p = w[e];
      const Vec3& q = w[(e + 1) % 3];
      const double len = std::hypot(q.x() - p.x(), q.y() - p.y());
      const double pieces_wanted = std::ceil(len / step);
      if (pieces_wanted > 4.0 * n) {  // an edge much longer than the grid: cover its whole box row by row
        mark_box(std::min(p.x(), q.x()), std::max(p.x(), q.x()), std::min(p.y(), q.y()), std::max(p.y(), q.y()));
        continue;
      }
      const int pieces = std::max(1, static_cast<int>(pieces_wanted));
      for (int k = 0; k < pieces; ++k) {
        const Vec3 a = p + (q - p) * (static_cast<double>(k) / pieces), b = p + (q - p) * (static_cast<double>(k + 1) / pieces);
        mark_box(std::min(a.x(), b.x()), std::max(a.x(), b.x()), std::min(a.y(), b.y()), std::max(a.y(), b.y()));
      }
    }
  }
  return marked;
}

// `stopped` is set (and the estimate left incomplete) when `stop` asks between rows.
VolumeEstimate cast_rays(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b, const RigidTransform& pose_b,
                         const Vec3& lo, const Vec3& hi, int n, const StopToken& stop, bool& stopped_early) {
  VolumeEstimate out;
  const double dx = (hi.x() - lo.x()) / n, dy = (hi.y() - lo.y()) / n;
  out.cell_mm = std::max(dx, dy);
  std::vector<char> edged(static_cast<std::size_t>(n) * n, 0);
  edged = cells_crossed_by_edges(a, pose_a, lo, hi, n, dx, dy, std::move(edged));
  edged = cells_crossed_by_edges(b, pose_b, lo, hi, n, dx, dy, std::move(edged));
  // Rays along world +Z, expressed in each mesh's frame.
  const Vec3 up(0, 0, 1);
  const RigidTransform to_a = pose_a.inverse(), to_b = pose_b.inverse();
  const Vec3 dir_a = to_a.apply_direction(up), dir_b = to_b.apply_direction(up);
  std::vector<double> ta, tb;
  double total = 0.0;
  std::size_t edged_cells = 0;
  for (int i = 0; i < n; ++i) {
    if (stop.stop_requested()) {
      stopped_early = true;
      return out;
    }
    for (int j = 0; j < n; ++j) {
      const bool has_edge = edged[static_cast<std::size_t>(i) * n + j] != 0;
      edged_cells += has_edge ? 1 : 0;
      // Where an edge's projection crosses the cell, a tiny irrational offset keeps the ray off
      // the edges and vertices of meshes laid out on round coordinates (the cell's bound covers
      // any error there); elsewhere the exact centre keeps the midpoint rule exact.
      const double off_x = has_edge ? 1.3e-7 : 0.0, off_y = has_edge ? 2.9e-7 : 0.0;
      const Vec3 start(lo.x() + (i + 0.5 + off_x) * dx, lo.y() + (j + 0.5 + off_y) * dy, lo.z() - 1.0);
      crossings(a, to_a.apply(start), dir_a, ta);
      if (ta.size() < 2) continue;
      crossings(b, to_b.apply(start), dir_b, tb);
      if (tb.size() < 2) continue;
      ++out.rays;
      double length = 0.0;
      for (const auto& x : inside(ta))
        for (const auto& y : inside(tb)) length += std::max(0.0, std::min(x[1], y[1]) - std::max(x[0], y[0]));
      total += length;
      if (length > 0.0) ++out.rays_in_overlap;
    }
  }
  out.volume_mm3 = total * dx * dy;
  // A cell crossed by an edge errs by at most its area times the overlap's height.
  out.error_bound_mm3 = static_cast<double>(edged_cells) * dx * dy * (hi.z() - lo.z());
  return out;
}

}  // namespace

Result<VolumeEstimate> interference_volume(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                           const RigidTransform& pose_b, int cells_per_axis, const StopToken& stop) {
  if (!a.mesh().is_closed_oriented()) return invalid_argument("a", "volume needs a closed, consistently oriented mesh");
  if (!b.mesh().is_closed_oriented()) return invalid_argument("b", "volume needs a closed, consistently oriented mesh");
  // Both methods read "inside" from the triangles: shells crossing each other (two overlapping
  // boxes in one file) or nested the wrong way round would be counted wrongly, by either.
  for (const auto& [mesh, side] : {std::pair<const TriangleMesh*, const char*>{&a.mesh(), "a"}, {&b.mesh(), "b"}}) {
    auto valid = bounds_a_volume(*mesh, side);
    if (!valid.ok()) return valid.error();
    if (!valid.value())
      return Error{ErrorCode::kFailedPrecondition, side,
                   "volume needs a mesh that bounds a volume: its shells intersect themselves or each other, or are "
                   "nested with the wrong orientation"};
  }
  if (cells_per_axis < 4 || cells_per_axis > 4096) return invalid_argument("cells_per_axis", "must be in [4, 4096]");
  if (!pose_a.is_rigid()) return invalid_argument("pose_a", "not a finite rigid transform");
  if (!pose_b.is_rigid()) return invalid_argument("pose_b", "not a finite rigid transform");
  const Aabb ba = transformed_box(a.root_bounds(), pose_a), bb = transformed_box(b.root_bounds(), pose_b);
  const Vec3 lo = ba.min.cwiseMax(bb.min), hi = ba.max.cwiseMin(bb.max);
  if (!((hi - lo).array() > 0.0).all()) return VolumeEstimate{};
  // A grid too coarse for the overlap (few rays inside it: a corner, a sliver) is refined while the
  // bound exceeds 1 % of the volume, up to kMaxRays rays. Where many rays cross the overlap the
  // bound is dominated by the triangle edges' projections and refining buys little.
  bool stopped_early = false;
  VolumeEstimate out = cast_rays(a, pose_a, b, pose_b, lo, hi, cells_per_axis, stop, stopped_early);
  for (int n = cells_per_axis * 2; n <= 4096 && static_cast<double>(n) * n <= kMaxRays && !stopped_early; n *= 2) {
    if (out.error_bound_mm3 <= kTargetRelativeError * out.volume_mm3 || out.rays_in_overlap >= kResolvedRays) break;
    out = cast_rays(a, pose_a, b, pose_b, lo, hi, n, stop, stopped_early);
  }
  if (stopped_early) return stopped("the interference volume");
  if (out.error_bound_mm3 <= kTargetRelativeError * out.volume_mm3) return out;
  const std::size_t triangles = a.mesh().triangle_count() + b.mesh().triangle_count();
  if (triangles > kMaxExactTriangles) {
    out.exact_not_used = "the exact corefinement is limited to " + std::to_string(kMaxExactTriangles) + " triangles (" +
                         std::to_string(triangles) + " here)";
    return out;
  }
  if (stop.stop_requested()) return stopped("the interference volume");
  auto exact = exact_interference_volume(a.mesh(), pose_a, b.mesh(), pose_b, stop);
  if (!exact.ok() && exact.error().code == ErrorCode::kStopped) return exact.error();
  if (!exact.ok()) {
    out.exact_not_used = exact.error().to_string();
    return out;
  }
  out.method = VolumeMethod::kExactCorefinement;
  out.cell_mm = 0.0;
  out.volume_mm3 = exact.value().volume_mm3;
  out.error_bound_mm3 = exact.value().error_bound_mm3;
  return out;
}

double tessellation_band_volume(const TriangleMesh& mesh, const RigidTransform& pose, double band_mm, const Aabb& region) {
  if (!(band_mm > 0.0)) return 0.0;
  const Aabb reach = region.expanded(band_mm);
  double total = 0.0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Triangle local = mesh.triangle(t);
    const Triangle w = {pose.apply(local[0]), pose.apply(local[1]), pose.apply(local[2])};
    Aabb box;
    for (const Vec3& p : w) box.extend(p);
    if (!box.overlaps(reach)) continue;
    const double area = 0.5 * (w[1] - w[0]).cross(w[2] - w[0]).norm();
    const double perimeter = (w[1] - w[0]).norm() + (w[2] - w[1]).norm() + (w[0] - w[2]).norm();
    total += 2.0 * area * band_mm + 0.5 * kPi * perimeter * band_mm * band_mm + 4.0 / 3.0 * kPi * band_mm * band_mm * band_mm;
  }
  // Rounding of the sum: far below the terms; a relative margin covers it.
  return total * (1.0 + 1e-12);
}

}  // namespace gk
