#include "engine/clearance/clearance_query.h"

#include "engine/input_checks.h"

#include "engine/verdicts/exact_depth.h"
#include "engine/verdicts/number_text.h"
#include "engine/verdicts/pair_verdict.h"
#include "kernel/measure/contact_regions.h"
#include "kernel/query/contact_verdict.h"
#include "kernel/measure/interference_volume.h"
#include "kernel/query/mesh_distance.h"
#include "kernel/measure/penetration_depth.h"
#include "kernel/core/tolerances.h"
#include "occt_adapters/brep_contact.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <set>

namespace gk::engine {
namespace {

constexpr std::size_t kMaxReportedPairs = 100000;
// Depth: lattice size (the resolution is tolerances::kClearanceDepthResolutionMm).
constexpr int kDepthLatticeDirections = 162;
// How long the search over directions may run before the best found so far is reported [us].
constexpr double kDepthBudgetUs = 2.0e6;
constexpr int kVolumeRaysPerAxis = 256;

struct PosedSide {
  std::shared_ptr<const LoadedPart> part;
  RigidTransform pose;
  bool is_cad() const { return !part->shape.is_null(); }
};

// A side is an uploaded part at a pose, or a scene object (its part at its pose).
Result<PosedSide> resolve(const ClearanceSide& in, const std::string& side, PartRegistry& parts, SceneStore& scenes) {
  std::string part_id = in.part_id;
  if (!in.object_id.empty() && !in.part_id.empty())
    return invalid_argument(side + ".part_id", "give a part at a pose or a scene object (scene_id, object_id), not both");
  RigidTransform pose;
  if (in.object_id.empty()) {
    auto checked = checked_pose(in.pose.translation, in.pose.axis, in.pose.angle_deg, side + ".pose");
    if (!checked.ok()) return checked.error();
    pose = checked.value().transform();
  }
  if (!in.object_id.empty()) {
    auto scene = scenes.get(in.scene_id);
    if (!scene.ok()) return Error{scene.error().code, side + ".scene_id", scene.error().message};
    auto it = scene.value().objects.find(in.object_id);
    if (it == scene.value().objects.end()) return Error{ErrorCode::kNotFound, side + ".object_id", "no object '" + in.object_id + "'"};
    part_id = it->second.part_id;
    pose = it->second.pose.transform();
  }
  auto loaded = parts.load(part_id, kPartDeflectionMm);
  if (!loaded.ok()) return Error{loaded.error().code, side + ".part_id", loaded.error().message};
  return PosedSide{loaded.value(), pose};
}

void add_regions(const std::vector<ProximityPair>& pairs, double merge_mm, const PosedSide& a, const PosedSide& b,
                 ClearanceResult& result) {
  for (const ContactRegion& r : group_into_regions(pairs, merge_mm)) {
    ContactPlace out = place_of(r);
    std::set<int> faces_a, faces_b;
    for (const ProximityPair& p : r.pairs) {
      if (a.is_cad()) faces_a.insert(a.part->face_of_triangle[p.triangle_a]);
      if (b.is_cad()) faces_b.insert(b.part->face_of_triangle[p.triangle_b]);
    }
    out.faces_a.assign(faces_a.begin(), faces_a.end());
    out.faces_b.assign(faces_b.begin(), faces_b.end());
    result.regions.push_back(std::move(out));
  }
}

// The depth on the triangles, then (CAD parts) checked free on the exact faces.
std::string add_depth(const PosedSide& a, const PosedSide& b, const Vec3& along, const StopToken& stop,
                      ClearanceResult& result) {
  const PosedPart pa{a.part.get(), a.pose}, pb_{b.part.get(), b.pose};
  double depth = 0.0;
  Vec3 direction = Vec3::Zero();
  std::string method;
  DepthMethod kind = DepthMethod::kNone;
  bool exact = false;
  if (along != Vec3::Zero()) {
    auto d = penetration_along(*a.part->bvh, a.pose, *b.part->bvh, b.pose, along, tolerances::kClearanceDepthResolutionMm, stop);
    if (!d.ok()) return "depth: " + d.error().to_string() + "; ";
    depth = d.value().depth_mm;
    direction = along.normalized();
    method = "along the requested direction";
    kind = DepthMethod::kAlongRequested;
  } else {
    // The directions are tried within a time budget (or until the caller gives up): every one
    // tried gives a freeing depth, so the best so far is still a certified upper bound.
    const auto started = std::chrono::steady_clock::now();
    const StopToken budget([&] { return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - started).count() > kDepthBudgetUs; });
    auto found = penetration_vector(*a.part->bvh, a.pose, *b.part->bvh, b.pose, kDepthLatticeDirections, tolerances::kClearanceDepthResolutionMm,
                                    stop, budget);
    if (!found.ok()) return "depth: " + found.error().to_string() + "; ";
    const DepthVector& d = found.value();
    depth = d.depth_mm;
    direction = d.direction;
    exact = d.exact;
    method = d.from_piece_axis ? "convex-piece or part axis" : "lattice direction";
    kind = d.from_piece_axis ? DepthMethod::kPieceOrPartAxis : DepthMethod::kLatticeDirection;
    if (d.stopped_early)
      method += " (time budget: " + std::to_string(d.directions_tried) + " directions tried)";
    result.depth_max_angle_deg = d.max_angle_between_samples_deg;
    result.depth_pieces_a = static_cast<std::uint32_t>(d.pieces_a);
    result.depth_pieces_b = static_cast<std::uint32_t>(d.pieces_b);
  }
  if (!(direction.norm() > 0.0) || (along == Vec3::Zero() && depth == 0.0)) {
    // The tessellations are already free (the exact solids overlap by less than the deflections):
    // B is moved apart along the line between the parts' centres, checked on the exact faces.
    direction = transformed_box(b.part->mesh->bounds(), b.pose).center() - transformed_box(a.part->mesh->bounds(), a.pose).center();
    if (!(direction.norm() > 0.0)) direction = Vec3::UnitZ();
    direction.normalize();
    method = "between the parts' centres";
    kind = DepthMethod::kBetweenCentres;
  }
  auto checked = check_depth_on_brep(pa, pb_, direction, depth, stop);
  if (!checked.ok()) return "depth: " + checked.error().message + "; ";
  if (deflection_window(pa, pb_) > 0.0) {
    exact = false;  // found on a tessellation, not on the parts
    method += "; checked clear on the exact faces" +
                (checked.value().added_mm > 0.0 ? " after adding " + number_text(checked.value().added_mm) + " mm" : std::string());
  }
  result.depth_direction = Direction::of(direction);
  result.depth_mm = checked.value().depth_mm;
  result.depth_exact = exact;
  result.depth_method = method;
  result.depth_method_kind = kind;
  return "";
}

// Where the two parts' boxes overlap (world).
Aabb overlap_box(const PosedSide& a, const PosedSide& b) {
  const Aabb ba = transformed_box(a.part->mesh->bounds(), a.pose), bb = transformed_box(b.part->mesh->bounds(), b.pose);
  return {ba.min.cwiseMax(bb.min), ba.max.cwiseMin(bb.max)};
}

std::string add_volume(const PosedSide& a, const PosedSide& b, const Vec3& near_point, const StopToken& stop,
                       ClearanceResult& result) {
  std::string why_not_brep;
  if (a.is_cad() && b.is_cad()) {
    // In a frame local to the overlap: OCCT's Booleans lose overlaps at factory coordinates.
    auto exact = occt::shared_volume(a.part->shape, a.pose, b.part->shape, b.pose, near_point, /*bound_error=*/true);
    if (exact.ok() && exact.value().volume_mm3 <= tolerances::kBrepOverlapVolumeMm3) {
      // The verdict found them crossing, but the common holds (almost) nothing: a lens too small
      // for OCCT's Boolean to build. No figure rather than a 0 that reads as exact.
      result.interference_volume_mm3 = -1.0;
      return "volume: the Boolean common lost the overlap (" + number_text(exact.value().volume_mm3) +
             " mm^3: a crossing of micrometres); ";
    }
    if (exact.ok()) {
      result.interference_volume_mm3 = exact.value().volume_mm3;
      result.volume_error_bound_mm3 = exact.value().error_bound_mm3;
      result.volume_cell_mm = 0.0;
      result.volume_method = "brep boolean common";
      result.volume_method_kind = SharedVolumeMethod::kBrepBooleanCommon;
      return "";
    }
    why_not_brep = " (the Boolean common failed: " + exact.error().message + ")";
  }
  auto volume = interference_volume(*a.part->bvh, a.pose, *b.part->bvh, b.pose, kVolumeRaysPerAxis, stop);
  if (!volume.ok()) {
    result.interference_volume_mm3 = -1.0;
    return "volume: " + volume.error().to_string() + why_not_brep;
  }
  // A CAD part measured on its tessellation: the figure is the triangles', the bound covers the
  // band between them and the exact faces.
  const Aabb region = overlap_box(a, b);
  const double band = tessellation_band_volume(*a.part->mesh, a.pose, a.part->deflection_mm, region) +
                      tessellation_band_volume(*b.part->mesh, b.pose, b.part->deflection_mm, region);
  const std::string on_tessellation = band > 0.0 ? " on the CAD part's tessellation (the bound includes its deflection)" : "";
  result.interference_volume_mm3 = volume.value().volume_mm3;
  result.volume_error_bound_mm3 = volume.value().error_bound_mm3 + band;
  result.volume_cell_mm = volume.value().cell_mm;
  result.volume_method_kind = volume.value().method == VolumeMethod::kExactCorefinement ? SharedVolumeMethod::kMeshExactCorefinement
                                                                                       : SharedVolumeMethod::kMeshRayCast;
  if (volume.value().method == VolumeMethod::kExactCorefinement)
    result.volume_method = "mesh exact corefinement" + on_tessellation + why_not_brep;
  else if (!volume.value().exact_not_used.empty())
    result.volume_method = "mesh ray cast" + on_tessellation + " (not exact: " + volume.value().exact_not_used + ")" +
                                why_not_brep;
  else
    result.volume_method = "mesh ray cast" + on_tessellation + why_not_brep;
  return "";
}

}  // namespace

