#include "kernel/query/point_containment.h"

#include "kernel/internal/bvh_ray.h"
#include "kernel/predicates/exact_predicates.h"
#include "kernel/core/tolerances.h"

#include <array>
#include <cmath>
#include <limits>

namespace gk {
namespace {

// Sideways tilts of the exit direction: no special relation to axis-aligned or symmetric meshes.
const std::array<Vec3, 6> kTilts = {Vec3(0.0130895, 0.0071234, 0), Vec3(-0.0093121, 0.0152367, 0),
                                    Vec3(0.0213411, -0.0117718, 0), Vec3(-0.0311323, -0.0207145, 0),
                                    Vec3(0.0471271, 0.0392233, 0), Vec3(-0.0618821, 0.0512289, 0)};

using exact::orient3d;

// Crossings of segment p-q with the mesh; nullopt when some test was degenerate.
std::optional<int> crossings(const MeshBvh& mesh, const Vec3& p, const Vec3& q, double slack) {
  int count = 0;
  bool degenerate = false;
  for_each_leaf_along(mesh, p, q - p, 0.0, 1.0, slack, [&](int first, int last) {
    for (int k = first; k <= last; ++k) {
      if (mesh.ordered_is_degenerate(k)) continue;  // zero area: no side to cross
      const Triangle t = mesh.ordered_triangle(k);
      const int sp = orient3d(t[0], t[1], t[2], p), sq = orient3d(t[0], t[1], t[2], q);
      if (sp == 0) {
        // The start lies in this triangle's plane: degenerate only if it is on the triangle.
        const int e0 = orient3d(p, q, t[0], t[1]), e1 = orient3d(p, q, t[1], t[2]), e2 = orient3d(p, q, t[2], t[0]);
        if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) return !(degenerate = true);
        continue;
      }
      if (sq == 0) return !(degenerate = true);  // the far end cannot be on the mesh; be safe
      if (sp == sq) continue;
      const int e0 = orient3d(p, q, t[0], t[1]), e1 = orient3d(p, q, t[1], t[2]), e2 = orient3d(p, q, t[2], t[0]);
      if (e0 == 0 || e1 == 0 || e2 == 0) {
        if ((e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0)) return !(degenerate = true);  // through an edge or vertex
        continue;
      }
      if (e0 == e1 && e1 == e2) ++count;
    }
    return true;
  });
  if (degenerate) return std::nullopt;
  return count;
}

}  // namespace

std::optional<bool> point_inside(const MeshBvh& mesh, const Vec3& point) {
  const Aabb box = mesh.root_bounds();
  if (!box.expanded(tolerances::kComparisonSlackRelative * (1.0 + box.max.cwiseAbs().maxCoeff())).overlaps(Aabb{point, point})) return false;
  // Leave through the nearest face of the box: the shortest segment meets the fewest nodes.
  int axis = 0;
  double exit = std::numeric_limits<double>::infinity(), toward = 1.0;
  for (int k = 0; k < 3; ++k) {
    if (box.max[k] - point[k] < exit) exit = box.max[k] - point[k], axis = k, toward = 1.0;
    if (point[k] - box.min[k] < exit) exit = point[k] - box.min[k], axis = k, toward = -1.0;
  }
  const double scale = 1.0 + std::max(box.max.cwiseAbs().maxCoeff(), box.min.cwiseAbs().maxCoeff());
  const double slack = tolerances::kComparisonSlackRelative * scale;
  for (const Vec3& tilt : kTilts) {
    Vec3 d = Vec3::Zero();
    d[axis] = toward;
    d[(axis + 1) % 3] = tilt.x();
    d[(axis + 2) % 3] = tilt.y();
    const double length = (std::max(exit, 0.0) + 1e-6 * scale + 1.0);
    const auto n = crossings(mesh, point, point + length * d, slack);
    if (n) return (*n % 2) == 1;
  }
  return std::nullopt;
}

}  // namespace gk
