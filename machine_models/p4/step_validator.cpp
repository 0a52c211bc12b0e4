#include "machine_models/p4/step_validator.h"

#include "kernel/mesh_bvh.h"
#include "kernel/mesh_collision.h"
#include "kernel/mesh_distance.h"
#include "machine_models/p4/organ_geometry.h"
#include "machine_models/p4/plate_shapes.h"
#include "occt_adapters/exact_measures.h"
#include "occt_adapters/shape_builders.h"

#include <algorithm>
#include <chrono>
#include <cmath>

namespace gk::p4 {
namespace {

constexpr double kPi = 3.14159265358979323846;
using Clock = std::chrono::steady_clock;

double us_since(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

std::uint64_t mix(std::uint64_t h, std::uint64_t v) {
  h ^= v + 0x9e3779b97f4a7c15ull + (h << 6) + (h >> 2);
  return h;
}

bool is_bend(StepKind k) { return k == StepKind::kBendUp || k == StepKind::kBendDown; }

// How deep the bodies' vertices (moved by body_pose) reach into the organ's prism, 0 if outside.
double deepest_inside(const Organ& organ, const RigidTransform& organ_pose, const std::vector<MovingBody>& bodies,
                      const RigidTransform& body_pose) {
  const RigidTransform to_organ = organ_pose.inverse() * body_pose;
  double depth = 0.0;
  for (const MovingBody& b : bodies)
    for (const Vec3& p : b.points)
      depth = std::max(depth, depth_inside_prism(organ.profile_yz, organ.x_min, organ.x_max, to_organ.apply(p)));
  return depth;
}

// The B-Rep distance between the plates (moved by `motion_pose`) and the organ's prism.
Result<double> exact_clearance(const std::vector<Plate>& plates, const RigidTransform& motion_pose, const Organ& organ,
                               const RigidTransform& organ_pose) {
  auto prism = occt::make_prism_yz(organ.profile_yz, organ.x_min, organ.x_max);
  if (!prism.ok()) return prism.error();
  auto placed_organ = occt::place(prism.value(), organ_pose);
  if (!placed_organ.ok()) return placed_organ.error();
  auto compound = plates_shape(plates, motion_pose);
  if (!compound.ok()) return compound.error();
  auto d = occt::exact_distance(compound.value(), placed_organ.value());
  if (!d.ok()) return d.error();
  return d.value().distance_mm;
}

// The plate cut across its edge that runs most nearly away from the rotation axis, into bands of
// 4, 8, 16, ... mm from the end nearer the axis. Translations keep the plate whole.
std::vector<Plate> radial_bands(const Plate& plate, const Motion& motion) {
  if (!motion.rotation) return {plate};
  auto radius = [&](const Vec3& x) {
    const Vec3 rel = x - motion.axis_point;
    return (rel - rel.dot(motion.axis_direction) * motion.axis_direction).norm();
  };
  int k = 0;
  double best = -1.0;
  for (int e = 0; e < 3; ++e) {
    const double change = std::fabs(radius(plate.origin + plate.edge[e]) - radius(plate.origin));
    if (change > best) {
      best = change;
      k = e;
    }
  }
  const double length = plate.edge[k].norm();
  const bool from_origin = radius(plate.origin) <= radius(plate.origin + plate.edge[k]);
  std::vector<Plate> bands;
  double start = 0.0, width = 4.0;
  while (start < length) {
    const double end = (length - (start + width) < 0.5 * width) ? length : start + width;
    Plate band = plate;
    const double a0 = from_origin ? start / length : 1.0 - end / length;
    const double a1 = from_origin ? end / length : 1.0 - start / length;
    band.origin = plate.origin + a0 * plate.edge[k];
    band.edge[k] = (a1 - a0) * plate.edge[k];
    bands.push_back(band);
    start = end;
    width *= 2.0;
  }
  return bands;
}

// The lowest Z reached by any body corner while rotating about an axis parallel to X. A box's
// lowest point over a rotation is at a corner, and each corner's lowest point is on its arc.
double lowest_point_of_rotation(const std::vector<MovingBody>& bodies, const Motion& motion) {
  double lowest = std::numeric_limits<double>::infinity();
  const double a0 = std::min(0.0, motion.angle_rad), a1 = std::max(0.0, motion.angle_rad);
  for (const MovingBody& b : bodies)
    for (const Vec3& p : b.points) {
      const double y = p.y() - motion.axis_point.y(), z = p.z() - motion.axis_point.z();
      const double r = std::hypot(y, z), phi = std::atan2(z, y);
      // z(angle) = r sin(phi + angle) over angle in [a0, a1]: its minimum is at an end, or at
      // phi + angle = -pi/2 (mod 2 pi) when that lies inside.
      double m = std::min(r * std::sin(phi + a0), r * std::sin(phi + a1));
      for (double k = -2.0; k <= 2.0; k += 1.0) {
        const double at = -0.5 * kPi + 2.0 * kPi * k - phi;
        if (at >= a0 && at <= a1) m = -r;
      }
      lowest = std::min(lowest, motion.axis_point.z() + m);
    }
  return lowest;
}

}  // namespace

const char* to_string(Stage stage) {
  switch (stage) {
    case Stage::kCache: return "cache";
    case Stage::kGlobalBox: return "global_box";
    case Stage::kBroadPhase: return "broad_phase";
    case Stage::kHullLod: return "hull_lod";
    case Stage::kNarrow: return "narrow";
    case Stage::kExact: return "exact";
  }
  return "?";
}

const char* to_string(CorrectionKind kind) {
  switch (kind) {
    case CorrectionKind::kNone: return "NONE";
    case CorrectionKind::kRepoShift: return "REPO";
    case CorrectionKind::kChangeAba: return "CHANGE_ABA";
    case CorrectionKind::kRetract: return "RETRACT";
    case CorrectionKind::kFlip: return "FLIP";
  }
  return "?";
}

// What a step needs before any organ is looked at: the moving bodies in machine coordinates, the
// motion, and which organs take part. Cached per part, step and (for manipulator moves) state.
struct StepValidator::Prepared {
  std::vector<MovingBody> bodies;  // one per rigid group (part, manipulator): for the hull
  // The same plates cut into radial bands, for advancement: built on first use, since most
  // answers are settled before the narrow phase.
  mutable std::vector<MovingBody> pieces;
  mutable bool pieces_built = false;
  std::vector<Plate> plates;  // the bodies' plates, machine coordinates (for the exact phase)
  Motion motion;
  double extra_clearance_mm = 0.0;  // a tessellated part's deflection, added to every clearance
  bool exact_possible = true;       // the plates are the part's exact geometry
  bool is_static = false;     // CLAMP: no motion
  double lift_mm = 0.0;       // clamp-relative organs raised by this during the step
};

StepValidator::StepValidator(std::shared_ptr<MachineScene> scene, ValidatorOptions options)
    : scene_(std::move(scene)), options_(options) {}

Result<bool> StepValidator::set_state(const MachineState& state) { return scene_->apply_state(state); }

void StepValidator::clear_caches() {
  memo_.clear();
  prepared_.clear();
}

Result<std::shared_ptr<const StepValidator::Prepared>> StepValidator::prepare(const SheetPart& part, const BendStep& step) {
  const MachineModel& model = scene_->model();
  const MachineState& state = scene_->state();
  std::uint64_t key = mix(part.content_hash(), step.hash());
  if (!is_bend(step.kind)) key = mix(key, state.hash());
  if (auto it = prepared_.find(key); it != prepared_.end()) return it->second;

  auto prepared = std::make_shared<Prepared>();
  const RigidTransform placement = part_placement(part, step);
  const double t = part.thickness_mm();
  std::vector<Plate> plates;
  if (part.has_surface()) {
    // A part given by its surface: one body of (clipped) triangles; no plates, so the exact phase
    // is replaced by adding the tessellation's deflection to the clearance.
    std::vector<Vec3> vertices;
    std::vector<TriangleMesh::Face> faces;
    bool fixed_empty = true;
    if (is_bend(step.kind)) {
      auto split = part.split_surface(step.bend_point_mm, step.bend_direction, model.bend_zone_mm, vertices, faces, fixed_empty);
      if (!split.ok()) return split.error();
      if (faces.empty()) return invalid_argument("bend_line", "nothing of the part lies on the moving side beyond the bend zone");
      if (fixed_empty) return invalid_argument("bend_line", "nothing of the part is left under the blankholder");
    } else {
      vertices = part.surface().vertices();
      faces = part.surface().faces();
    }
    for (Vec3& v : vertices) v = placement.apply(v);
    auto mesh = TriangleMesh::create(std::move(vertices), std::move(faces), {true});
    if (!mesh.ok()) return mesh.error();
    MovingBody body;
    body.points = mesh.value().vertices();
    auto bvh = MeshBvh::build(std::make_shared<const TriangleMesh>(std::move(mesh).value()));
    if (!bvh.ok()) return bvh.error();
    body.mesh = bvh.value();
    prepared->bodies.push_back(body);
    prepared->pieces.push_back(body);
    prepared->pieces_built = true;
    prepared->extra_clearance_mm = part.deflection_mm();
    prepared->exact_possible = false;
  } else if (is_bend(step.kind)) {
    std::vector<Plate> moving, fixed;
    auto split = part.split(step.bend_point_mm, step.bend_direction, model.bend_zone_mm, moving, fixed);
    if (!split.ok()) return split.error();
    if (moving.empty()) return invalid_argument("bend_line", "nothing of the part lies on the moving side beyond the bend zone");
    if (fixed.empty()) return invalid_argument("bend_line", "nothing of the part is left under the blankholder");
    plates = moving;
  } else {
    plates = part.plates();
  }
  for (Plate& p : plates) p = p.transformed(placement);
  std::vector<std::vector<Plate>> groups;
  if (!plates.empty()) groups.push_back(plates);
  if (step.kind == StepKind::kRotate || step.kind == StepKind::kApproach || step.kind == StepKind::kRetract) {
    // The manipulator's rotator column rides with the part: a body of its own, so that each gets
    // a tight hull (the column turns about its own axis and sweeps little).
    const double r = model.manipulator.rotator_radius_mm;
    const Vec3 c(state.manipulator_x_mm, state.manipulator_y_mm, t);
    groups.push_back({{c + Vec3(-r, -r, 0.0), {Vec3(2 * r, 0, 0), Vec3(0, 2 * r, 0), Vec3(0, 0, model.manipulator.rotator_height_mm)},
                       "manipulator.rotator"}});
  }
  for (auto& group : groups) {
    if (step.kind == StepKind::kRotate && step.retract_mm > 0.0)
      for (Plate& p : group) p = p.transformed(RigidTransform::from_translation(Vec3(0, -step.retract_mm, 0)));
    MovingBody body;
    TriangleMesh mesh = plates_mesh(group);
    body.points = mesh.vertices();
    auto bvh = MeshBvh::build(std::make_shared<const TriangleMesh>(std::move(mesh)));
    if (!bvh.ok()) return bvh.error();
    body.mesh = bvh.value();
    if (prepared->pieces_built) prepared->pieces.push_back(body);  // a surface part's bodies are its pieces
    prepared->bodies.push_back(std::move(body));
    prepared->plates.insert(prepared->plates.end(), group.begin(), group.end());
  }

  switch (step.kind) {
    case StepKind::kBendUp:
      prepared->motion = {true, Vec3(0, 0, t), Vec3::UnitX(), step.target_angle_deg * kPi / 180.0, Vec3::Zero()};
      break;
    case StepKind::kBendDown:
      prepared->motion = {true, Vec3::Zero(), Vec3::UnitX(), -step.target_angle_deg * kPi / 180.0, Vec3::Zero()};
      break;
    case StepKind::kRotate:
      prepared->motion = {true, Vec3(state.manipulator_x_mm, state.manipulator_y_mm - step.retract_mm, 0.0), Vec3::UnitZ(),
                          step.rotate_angle_deg * kPi / 180.0, Vec3::Zero()};
      prepared->lift_mm = model.aba_lift_for_rotation_mm;
      break;
    case StepKind::kApproach:
    case StepKind::kRetract:
      prepared->motion = {false, Vec3::Zero(), Vec3::UnitX(), 0.0, step.travel_mm};
      prepared->lift_mm = model.aba_lift_for_rotation_mm;
      break;
    case StepKind::kClamp:
      prepared->is_static = true;
      prepared->motion = {false, Vec3::Zero(), Vec3::UnitX(), 0.0, Vec3::Zero()};
      break;
  }
  if (prepared_.size() >= options_.memo_capacity) prepared_.clear();
  prepared_[key] = prepared;
  return std::shared_ptr<const Prepared>(prepared);
}

Result<StepAnswer> StepValidator::validate(const SheetPart& part, const BendStep& step) {
  return validate(part, step, options_.compute_corrections);
}

Result<StepAnswer> StepValidator::validate(const SheetPart& part, const BendStep& step, bool with_corrections) {
  const auto t0 = Clock::now();
  auto valid = validate_step(scene_->model(), step);
  if (!valid.ok()) return valid.error();
  const MachineModel& model = scene_->model();
  if (part.thickness_mm() < model.min_thickness_mm || part.thickness_mm() > model.max_thickness_mm)
    return invalid_argument("part.thickness_mm", "outside the machine's range [" + std::to_string(model.min_thickness_mm) +
                                                     ", " + std::to_string(model.max_thickness_mm) + "] mm");
  const std::uint64_t key = mix(mix(mix(part.content_hash(), step.hash()), scene_->state().hash()), with_corrections ? 1 : 2);
  if (auto it = memo_.find(key); it != memo_.end()) {
    StepAnswer hit = it->second;
    hit.decided_by = Stage::kCache;
    hit.times = StageTimes{};
    hit.times.cache_us = hit.times.total_us = us_since(t0);
    return hit;
  }
  auto answer = run_pipeline(part, step);
  if (!answer.ok()) return answer;
  StepAnswer& a = answer.value();
  if (a.verdict == Verdict::kCollision && with_corrections) add_correction(part, step, a);
  a.times.cache_us = 0.0;
  a.times.total_us = us_since(t0);
  if (memo_.size() >= options_.memo_capacity) memo_.clear();
  memo_[key] = a;
  return answer;
}

Result<StepAnswer> StepValidator::run_pipeline(const SheetPart& part, const BendStep& step) {
  StepAnswer answer;
  auto t = Clock::now();
  auto prepared_or = prepare(part, step);
  if (!prepared_or.ok()) return prepared_or.error();
  answer.times.prepare_us = us_since(t);
  t = Clock::now();
  const Prepared& prep = *prepared_or.value();
  const std::vector<Organ>& organs = scene_->organs();
  const bool bend = is_bend(step.kind);
  const double step_rad = options_.hull_sample_step_deg * kPi / 180.0;

  // The organs that take part, placed for the step: supports carry the part (intended contact);
  // the blades form the flange being bent; clamp-relative organs rise while the part moves.
  auto takes_part = [&](const Organ& o) { return !o.support && !(bend && o.name.rfind("blade.", 0) == 0); };
  auto organ_pose = [&](const Organ& o) {
    return o.relative_to_clamp && prep.lift_mm != 0.0 ? RigidTransform::from_translation(Vec3(0, 0, prep.lift_mm)) * o.pose
                                                      : o.pose;
  };

  // 2. Global box: the whole motion against the whole machine.
  Aabb swept;
  if (prep.is_static) {
    for (const MovingBody& b : prep.bodies) swept.extend(b.mesh->root_bounds());
  } else {
    swept = swept_bounds(prep.bodies, prep.motion, step_rad);
  }
  const double clearance = options_.required_clearance_mm + prep.extra_clearance_mm;
  swept = swept.expanded(clearance);
  Aabb machine;
  for (const Organ& o : organs)
    if (takes_part(o)) machine.extend(o.box);
  machine.max.z() += prep.lift_mm;
  answer.times.global_box_us = us_since(t);
  if (!swept.overlaps(machine)) {
    answer.verdict = Verdict::kClear;
    answer.decided_by = Stage::kGlobalBox;
    answer.reason = "the motion's box misses the machine's box";
    return answer;
  }

  // 3. Broad phase over the organ tree (boxes lowered by the lift, so raised organs are found).
  t = Clock::now();
  Aabb query = swept;
  query.min.z() -= prep.lift_mm;
  std::vector<SweepOrgan> candidates;
  for (int i : scene_->organs_overlapping(query)) {
    if (!takes_part(organs[i])) continue;
    candidates.push_back({i, organs[i].mesh.get(), organ_pose(organs[i])});
  }
  if (step.kind == StepKind::kBendDown) {
    // The cheap lowest-point check: a flange turning down about the X axis reaches its exact
    // lowest point analytically (each corner on its circle); organs wholly below it drop out.
    const double lowest = lowest_point_of_rotation(prep.bodies, prep.motion);
    answer.lowest_point_mm = lowest;
    candidates.erase(std::remove_if(candidates.begin(), candidates.end(),
                                    [&](const SweepOrgan& c) {
                                      return organs[c.index].box.max.z() < lowest - clearance;
                                    }),
                     candidates.end());
  }
  answer.candidate_organs = static_cast<int>(candidates.size());
  answer.times.broad_us = us_since(t);
  if (candidates.empty()) {
    answer.verdict = Verdict::kClear;
    answer.decided_by = Stage::kBroadPhase;
    answer.reason = "no organ's box meets the motion's box";
    return answer;
  }

  // CLAMP: a static check. The blankholder pressing on the sheet is an intended touch, so the
  // clamp-relative organs are tested lifted by the required clearance: anything of the part that
  // still meets them stands up into the blankholder by more than that.
  if (prep.is_static) {
    t = Clock::now();
    answer.decided_by = Stage::kNarrow;
    answer.verdict = Verdict::kClear;
    const RigidTransform lift = RigidTransform::from_translation(Vec3(0, 0, clearance));
    for (const SweepOrgan& c : candidates) {
      const Organ& organ = organs[c.index];
      const RigidTransform pose = organ.relative_to_clamp ? lift * c.pose : c.pose;
      for (const MovingBody& b : prep.bodies) {
        auto hit = collide(*b.mesh, RigidTransform{}, *c.mesh, pose);
        if (!hit.ok()) return hit.error();
        if (hit.value().colliding) {
          StepCollision col;
          col.organ = organ.name;
          col.point_mm = hit.value().contacts.front().point;
          col.organ_point_mm = col.point_mm;
          col.depth_mm = deepest_inside(organ, c.pose, {b}, RigidTransform{});
          answer.collisions.push_back(col);
          answer.verdict = Verdict::kCollision;
          continue;
        }
        // Clearance from the organs that are not pressing on the sheet (within 50 mm).
        if (organ.relative_to_clamp && organ.engaged) continue;
        DistanceRequest near;
        near.upper_bound_mm = std::min(answer.min_clearance_mm, 50.0);
        auto d = distance(*b.mesh, RigidTransform{}, *c.mesh, c.pose, near);
        if (!d.ok()) return d.error();
        if (d.value().found) {
          answer.min_clearance_mm = d.value().distance_mm;
          answer.clearance_organ = organ.name;
          answer.clearance_point_mm = d.value().point_a;
        }
      }
    }
    answer.reason = answer.verdict == Verdict::kClear ? "the blankholder closes on the sheet without hitting it"
                                                      : "the blankholder would close on part of the sheet";
    answer.times.narrow_us = us_since(t);
    return answer;
  }

  // 4. Hull level of detail.
  t = Clock::now();
  auto lod = hull_lod(prep.bodies, prep.motion, candidates, clearance, step_rad);
  if (!lod.ok()) return lod.error();
  std::vector<SweepOrgan> narrow;
  for (int i : lod.value().remaining) narrow.push_back(candidates[i]);
  answer.times.hull_us = us_since(t);
  if (narrow.empty()) {
    answer.verdict = Verdict::kClear;
    answer.decided_by = Stage::kHullLod;
    answer.reason = "the swept hull (inflated by the sagitta) clears every candidate organ";
    return answer;
  }

  // 5. Narrow phase.
  t = Clock::now();
  AdvanceOptions adv;
  adv.required_clearance_mm = clearance;
  adv.body_hull_step_rad = step_rad;
  if (!prep.pieces_built) {
    // Advancement steps by the fastest point of a body: cutting the plates into bands of growing
    // distance from the rotation axis lets the slow band next to a tool take long steps.
    for (const Plate& plate : prep.plates) {
      for (const Plate& band : radial_bands(plate, prep.motion)) {
        MovingBody piece;
        TriangleMesh mesh = plates_mesh({band});
        piece.points = mesh.vertices();
        auto bvh = MeshBvh::build(std::make_shared<const TriangleMesh>(std::move(mesh)));
        if (!bvh.ok()) return bvh.error();
        piece.mesh = bvh.value();
        prep.pieces.push_back(std::move(piece));
      }
    }
    prep.pieces_built = true;
  }
  auto swept_or = conservative_advance(prep.pieces, prep.motion, narrow, adv);
  if (!swept_or.ok()) return swept_or.error();
  const SweepOutcome& out = swept_or.value();
  answer.narrow_steps = out.steps;
  answer.times.narrow_us = us_since(t);
  answer.decided_by = Stage::kNarrow;
  const double full_deg = prep.motion.rotation ? prep.motion.angle_rad * 180.0 / kPi : 0.0;
  if (out.budget_exceeded) {
    answer.verdict = Verdict::kInconclusive;
    answer.reason = "the motion grazes an organ for too long to certify (advancement budget exhausted)";
    return answer;
  }
  if (out.collided) {
    const SweepOrgan& hit = narrow[out.organ];
    const Organ& organ = organs[hit.index];
    StepCollision col;
    col.organ = organ.name;
    col.point_mm = out.point_on_body;
    col.organ_point_mm = out.point_on_organ;
    col.normal = out.normal;
    col.first_contact_fraction = out.contact_s;
    col.first_contact_deg = std::fabs(full_deg) * out.contact_s;
    // Depth at the end of the step: the deepest moving vertex inside the organ.
    col.depth_mm = deepest_inside(organ, hit.pose, prep.bodies, prep.motion.at(1.0));
    answer.collisions.push_back(col);
    answer.verdict = Verdict::kCollision;
    answer.reason = out.contact_s == 0.0 ? "already within the required clearance of " + organ.name + " at the start"
                                         : "reaches " + organ.name + " during the motion";
    return answer;
  }
  answer.verdict = Verdict::kClear;
  answer.min_clearance_mm = out.min_clearance_mm;
  answer.certified_clearance_mm = out.certified_clearance_mm;
  answer.clearance_point_mm = out.min_clearance_point;
  if (out.min_clearance_organ >= 0) answer.clearance_organ = organs[narrow[out.min_clearance_organ].index].name;
  answer.reason = "the exact sweep keeps its clearance from every organ";

  // 6. Exact phase, only inside the tolerance window. The advancement already proves the clearance
  // never falls below the required one between samples on these meshes; a near miss is measured
  // again on the B-Rep (the moving plates and the organ's prism) at the closest sampled pose, so a
  // tessellation can never turn a real collision into a clear answer.
  if (prep.exact_possible && out.min_clearance_mm < options_.required_clearance_mm + options_.exact_window_mm) {
    t = Clock::now();
    answer.decided_by = Stage::kExact;
    const SweepOrgan& near = narrow[out.min_clearance_organ];
    auto exact = exact_clearance(prep.plates, prep.motion.at(out.min_clearance_s), organs[near.index], near.pose);
    if (!exact.ok()) {
      answer.verdict = Verdict::kInconclusive;
      answer.reason = "near miss that the B-Rep confirmation could not measure: " + exact.error().to_string();
    } else if (exact.value() <= options_.required_clearance_mm) {
      answer.verdict = Verdict::kCollision;
      answer.reason = "the B-Rep comes closer to " + organs[near.index].name + " than the required clearance";
      StepCollision col;
      col.organ = organs[near.index].name;
      col.point_mm = out.min_clearance_point;
      col.first_contact_fraction = out.min_clearance_s;
      col.first_contact_deg = std::fabs(full_deg) * out.min_clearance_s;
      answer.collisions.push_back(col);
    } else {
      answer.reason = "near miss confirmed on the B-Rep";
    }
    answer.times.exact_us = us_since(t);
  }
  return answer;
}

}  // namespace gk::p4
