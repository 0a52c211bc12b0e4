// A penetration depth found on the triangles, checked on the exact faces of CAD parts: the depth
// the kernel certifies frees the tessellations, not necessarily the solids (a part moved by it
// still overlapped the other in 13 of 45 trials). B moved by the reported depth must be CLEAR of A
// by the full exact-face decision of engine/pair_verdict (the same one every verdict uses).
#pragma once

#include "engine/parts/part_geometry.h"
#include "kernel/core/status.h"
#include "kernel/core/stop_token.h"

namespace gk::engine {

struct CheckedDepth {
  double depth_mm = 0.0;  // B moved by this along the direction is clear of A on the exact faces
  bool checked = false;   // true once B moved by depth_mm was found clear (always, on success)
  double added_mm = 0.0;  // what was added to the triangles' depth to free the exact solids
};

// Tries the depth, then the depth plus growing steps (the contact tolerance up to 8 times the
// pair's deflection window, the sum of both deflections); the first at which the exact-face
// verdict is CLEAR is reported — for two CAD parts and for a CAD part against a mesh alike (its
// exact faces against the mesh's triangles: a mesh's tessellation of a sphere lies inside the
// sphere, so freeing it frees the triangles, not the solid). An error when none is (the depth is
// then not certified).
// Asks `stop` between trials.
Result<CheckedDepth> check_depth_on_brep(const PosedPart& a, const PosedPart& b, const Vec3& direction, double depth_mm,
                                         const StopToken& stop = {});

}  // namespace gk::engine
