#include "server/clearance_query.h"

#include "engine/exact_depth.h"
#include "engine/number_text.h"
#include "engine/pair_verdict.h"
#include "kernel/contact_regions.h"
#include "kernel/contact_verdict.h"
#include "kernel/interference_volume.h"
#include "kernel/mesh_distance.h"
#include "kernel/penetration_depth.h"
#include "kernel/tolerances.h"
#include "occt_adapters/brep_contact.h"
#include "server/proto_convert.h"
#include "server/rpc_helpers.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

namespace gk::server {
namespace {

constexpr std::size_t kMaxReportedPairs = 100000;
constexpr double kDefaultRegionMergeMm = 10.0;
// Depth: lattice size and contact resolution [mm] of the advancement along each candidate.
constexpr int kDepthLatticeDirections = 162;
// How long the search over directions may run before the best found so far is reported [us].
constexpr double kDepthBudgetUs = 2.0e6;
constexpr double kDepthResolutionMm = 1e-4;
constexpr int kVolumeRaysPerAxis = 256;

struct PosedSide {
  std::shared_ptr<const LoadedPart> part;
  RigidTransform pose;
  bool is_cad() const { return !part->shape.is_null(); }
};

// A side is an uploaded part at a pose, or a scene object (its part at its pose).
Result<PosedSide> resolve(const pb::PosedPart& in, const std::string& side, PartRegistry& parts, SceneStore& scenes) {
  std::string part_id = in.part_id();
  RigidTransform pose;
  if (!in.object_id().empty()) {
    auto scene = scenes.get(in.scene_id());
    if (!scene.ok()) return Error{scene.error().code, side + ".scene_id", scene.error().message};
    auto it = scene.value().objects.find(in.object_id());
    if (it == scene.value().objects.end()) return Error{ErrorCode::kNotFound, side + ".object_id", "no object '" + in.object_id() + "'"};
    part_id = it->second.part_id;
    pose = it->second.pose.transform();
  } else {
    auto p = to_pose(in.pose(), side + ".pose");
    if (!p.ok()) return p.error();
    pose = p.value();
  }
  auto loaded = parts.load(part_id, kPartDeflectionMm);
  if (!loaded.ok()) return Error{loaded.error().code, side + ".part_id", loaded.error().message};
  return PosedSide{loaded.value(), pose};
}

void add_regions(const std::vector<ProximityPair>& pairs, double merge_mm, const PosedSide& a, const PosedSide& b,
                 pb::ClearanceQueryResponse* response) {
  for (const ContactRegion& r : group_into_regions(pairs, merge_mm)) {
    pb::ContactRegion* out = response->add_regions();
    out->set_min_distance_mm(r.min_distance_mm);
    to_proto(r.point_a, out->mutable_point_a());
    to_proto(r.point_b, out->mutable_point_b());
    out->set_triangle_pairs(static_cast<std::uint32_t>(r.pairs.size()));
    to_proto(r.bounds.min, out->mutable_bounds_min());
    to_proto(r.bounds.max, out->mutable_bounds_max());
    std::set<int> faces_a, faces_b;
    for (const ProximityPair& p : r.pairs) {
      if (a.is_cad()) faces_a.insert(a.part->face_of_triangle[p.triangle_a]);
      if (b.is_cad()) faces_b.insert(b.part->face_of_triangle[p.triangle_b]);
    }
    for (int f : faces_a) out->add_faces_a(static_cast<std::uint32_t>(f));
    for (int f : faces_b) out->add_faces_b(static_cast<std::uint32_t>(f));
  }
}

// The depth on the triangles, then (CAD parts) checked free on the exact faces.
std::string add_depth(const PosedSide& a, const PosedSide& b, const Vec3& along, const StopToken& stop,
                      pb::ClearanceQueryResponse* response) {
  const engine::PosedPart pa{a.part.get(), a.pose}, pb_{b.part.get(), b.pose};
  double depth = 0.0;
  Vec3 direction = Vec3::Zero();
  std::string method;
  bool exact = false;
  if (along != Vec3::Zero()) {
    auto d = penetration_along(*a.part->bvh, a.pose, *b.part->bvh, b.pose, along, kDepthResolutionMm, stop);
    if (!d.ok()) return "depth: " + d.error().to_string() + "; ";
    depth = d.value().depth_mm;
    direction = along.normalized();
    method = "along the requested direction";
  } else {
    // The directions are tried within a time budget (or until the caller gives up): every one
    // tried gives a freeing depth, so the best so far is still a certified upper bound.
    const auto started = Clock::now();
    const StopToken budget([&] { return us_since(started) > kDepthBudgetUs; });
    auto found = penetration_vector(*a.part->bvh, a.pose, *b.part->bvh, b.pose, kDepthLatticeDirections, kDepthResolutionMm,
                                    stop, budget);
    if (!found.ok()) return "depth: " + found.error().to_string() + "; ";
    const DepthVector& d = found.value();
    depth = d.depth_mm;
    direction = d.direction;
    exact = d.exact;
    method = d.from_piece_axis ? "convex-piece or part axis" : "lattice direction";
    if (d.stopped_early)
      method += " (time budget: " + std::to_string(d.directions_tried) + " directions tried)";
    response->set_depth_max_angle_deg(d.max_angle_between_samples_deg);
    response->set_depth_pieces_a(static_cast<std::uint32_t>(d.pieces_a));
    response->set_depth_pieces_b(static_cast<std::uint32_t>(d.pieces_b));
  }
  if (!(direction.norm() > 0.0) || (along == Vec3::Zero() && depth == 0.0)) {
    // The tessellations are already free (the exact solids overlap by less than the deflections):
    // B is moved apart along the line between the parts' centres, checked on the exact faces.
    direction = transformed_box(b.part->mesh->bounds(), b.pose).center() - transformed_box(a.part->mesh->bounds(), a.pose).center();
    if (!(direction.norm() > 0.0)) direction = Vec3::UnitZ();
    direction.normalize();
    method = "between the parts' centres";
  }
  auto checked = engine::check_depth_on_brep(pa, pb_, direction, depth, stop);
  if (!checked.ok()) return "depth: " + checked.error().message + "; ";
  if (engine::deflection_window(pa, pb_) > 0.0) {
    exact = false;  // found on a tessellation, not on the parts
    method += "; checked clear on the exact faces" +
                (checked.value().added_mm > 0.0 ? " after adding " + engine::number_text(checked.value().added_mm) + " mm" : std::string());
  }
  to_proto(direction, response->mutable_depth_direction());
  response->set_depth_mm(checked.value().depth_mm);
  response->set_depth_exact(exact);
  response->set_depth_method(method);
  return "";
}

// Where the two parts' boxes overlap (world).
Aabb overlap_box(const PosedSide& a, const PosedSide& b) {
  const Aabb ba = transformed_box(a.part->mesh->bounds(), a.pose), bb = transformed_box(b.part->mesh->bounds(), b.pose);
  return {ba.min.cwiseMax(bb.min), ba.max.cwiseMin(bb.max)};
}

std::string add_volume(const PosedSide& a, const PosedSide& b, const Vec3& near_point, const StopToken& stop,
                       pb::ClearanceQueryResponse* response) {
  std::string why_not_brep;
  if (a.is_cad() && b.is_cad()) {
    // In a frame local to the overlap: OCCT's Booleans lose overlaps at factory coordinates.
    auto exact = occt::shared_volume(a.part->shape, a.pose, b.part->shape, b.pose, near_point, /*bound_error=*/true);
    if (exact.ok() && exact.value().volume_mm3 <= tolerances::kBrepOverlapVolumeMm3) {
      // The verdict found them crossing, but the common holds (almost) nothing: a lens too small
      // for OCCT's Boolean to build. No figure rather than a 0 that reads as exact.
      response->set_interference_volume_mm3(-1.0);
      return "volume: the Boolean common lost the overlap (" + engine::number_text(exact.value().volume_mm3) +
             " mm^3: a crossing of micrometres); ";
    }
    if (exact.ok()) {
      response->set_interference_volume_mm3(exact.value().volume_mm3);
      response->set_volume_error_bound_mm3(exact.value().error_bound_mm3);
      response->set_volume_cell_mm(0.0);
      response->set_volume_method("brep boolean common");
      return "";
    }
    why_not_brep = " (the Boolean common failed: " + exact.error().message + ")";
  }
  auto volume = interference_volume(*a.part->bvh, a.pose, *b.part->bvh, b.pose, kVolumeRaysPerAxis, stop);
  if (!volume.ok()) {
    response->set_interference_volume_mm3(-1.0);
    return "volume: " + volume.error().to_string() + why_not_brep;
  }
  // A CAD part measured on its tessellation: the figure is the triangles', the bound covers the
  // band between them and the exact faces.
  const Aabb region = overlap_box(a, b);
  const double band = tessellation_band_volume(*a.part->mesh, a.pose, a.part->deflection_mm, region) +
                      tessellation_band_volume(*b.part->mesh, b.pose, b.part->deflection_mm, region);
  const std::string on_tessellation = band > 0.0 ? " on the CAD part's tessellation (the bound includes its deflection)" : "";
  response->set_interference_volume_mm3(volume.value().volume_mm3);
  response->set_volume_error_bound_mm3(volume.value().error_bound_mm3 + band);
  response->set_volume_cell_mm(volume.value().cell_mm);
  if (volume.value().method == VolumeMethod::kExactCorefinement)
    response->set_volume_method("mesh exact corefinement" + on_tessellation + why_not_brep);
  else if (!volume.value().exact_not_used.empty())
    response->set_volume_method("mesh ray cast" + on_tessellation + " (not exact: " + volume.value().exact_not_used + ")" +
                                why_not_brep);
  else
    response->set_volume_method("mesh ray cast" + on_tessellation + why_not_brep);
  return "";
}

}  // namespace

grpc::Status answer_clearance(const pb::ClearanceQueryRequest& request, PartRegistry& parts, SceneStore& scenes,
                              const StopToken& stop, pb::ClearanceQueryResponse* response) {
  const auto t0 = Clock::now();
  if (!std::isfinite(request.safety_gap_mm()) || request.safety_gap_mm() < 0.0 ||
      request.safety_gap_mm() > tolerances::kMaxCoordinateMm)
    return {grpc::StatusCode::INVALID_ARGUMENT, "safety_gap_mm: must be a distance from 0 to 1e7 mm"};
  if (!std::isfinite(request.region_merge_mm()) || request.region_merge_mm() < 0.0)
    return {grpc::StatusCode::INVALID_ARGUMENT, "region_merge_mm: must be a finite, non-negative distance"};
  auto ra = resolve(request.a(), "a", parts, scenes);
  if (!ra.ok()) return to_status(ra.error());
  auto rb = resolve(request.b(), "b", parts, scenes);
  if (!rb.ok()) return to_status(rb.error());
  const PosedSide& a = ra.value();
  const PosedSide& b = rb.value();
  engine::PairVerdictOptions options;
  options.clearance_mm = request.safety_gap_mm();
  options.measure_on_brep = true;
  options.mesh.stop = &stop;
  auto decided = engine::decide_pair({a.part.get(), a.pose}, {b.part.get(), b.pose}, options);
  if (!decided.ok()) return to_status(decided.error());
  const engine::PairVerdict& pv = decided.value();
  const VerdictResult& v = pv.result;
  response->set_verdict(to_proto(v.verdict));
  response->set_inconclusive_reason(to_proto(v.inconclusive_reason));
  response->set_reason(v.reason);
  response->set_distance_mm(v.distance_mm);
  to_proto(v.point_a, response->mutable_point_a());
  to_proto(v.point_b, response->mutable_point_b());
  if (!v.contacts.empty()) {
    response->set_triangle_a(v.contacts.front().triangle_a);
    response->set_triangle_b(v.contacts.front().triangle_b);
    if (a.is_cad()) response->set_face_a(static_cast<std::uint32_t>(a.part->face_of_triangle[v.contacts.front().triangle_a]));
    if (b.is_cad()) response->set_face_b(static_cast<std::uint32_t>(b.part->face_of_triangle[v.contacts.front().triangle_b]));
  }
  if (pv.face_a > 0) response->set_face_a(static_cast<std::uint32_t>(pv.face_a));
  if (pv.face_b > 0) response->set_face_b(static_cast<std::uint32_t>(pv.face_b));
  response->set_refined_on_brep(pv.decided_on_brep);
  response->set_exact_faces_us(1000.0 * pv.brep_ms);
  response->set_error_bound_mm(pv.error_bound_mm);
  auto near = pairs_within(*a.part->bvh, a.pose, *b.part->bvh, b.pose, request.safety_gap_mm(), kMaxReportedPairs, stop);
  if (!near.ok()) return to_status(near.error());
  response->set_pairs_within_gap(static_cast<std::uint32_t>(near.value().pairs.size()));
  response->set_pairs_truncated(near.value().truncated);
  add_regions(near.value().pairs, request.region_merge_mm() > 0.0 ? request.region_merge_mm() : kDefaultRegionMergeMm,
              a, b, response);
  response->set_gap_violated(v.verdict != Verdict::kClear || v.distance_mm < request.safety_gap_mm());
  const bool interpenetrating = v.verdict == Verdict::kCollision;
  std::string not_computed;
  const Vec3 along(request.depth_along().x_mm(), request.depth_along().y_mm(), request.depth_along().z_mm());
  if (!along.allFinite()) return {grpc::StatusCode::INVALID_ARGUMENT, "depth_along: must be finite"};
  if (interpenetrating && request.compute_depth()) {
    const std::string why = add_depth(a, b, along, stop, response);
    if (!why.empty()) response->set_depth_mm(-1.0);  // no depth certified: never a 0 that reads as "free"
    not_computed += why;
  }
  // Touching parts may still share a sliver (an overlap whose crossing segments are all shorter
  // than the point-contact tolerance): measured, not assumed 0. Apart (CLEAR), they share nothing.
  if (request.compute_volume()) {
    if (interpenetrating || v.verdict == Verdict::kTouching) {
      not_computed += add_volume(a, b, v.point_a, stop, response);
    } else if (v.verdict == Verdict::kClear) {
      response->set_interference_volume_mm3(0.0);
      response->set_volume_error_bound_mm3(0.0);
      response->set_volume_method("apart: nothing shared");
    } else {
      response->set_interference_volume_mm3(-1.0);
      not_computed += "volume: the verdict is INCONCLUSIVE; ";
    }
  }
  // The caller gave up (deadline, cancel): the work stopped where it was, and nobody reads this.
  if (stop.stop_requested()) return {grpc::StatusCode::DEADLINE_EXCEEDED, "stopped: the deadline passed or the call was cancelled"};
  response->set_not_computed(not_computed);
  response->set_elapsed_us(us_since(t0));
  return grpc::Status::OK;
}

}  // namespace gk::server
