// A penetration depth found on the triangles, checked on the exact faces of CAD parts: the depth
// the kernel certifies frees the tessellations, not necessarily the solids (a part moved by it
// still overlapped the other in 13 of 45 trials). B moved by the reported depth must be free of A
// on the B-Rep (apart or touching, by the exact-face decision of engine/pair_verdict).
#pragma once

#include "engine/part_geometry.h"
#include "kernel/status.h"

namespace gk::engine {

struct CheckedDepth {
  double depth_mm = 0.0;  // B moved by this along the direction is free on the exact faces
  bool checked = false;   // false: a CAD part against a mesh (no Boolean there): depth as found
  int extensions = 0;     // how many deflection windows were added to the triangles' depth
};

// Tries depth, then depth plus 1, 2, 4 and 8 times the pair's deflection window (the sum of both
// deflections). An error when none of them frees the solids (the depth is then not certified).
Result<CheckedDepth> check_depth_on_brep(const PosedPart& a, const PosedPart& b, const Vec3& direction, double depth_mm);

}  // namespace gk::engine