Result<ClearanceResult> clearance_query(const ClearanceRequest& request, PartRegistry& parts, SceneStore& scenes,
                                        const StopToken& stop) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!std::isfinite(request.safety_gap_mm) || request.safety_gap_mm < 0.0 || request.safety_gap_mm > tolerances::kMaxCoordinateMm)
    return invalid_argument("safety_gap_mm", "must be a distance from 0 to 1e7 mm");
  if (!std::isfinite(request.region_merge_mm) || request.region_merge_mm < 0.0)
    return invalid_argument("region_merge_mm", "must be a finite, non-negative distance");
  if (!request.depth_along.allFinite()) return invalid_argument("depth_along", "must be finite");
  auto ra = resolve(request.a, "a", parts, scenes);
  if (!ra.ok()) return ra.error();
  auto rb = resolve(request.b, "b", parts, scenes);
  if (!rb.ok()) return rb.error();
  const PosedSide& a = ra.value();
  const PosedSide& b = rb.value();
  PairVerdictOptions options;
  options.clearance_mm = request.safety_gap_mm;
  options.measure_on_brep = true;
  options.mesh.stop = &stop;
  auto decided = decide_pair({a.part.get(), a.pose}, {b.part.get(), b.pose}, options);
  if (!decided.ok()) return decided.error();
  const PairVerdict& pv = decided.value();
  const VerdictResult& v = pv.result;
  ClearanceResult result;
  result.verdict = v.verdict;
  result.inconclusive_reason = v.inconclusive_reason;
  result.reason = v.reason;
  result.distance_mm = v.distance_mm;
  result.point_a = v.point_a;
  result.point_b = v.point_b;
  if (!v.contacts.empty()) {
    result.triangle_a = v.contacts.front().triangle_a;
    result.triangle_b = v.contacts.front().triangle_b;
    if (a.is_cad()) result.face_a = static_cast<std::uint32_t>(a.part->face_of_triangle[v.contacts.front().triangle_a]);
    if (b.is_cad()) result.face_b = static_cast<std::uint32_t>(b.part->face_of_triangle[v.contacts.front().triangle_b]);
  }
  if (pv.face_a > 0) result.face_a = static_cast<std::uint32_t>(pv.face_a);
  if (pv.face_b > 0) result.face_b = static_cast<std::uint32_t>(pv.face_b);
  result.refined_on_brep = pv.decided_on_brep;
  result.exact_faces_us = 1000.0 * pv.brep_ms;
  result.error_bound_mm = pv.error_bound_mm;
  auto near = pairs_within(*a.part->bvh, a.pose, *b.part->bvh, b.pose, request.safety_gap_mm, kMaxReportedPairs, stop);
  if (!near.ok()) return near.error();
  result.pairs_within_gap = static_cast<std::uint32_t>(near.value().pairs.size());
  result.pairs_truncated = near.value().truncated;
  add_regions(near.value().pairs, request.region_merge_mm > 0.0 ? request.region_merge_mm : tolerances::kRegionMergeMm, a, b, result);
  result.gap_violated = v.verdict != Verdict::kClear || v.distance_mm < request.safety_gap_mm;
  const bool interpenetrating = v.verdict == Verdict::kCollision;
  std::string not_computed;
  if (interpenetrating && request.compute_depth) {
    const std::string why = add_depth(a, b, request.depth_along, stop, result);
    if (!why.empty()) result.depth_mm = -1.0;  // no depth certified: never a 0 that reads as "free"
    not_computed += why;
  }
  // Touching parts may still share a sliver (an overlap whose crossing segments are all shorter
  // than the point-contact tolerance): measured, not assumed 0. Apart (CLEAR), they share nothing.
  if (request.compute_volume) {
    if (interpenetrating || v.verdict == Verdict::kTouching) {
      not_computed += add_volume(a, b, v.point_a, stop, result);
    } else if (v.verdict == Verdict::kClear) {
      result.interference_volume_mm3 = 0.0;
      result.volume_error_bound_mm3 = 0.0;
      result.volume_method = "apart: nothing shared";
      result.volume_method_kind = SharedVolumeMethod::kApart;
    } else {
      result.interference_volume_mm3 = -1.0;
      not_computed += "volume: the verdict is INCONCLUSIVE; ";
    }
  }
  // The caller gave up (deadline, cancel): the work stopped where it was, and nobody reads this.
  if (stop.stop_requested()) return stopped("the clearance query");
  result.not_computed = not_computed;
  result.elapsed_us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace gk::engine
