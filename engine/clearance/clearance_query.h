// ClearanceQuery: the certified distance, the places closer than the safety gap, and for
// interpenetrating parts the depth and the shared volume, between two uploaded parts at poses or
// two scene objects. The geometry is the kernel's; CAD parts are refined on their exact faces
// (engine/verdicts/pair_verdict).
#pragma once

#include "kernel/core/direction.h"
#include "engine/verdicts/contact_place.h"
#include "engine/parts/part_registry.h"
#include "engine/scenes/scene_store.h"
#include "kernel/core/aabb.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/core/stop_token.h"

#include <cstdint>
#include <string>
#include <optional>
#include <vector>

namespace gk::engine {

// One side: an uploaded part at a pose, or (object_id set) a scene object, its part at its pose.
struct ClearanceSide {
  std::string part_id;
  StoredPose pose;  // checked here (engine::checked_pose)
  std::string scene_id, object_id;
};

struct ClearanceRequest {
  ClearanceSide a, b;
  double safety_gap_mm = 0.0;     // places closer than this are reported [0, 1e7]
  double region_merge_mm = 0.0;   // close pairs this near each other form one region (0: 10 mm)
  bool compute_depth = false;     // interpenetrating parts: the penetration depth...
  Vec3 depth_along = Vec3::Zero();  // ...along this direction (zero: the smallest found)
  bool compute_volume = false;    // touching or interpenetrating parts: the shared volume
};

// How the penetration depth was found.
enum class DepthMethod {
  kNone,                   // not computed
  kAlongRequested,         // along the requested direction
  kPieceOrPartAxis,        // a separating axis of the convex pieces or of the parts
  kLatticeDirection,       // one of the lattice's directions
  kBetweenCentres,         // the tessellations were free: along the centres' line, checked on the exact faces
};

// How the shared volume was measured.
enum class SharedVolumeMethod {
  kNone,                   // not computed
  kApart,                  // CLEAR: nothing shared
  kBrepBooleanCommon,      // OCCT's Boolean common of two CAD parts
  kMeshExactCorefinement,  // CGAL's corefinement in rational arithmetic
  kMeshRayCast,            // a ray-cast grid with a proven bound
};

// Figures that were not computed keep these defaults; a measure asked for and not certified is
// -1 with the reason in not_computed.
struct ClearanceResult {
  Verdict verdict = Verdict::kInconclusive;
  InconclusiveReason inconclusive_reason = InconclusiveReason::kNone;
  std::string reason;
  double distance_mm = 0.0;
  Vec3 point_a = Vec3::Zero(), point_b = Vec3::Zero();
  std::uint32_t triangle_a = 0, triangle_b = 0;  // of the first contact (when there is one)
  std::uint32_t face_a = 0, face_b = 0;          // 1-based B-Rep faces of the witnesses (0: none)
  bool refined_on_brep = false;                  // decided on the exact faces
  double exact_faces_us = 0.0;
  double error_bound_mm = 0.0;                   // |distance_mm - true distance| <= this
  std::uint32_t pairs_within_gap = 0;
  bool pairs_truncated = false;
  std::vector<ContactPlace> regions;  // the pairs closer than the gap, grouped
  bool gap_violated = false;
  // Depth (COLLISION, on request): B moved by depth_mm along depth_direction is free.
  double depth_mm = 0.0;
  std::optional<Direction> depth_direction;
  bool depth_exact = false;
  DepthMethod depth_method_kind = DepthMethod::kNone;
  std::string depth_method;  // the same in words, with what it took
  double depth_max_angle_deg = 0.0;
  std::uint32_t depth_pieces_a = 0, depth_pieces_b = 0;
  // Shared volume (on request): |interference_volume_mm3 - true| <= volume_error_bound_mm3.
  double interference_volume_mm3 = 0.0;
  double volume_error_bound_mm3 = 0.0;
  double volume_cell_mm = 0.0;
  SharedVolumeMethod volume_method_kind = SharedVolumeMethod::kNone;
  std::string volume_method;  // the same in words, with why a better one was not used
  std::string not_computed;  // why a requested measure is absent
  double elapsed_us = 0.0;
};

// Long parts (depth, volume) ask `stop` as they go; a stopped query returns kStopped.
Result<ClearanceResult> clearance_query(const ClearanceRequest& request, PartRegistry& parts, SceneStore& scenes,
                                        const StopToken& stop = {});

}  // namespace gk::engine
