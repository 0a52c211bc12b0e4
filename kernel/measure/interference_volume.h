// The volume two closed meshes share, by ray casting: vertical rays on a grid over the overlap of
// their boxes; along each ray the intervals inside A and inside B (from the sorted crossings of
// each closed surface) are intersected and their length summed.
//
// The error is bounded, not estimated: in a cell that no triangle edge crosses (projected on the
// grid's plane) the overlap length is linear, so the centre ray gives the cell's volume exactly; a
// cell crossed by an edge can err by at most its area times the overlap's height. A grid with few
// rays inside the overlap (a corner, a sliver) is refined, up to about a million rays, until the
// bound is within 1 % of the volume. Where it stays looser (finely tessellated parts: edges
// everywhere; overlaps thinner than any grid), the exact corefinement
// (kernel/measure/exact_interference_volume.h) replaces the figure when the meshes allow it. Exact B-Rep
// volumes come from occt_adapters (Boolean common).
#pragma once

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "kernel/core/stop_token.h"

#include <string>

namespace gk {

enum class VolumeMethod {
  kRayCast,            // the grid's figure, within error_bound_mm3
  kExactCorefinement,  // exact rationals; error_bound_mm3 is the final rounding to double
};

struct VolumeEstimate {
  VolumeMethod method = VolumeMethod::kRayCast;
  double volume_mm3 = 0.0;
  double error_bound_mm3 = 0.0;  // |volume_mm3 - true shared volume| <= this
  double cell_mm = 0.0;   // grid spacing used (the larger of the two cell sides); 0 when exact
  int rays = 0;             // rays through both meshes' boxes
  int rays_in_overlap = 0;  // ... with a non-zero overlap length
  // Why the exact fallback did not replace a ray-cast figure looser than 1 % (empty when it was
  // not needed or did run).
  std::string exact_not_used;
};

// Both meshes must be closed and consistently oriented; cells_per_axis in [4, 4096]: the first grid.
// Asks `stop` between rows of rays: kStopped when it says so.
Result<VolumeEstimate> interference_volume(const MeshBvh& a, const RigidTransform& pose_a, const MeshBvh& b,
                                           const RigidTransform& pose_b, int cells_per_axis = 256, const StopToken& stop = {});

// How far a volume measured on a tessellation can be from the volume on the exact surface it
// approximates, within `region` (world): the tessellation is taken to lie within band_mm of the
// surface and the surface within band_mm of it (a CAD part's deflection), so what lies between
// them is within band_mm of the triangles that reach the region. Per triangle that neighbourhood
// holds at most 2 A d + (pi / 2) P d^2 + (4 / 3) pi d^3 (Steiner's formula for a flat convex set
// of area A and perimeter P) [mm^3].
double tessellation_band_volume(const TriangleMesh& mesh, const RigidTransform& pose, double band_mm, const Aabb& region);

}  // namespace gk
