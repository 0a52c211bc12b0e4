#include "engine/exact_depth.h"

#include "engine/pair_verdict.h"
#include "kernel/tolerances.h"
#include "occt_adapters/brep_contact.h"

namespace gk::engine {

Result<CheckedDepth> check_depth_on_brep(const PosedPart& a, const PosedPart& b, const Vec3& direction, double depth_mm) {
  CheckedDepth out;
  out.depth_mm = depth_mm;
  const double window = deflection_window(a, b);
  if (window == 0.0) {  // the triangles are the parts: the kernel's depth stands
    out.checked = true;
    return out;
  }
  if (!a.part->is_cad() || !b.part->is_cad()) return out;
  if (!direction.allFinite() || !(direction.norm() > 0.0)) return invalid_argument("direction", "must be a non-zero vector");
  const Vec3 u = direction.normalized();
  const double extra[] = {0.0, 1.0, 2.0, 4.0, 8.0};
  for (int k = 0; k < 5; ++k) {
    const double d = depth_mm + extra[k] * window;
    RigidTransform moved = b.pose;
    moved.translation += d * u;
    const Vec3 origin = 0.5 * (transformed_box(a.part->mesh->bounds(), a.pose).center() +
                               transformed_box(b.part->mesh->bounds(), moved).center());
    auto c = occt::decide_brep_contact(a.part->shape, a.pose, b.part->shape, moved, origin, {}, tolerances::kContactMm,
                                       tolerances::kBrepOverlapVolumeMm3);
    if (!c.ok()) return c.error();
    if (c.value().relation != occt::BrepRelation::kOverlapping) {
      out.depth_mm = d;
      out.checked = true;
      out.extensions = static_cast<int>(extra[k]);
      return out;
    }
  }
  return Error{ErrorCode::kInternal, "depth", "moved by the depth found on the triangles (plus up to 8 deflection windows) the exact solids still overlap"};
}

}  // namespace gk::engine
