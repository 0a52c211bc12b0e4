#include "engine/verdicts/exact_depth.h"

#include "engine/verdicts/pair_verdict.h"
#include "kernel/core/tolerances.h"

namespace gk::engine {

Result<CheckedDepth> check_depth_on_brep(const PosedPart& a, const PosedPart& b, const Vec3& direction, double depth_mm,
                                         const StopToken& stop) {
  CheckedDepth out;
  out.depth_mm = depth_mm;
  const double window = deflection_window(a, b);
  if (window == 0.0) {  // the triangles are the parts: the kernel's depth stands
    out.checked = true;
    return out;
  }
  if (!direction.allFinite() || !(direction.norm() > 0.0)) return invalid_argument("direction", "must be a non-zero vector");
  const Vec3 u = direction.normalized();
  // Small steps first: the triangles' depth is usually short of the solids' by much less than the
  // window (the tessellations' chords cut off a sliver of each solid).
  const double extra[] = {0.0, tolerances::kContactMm, 10.0 * tolerances::kContactMm, 0.25 * window, 0.5 * window,
                          window, 2.0 * window, 4.0 * window, 8.0 * window};
  // Decided as ClearanceQuery decides (measured on the exact faces even where the triangles look
  // apart: their nominal deflection is not a bound everywhere, e.g. near a cone's apex).
  PairVerdictOptions options;
  options.measure_on_brep = true;
  for (double e : extra) {
    if (stop.stop_requested()) return stopped("the depth check on the exact faces");
    PosedPart moved = b;
    moved.pose.translation += (depth_mm + e) * u;
    auto v = decide_pair(a, moved, options);
    if (!v.ok()) return v.error();
    if (v.value().result.verdict == Verdict::kClear) {
      out.depth_mm = depth_mm + e;
      out.checked = true;
      out.added_mm = e;
      return out;
    }
  }
  return Error{ErrorCode::kInternal, "depth",
               "moved by the depth found on the triangles (plus up to 8 deflection windows) the exact solids are not clear"};
}

}  // namespace gk::engine
