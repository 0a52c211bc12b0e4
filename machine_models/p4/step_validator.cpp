#include "machine_models/p4/step_validator.h"

#include "kernel/bvh/mesh_bvh.h"
#include "kernel/query/mesh_distance.h"
#include "machine_models/p4/contact_layers.h"
#include "machine_models/p4/convex_polytope.h"
#include "machine_models/p4/manipulator_geometry.h"
#include "machine_models/p4/organ_geometry.h"
#include "kernel/core/units.h"
#include "kernel/core/tolerances.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>

namespace gk::p4 {
namespace {

using Clock = std::chrono::steady_clock;

double us_since(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }


bool is_bend(StepKind k) { return k == StepKind::kBendUp || k == StepKind::kBendDown; }

Result<MovingBody> make_body(TriangleMesh mesh, std::vector<Plate> plates) {
  MovingBody body;
  body.points = mesh.vertices();
  // A few boxes' worth of triangles: leaves of 4 build several times faster and query as fast.
  BvhBuildOptions options;
  options.leaf_size = 4;
  auto bvh = MeshBvh::build(std::make_shared<const TriangleMesh>(std::move(mesh)), options);
  if (!bvh.ok()) return bvh.error();
  body.mesh = bvh.value();
  body.plates = std::move(plates);
  return body;
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

// The lowest Z reached by any body point while rotating about an axis parallel to X: each point's
// lowest position is on its arc.
double lowest_point_of_rotation(const std::vector<Vec3>& points, const Motion& motion) {
  double lowest = std::numeric_limits<double>::infinity();
  const double a0 = std::min(0.0, motion.angle_rad), a1 = std::max(0.0, motion.angle_rad);
  for (const Vec3& p : points) {
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
    case Stage::kLimits: return "limits";
    case Stage::kStatic: return "static";
    case Stage::kGlobalBox: return "global_box";
    case Stage::kBroadPhase: return "broad_phase";
    case Stage::kHullLod: return "hull_lod";
    case Stage::kNarrow: return "narrow";
  }
  return "?";
}

const char* to_string(DenialReason reason) {
  switch (reason) {
    case DenialReason::kNone: return "NONE";
    case DenialReason::kMachineLimit: return "MACHINE_LIMIT";
    case DenialReason::kSweepBudget: return "SWEEP_BUDGET";
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

// One rigid group of the step, in machine coordinates at the start of the motion.
struct StepBody {
  std::string name;                // "part", "flange", "manipulator"
  MovingBody whole;
  // For advancement: radial bands of the plates (or the whole body), cut on first use since most
  // answers are settled before the narrow phase.
  mutable std::vector<MovingBody> pieces;
  bool moves = false;              // swept by the motion; otherwise held still through the step
  bool rests_on_supports = false;  // its lower face lies on the supports' top faces
  bool pressed_by_aba = false;     // its upper face is pressed by the engaged segments
  // The body outside the intended contact layers: what hangs below a support's top face (one per
  // support top height) and what stands above the pressing plane. Empty: nothing there.
  std::vector<std::pair<double, std::optional<MovingBody>>> below_support;
  std::optional<MovingBody> above_pressing;
  // The part: what stands above its sheet's upper face (tabs, flanges), which the manipulator
  // standing on that face must keep clear of.
  std::optional<MovingBody> above_sheet;
};

// Something a body must keep clear of, placed for the step: an organ, or (in a bend) a plate of
// the manipulator, which the flange must not sweep through.
struct Obstacle {
  std::string name;
  const MeshBvh* mesh = nullptr;
  RigidTransform pose;
  Aabb box;
  ConvexPolytope shape;          // machine coordinates
  bool support = false;          // a support's top face carries the part
  bool pressing = false;         // an engaged ABA segment pressing the part (CLAMP, bends)
  double top_z = 0.0;            // supports: the top face's height
};

// What a step needs before any organ is looked at. Cached per part, step and state.
struct StepValidator::Prepared {
  std::vector<StepBody> bodies;
  mutable std::vector<std::shared_ptr<MeshBvh>> manipulator_meshes;  // bends: the manipulator as obstacles
  std::vector<Plate> manipulator_plates;
  Motion motion;
  bool has_motion = false;
  double extra_clearance_mm = 0.0;  // a tessellated part's deflection, added to every clearance
  double lift_mm = 0.0;             // clamp-relative organs raised by this during the step
  double pressing_plane_z = 0.0;    // engaged segments' lower face, where the part is pressed
  LimitCheck limit;
};

StepValidator::StepValidator(std::shared_ptr<MachineScene> scene, ValidatorOptions options)
    : scene_(std::move(scene)), options_(options) {}

Result<bool> StepValidator::set_state(const MachineState& state) { return scene_->apply_state(state); }

void StepValidator::clear_caches() {
  memo_.clear();
  prepared_.clear();
  prepared_triangles_ = 0;
}

Result<std::shared_ptr<const StepValidator::Prepared>> StepValidator::prepare(const SheetPart& part, const BendStep& step) {
  const MachineModel& model = scene_->model();
  const MachineState& state = scene_->state();
  const Hash128 key = ContentHash().add(part.content_hash()).add(step.hash()).add(state.hash()).value();
  if (auto it = prepared_.find(key); it != prepared_.end()) return it->second;

  auto prepared = std::make_shared<Prepared>();
  Prepared& prep = *prepared;
  const double t = part.thickness_mm();
  const bool bend = is_bend(step.kind);
  const bool in_plane = !bend && step.kind != StepKind::kClamp;  // ROTATE, APPROACH, RETRACT
  double low = std::numeric_limits<double>::infinity();
  for (const Vec2& q : model.aba.profile_yz_mm) low = std::min(low, q.y());
  prep.pressing_plane_z = state.clamp_z_mm + low;

  // Where the part is: the step's placement, then (manipulator moves) the retract and earlier turn.
  const Vec2 grip(state.manipulator_x_mm, state.manipulator_y_mm - (in_plane ? step.retract_mm : 0.0));
  RigidTransform placement = part_placement(part, step);
  RigidTransform pre = RigidTransform{};
  if (in_plane) {
    const Vec3 pivot(grip.x(), grip.y(), 0.0);
    pre = RigidTransform::from_translation(pivot) * RigidTransform::from_axis_angle(Vec3::UnitZ(), step.turned_deg * kPi / 180.0) *
          RigidTransform::from_translation(-pivot) * RigidTransform::from_translation(Vec3(0, -step.retract_mm, 0));
    placement = pre * placement;
  }

  // The part: held whole, or split into the held side and the moving flange.
  std::vector<Plate> held_plates, moving_plates;
  std::vector<Vec3> held_vertices, moving_vertices;
  std::vector<TriangleMesh::Face> held_faces, moving_faces;
  if (part.has_surface()) {
    if (bend) {
      auto split = part.split_surface(step.bend_point_mm, step.bend_direction, model.bend_zone_mm, moving_vertices,
                                      moving_faces, held_vertices, held_faces);
      if (!split.ok()) return split.error();
      if (moving_faces.empty()) return invalid_argument("bend_point", "nothing of the part lies on the moving side beyond the bend zone");
      if (held_faces.empty()) return invalid_argument("bend_point", "nothing of the part is left under the blankholder");
    } else {
      held_vertices = part.surface().vertices();
      held_faces = part.surface().faces();
    }
    for (Vec3& v : held_vertices) v = placement.apply(v);
    for (Vec3& v : moving_vertices) v = placement.apply(v);
    prep.extra_clearance_mm = part.deflection_mm();
  } else {
    if (bend) {
      auto split = part.split(step.bend_point_mm, step.bend_direction, model.bend_zone_mm, moving_plates, held_plates);
      if (!split.ok()) return split.error();
      if (moving_plates.empty()) return invalid_argument("bend_point", "nothing of the part lies on the moving side beyond the bend zone");
      if (held_plates.empty()) return invalid_argument("bend_point", "nothing of the part is left under the blankholder");
    } else {
      held_plates = part.plates();
    }
    for (Plate& p : held_plates) p = p.transformed(placement);
    for (Plate& p : moving_plates) p = p.transformed(placement);
  }

  // The motion.
  switch (step.kind) {
    case StepKind::kBendUp:
      prep.motion = {true, Vec3(0, 0, t), Vec3::UnitX(), step.target_angle_deg * kPi / 180.0, Vec3::Zero()};
      prep.has_motion = true;
      break;
    case StepKind::kBendDown:
      prep.motion = {true, Vec3::Zero(), Vec3::UnitX(), -step.target_angle_deg * kPi / 180.0, Vec3::Zero()};
      prep.has_motion = true;
      break;
    case StepKind::kRotate:
      prep.motion = {true, Vec3(grip.x(), grip.y(), 0.0), Vec3::UnitZ(), step.rotate_angle_deg * kPi / 180.0, Vec3::Zero()};
      prep.has_motion = true;
      prep.lift_mm = model.aba_lift_for_rotation_mm;
      break;
    case StepKind::kApproach:
    case StepKind::kRetract:
      prep.motion = {false, Vec3::Zero(), Vec3::UnitX(), 0.0, step.travel_mm};
      prep.has_motion = true;
      prep.lift_mm = model.aba_lift_for_rotation_mm;
      break;
    case StepKind::kClamp:
      prep.motion = {false, Vec3::Zero(), Vec3::UnitX(), 0.0, Vec3::Zero()};
      break;
  }

  // Machine limits, in the order a programmer would look at them.
  const HeldSide held{part.has_surface() ? nullptr : &held_plates, part.has_surface() ? &held_vertices : nullptr,
                      part.has_surface() ? &held_faces : nullptr};
  auto deny = [&](MachineLimit limit, std::string detail) {
    if (prep.limit.limit == MachineLimit::kNone) prep.limit = {limit, std::move(detail)};
  };
  if (t < model.min_thickness_mm || t > model.max_thickness_mm)
    deny(MachineLimit::kThickness, "thickness " + std::to_string(t) + " mm is outside the machine's [" +
                                       std::to_string(model.min_thickness_mm) + ", " + std::to_string(model.max_thickness_mm) + "] mm");
  if (bend && step.target_angle_deg > model.max_bend_angle_deg)
    deny(MachineLimit::kBendAngle, "bend of " + std::to_string(step.target_angle_deg) + " degrees; the machine bends up to " +
                                       std::to_string(model.max_bend_angle_deg));
  if (bend) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    auto extend = [&](const Vec3& p) {
      lo = std::min(lo, p.x());
      hi = std::max(hi, p.x());
    };
    for (const Plate& p : moving_plates)
      for (const Vec3& c : p.corners()) extend(c);
    for (const Vec3& v : moving_vertices) extend(v);
    if (hi - lo > model.max_bend_length_mm)
      deny(MachineLimit::kBendLength, "the flange is " + std::to_string(hi - lo) + " mm long; the machine bends up to " +
                                          std::to_string(model.max_bend_length_mm) + " mm");
  }
  const ManipulatorSpec& m = model.manipulator;
  auto within = [](double v, const double range[2]) {
    return v >= range[0] - tolerances::kMachineLengthSlackMm && v <= range[1] + tolerances::kMachineLengthSlackMm;
  };
  if (!within(grip.x(), m.travel_x_mm))
    deny(MachineLimit::kManipulatorTravelX, "manipulator x " + std::to_string(grip.x()) + " mm is outside its travel");
  if (!within(grip.y(), m.travel_y_mm))
    deny(MachineLimit::kManipulatorTravelY, "manipulator y " + std::to_string(grip.y()) + " mm (after the retract) is outside its travel");
  if (step.kind == StepKind::kApproach || step.kind == StepKind::kRetract) {
    const Vec2 end = grip + Vec2(step.travel_mm.x(), step.travel_mm.y());
    if (!within(end.x(), m.travel_x_mm))
      deny(MachineLimit::kManipulatorTravelX, "the travel ends at manipulator x " + std::to_string(end.x()) +
                                                  " mm, outside [" + std::to_string(m.travel_x_mm[0]) + ", " +
                                                  std::to_string(m.travel_x_mm[1]) + "]");
    if (!within(end.y(), m.travel_y_mm))
      deny(MachineLimit::kManipulatorTravelY, "the travel ends at manipulator y " + std::to_string(end.y()) +
                                                  " mm, outside [" + std::to_string(m.travel_y_mm[0]) + ", " +
                                                  std::to_string(m.travel_y_mm[1]) + "]");
  }
  if (!point_on_upper_face(held, grip, t))
    deny(MachineLimit::kGripNotOnPart, std::string("the manipulator point is not on the part's upper face") +
                                           (bend ? " on the held side of the bend" : ""));
  if ((bend || step.kind == StepKind::kClamp) &&
      clamped_area_mm2(model, state, held, prep.pressing_plane_z) < tolerances::kMinClampedAreaMm2)
    deny(MachineLimit::kNoClampingSegment, "no engaged ABA segment presses the part's upper face (the blankholder's "
                                           "lower face is at z = " + std::to_string(prep.pressing_plane_z) +
                                           " mm, the sheet's upper face at " + std::to_string(t) + " mm)");

  auto keep = [&]() {
    // Bounded by count and by the triangles the bodies hold (a part of a thousand tabs is megabytes).
    std::size_t triangles = 0;
    for (const StepBody& b : prep.bodies) triangles += b.whole.mesh ? b.whole.mesh->mesh().triangle_count() * 3 : 0;
    if (prepared_.size() >= options_.prepared_capacity || prepared_triangles_ + triangles > options_.prepared_triangle_budget) {
      prepared_.clear();
      prepared_triangles_ = 0;
    }
    prepared_[key] = prepared;
    prepared_triangles_ += triangles;
    return std::shared_ptr<const Prepared>(prepared);
  };
  if (prep.limit.limit != MachineLimit::kNone) return keep();  // denied: no geometry needed

  // The bodies.
  std::vector<double> support_tops;
  for (const Organ& o : scene_->organs())
    if (o.support && std::find(support_tops.begin(), support_tops.end(), o.box.max.z()) == support_tops.end())
      support_tops.push_back(o.box.max.z());
  auto add_body = [&](std::string name, TriangleMesh mesh, std::vector<Plate> plates, bool moves, bool rests,
                      bool pressed) -> Result<bool> {
    StepBody b;
    b.name = std::move(name);
    b.moves = moves;
    b.rests_on_supports = rests;
    b.pressed_by_aba = pressed;
    const bool in_plane_motion = !moves || !prep.motion.rotation || prep.motion.axis_direction.isApprox(Vec3::UnitZ());
    if (rests && !in_plane_motion) return invalid_argument("step", "a body resting on the supports must move in the table's plane");
    if (rests)
      for (double top : support_tops) {
        auto below = clip_mesh_at_z(mesh, top - tolerances::kIntendedContactMm, true);
        if (!below.ok()) return below.error();
        std::optional<MovingBody> version;
        if (below.value()) {
          auto body = make_body(std::move(*below.value()), plates);
          if (!body.ok()) return body.error();
          version = std::move(body).value();
        }
        b.below_support.emplace_back(top, std::move(version));
      }
    if (pressed) {
      auto above = clip_mesh_at_z(mesh, prep.pressing_plane_z + tolerances::kIntendedContactMm, false);
      if (!above.ok()) return above.error();
      if (above.value()) {
        auto body = make_body(std::move(*above.value()), plates);
        if (!body.ok()) return body.error();
        b.above_pressing = std::move(body).value();
      }
    }
    if (b.name == "part") {
      auto above = clip_mesh_at_z(mesh, t + tolerances::kIntendedContactMm, false);
      if (!above.ok()) return above.error();
      if (above.value()) {
        auto body = make_body(std::move(*above.value()), plates);
        if (!body.ok()) return body.error();
        b.above_sheet = std::move(body).value();
      }
    }
    auto whole = make_body(std::move(mesh), plates);
    if (!whole.ok()) return whole.error();
    b.whole = std::move(whole).value();
    prep.bodies.push_back(std::move(b));
    return true;
  };
  auto surface_mesh = [](std::vector<Vec3> vertices, std::vector<TriangleMesh::Face> faces) {
    return TriangleMesh::create(std::move(vertices), std::move(faces));
  };
  const bool part_pressed = bend || step.kind == StepKind::kClamp;
  if (part.has_surface()) {
    auto held_mesh = surface_mesh(held_vertices, held_faces);
    if (!held_mesh.ok()) return held_mesh.error();
    if (auto r = add_body("part", std::move(held_mesh).value(), {}, in_plane, true, part_pressed); !r.ok()) return r.error();
    if (bend) {
      auto flange = surface_mesh(moving_vertices, moving_faces);
      if (!flange.ok()) return flange.error();
      if (auto r = add_body("flange", std::move(flange).value(), {}, true, false, false); !r.ok()) return r.error();
    }
  } else {
    if (auto r = add_body("part", plates_mesh(held_plates), held_plates, in_plane, true, part_pressed); !r.ok()) return r.error();
    if (bend)
      if (auto r = add_body("flange", plates_mesh(moving_plates), moving_plates, true, false, false); !r.ok()) return r.error();
  }
  std::vector<Plate> manipulator = manipulator_plates(m, Vec2(state.manipulator_x_mm, state.manipulator_y_mm),
                                                      state.manipulator_rotation_deg, t);
  for (Plate& p : manipulator) p = p.transformed(pre);
  if (auto r = add_body("manipulator", plates_mesh(manipulator), manipulator, in_plane, false, false); !r.ok()) return r.error();
  if (bend) {
    // The flange turns past the manipulator holding the part: each of its plates is an obstacle
    // (meshed when the flange's sweep comes near it).
    prep.manipulator_plates = manipulator;
    prep.manipulator_meshes.resize(manipulator.size());
  }
  return keep();
}

Result<StepAnswer> StepValidator::validate(const SheetPart& part, const BendStep& step) {
  return validate(part, step, options_.compute_corrections);
}

Result<StepAnswer> StepValidator::validate(const SheetPart& part, const BendStep& step, bool with_corrections) {
  return answer_step(part, step, with_corrections, Figures::kReport);
}

Result<StepAnswer> StepValidator::answer_step(const SheetPart& part, const BendStep& step, bool with_corrections, Figures figures) {
  const auto t0 = Clock::now();
  auto valid = validate_step(scene_->model(), step);
  if (!valid.ok()) return valid.error();
  const std::uint64_t kind = figures == Figures::kVerdictOnly ? 3 : with_corrections ? 1 : 2;
  const Hash128 key = ContentHash().add(part.content_hash()).add(step.hash()).add(scene_->state().hash()).add(kind).value();
  const bool memoize = options_.memoize_answers || figures == Figures::kVerdictOnly;
  if (auto it = memoize ? memo_.find(key) : memo_.end(); it != memo_.end()) {
    StepAnswer hit = it->second;
    hit.decided_by = Stage::kCache;
    hit.times = StageTimes{};
    hit.times.cache_us = hit.times.total_us = us_since(t0);
    return hit;
  }
  auto result = run_pipeline(part, step, figures);
  if (!result.ok()) return result;
  StepAnswer& a = result.value();
  if (a.verdict == Verdict::kCollision && with_corrections) add_correction(part, step, a);
  a.times.cache_us = 0.0;
  a.times.total_us = us_since(t0);
  if (!memoize) return result;
  if (memo_.size() >= options_.memo_capacity) memo_.clear();
  memo_[key] = a;
  return result;
}

namespace {

// The deepest penetration of the body into the obstacle at a pose: SAT on the body's plates, or
// (for a surface) how deep its vertices lie inside the obstacle.
double depth_at(const MovingBody& body, const RigidTransform& pose, const ConvexPolytope& obstacle) {
  double depth = 0.0;
  Aabb obstacle_box;
  for (const Vec3& v : obstacle.vertices) obstacle_box.extend(v);
  if (!body.plates.empty()) {
    // A plate whose box misses the obstacle's is apart from it (depth 0): no SAT needed.
    for (const Plate& p : body.plates) {
      Aabb box;
      for (const Vec3& c : p.corners()) box.extend(pose.apply(c));
      if (box.overlaps(obstacle_box))
        depth = std::max(depth, penetration_depth(ConvexPolytope::plate(p.transformed(pose)), obstacle));
    }
    return depth;
  }
  // A surface: each triangle is convex, and separating the body separates each of them, so the
  // deepest triangle is a lower bound of the body's depth.
  const TriangleMesh& mesh = body.mesh->mesh();
  ConvexPolytope tri;
  tri.vertices.resize(3);
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Triangle corners = mesh.triangle(t);
    Aabb box;
    for (int k = 0; k < 3; ++k) box.extend(tri.vertices[k] = pose.apply(corners[k]));
    if (!box.overlaps(obstacle_box)) continue;
    const Vec3 n = (tri.vertices[1] - tri.vertices[0]).cross(tri.vertices[2] - tri.vertices[0]);
    if (!(n.norm() > 0.0)) continue;
    tri.face_normals = {n.normalized()};
    tri.edge_directions.clear();
    for (int k = 0; k < 3; ++k) tri.edge_directions.push_back((tri.vertices[(k + 1) % 3] - tri.vertices[k]).normalized());
    depth = std::max(depth, penetration_depth(tri, obstacle));
  }
  return depth;
}

// The body's plate `index` alone, as a body (for the figures of one manipulator part).
MovingBody plate_of(const MovingBody& body, std::size_t index) {
  MovingBody one;
  one.mesh = body.mesh;
  one.plates = {body.plates[index]};
  for (const Vec3& c : body.plates[index].corners()) one.points.push_back(c);
  return one;
}

// The plate of a body that names a collision: the deepest into the obstacle when it penetrates,
// else the nearest to the witness point (machine coordinates at the body's start).
std::size_t naming_plate(const MovingBody& body, const RigidTransform& pose, const ConvexPolytope& obstacle, const Vec3& witness) {
  std::size_t best = 0;
  double deepest = 0.0, nearest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < body.plates.size(); ++i) {
    const double d = penetration_depth(ConvexPolytope::plate(body.plates[i].transformed(pose)), obstacle);
    if (d > deepest) {
      deepest = d;
      best = i;
    }
  }
  if (deepest > 0.0) return best;
  ConvexPolytope point;
  point.vertices = {witness};
  for (std::size_t i = 0; i < body.plates.size(); ++i) {
    const double d = separation_lower_bound(point, ConvexPolytope::plate(body.plates[i]));
    if (d < nearest) {
      nearest = d;
      best = i;
    }
  }
  return best;
}

// Where a body that starts inside an obstacle is: the mean of the body's corners inside it, or of
// the obstacle's corners inside the body's plates, or the deepest plate's centre.
Vec3 inside_point(const MovingBody& body, const ConvexPolytope& obstacle) {
  Vec3 sum = Vec3::Zero();
  int n = 0;
  ConvexPolytope point;
  point.vertices.resize(1);
  for (const Plate& p : body.plates)
    for (const Vec3& c : p.corners()) {
      point.vertices[0] = c;
      if (penetration_depth(point, obstacle) > 0.0) {
        sum += c;
        ++n;
      }
    }
  for (const Vec3& c : obstacle.vertices)
    for (const Plate& p : body.plates) {
      point.vertices[0] = c;
      if (penetration_depth(point, ConvexPolytope::plate(p)) > 0.0) {
        sum += c;
        ++n;
        break;
      }
    }
  if (n > 0) return sum / n;
  // Edge through edge: the middle of where the deepest plate's box and the obstacle's box overlap.
  Aabb obstacle_box;
  for (const Vec3& v : obstacle.vertices) obstacle_box.extend(v);
  Aabb body_box;
  if (!body.plates.empty()) {
    for (const Vec3& c : body.plates[naming_plate(body, RigidTransform{}, obstacle, Vec3::Zero())].corners()) body_box.extend(c);
  } else {
    for (const Vec3& v : body.points) body_box.extend(v);
  }
  const Vec3 lo = body_box.min.cwiseMax(obstacle_box.min), hi = body_box.max.cwiseMin(obstacle_box.max);
  return 0.5 * (lo + hi);
}

// The deepest penetration over s in [s0, 1]: a grid of samples, then a golden-section search
// around the deepest one. A lower bound of the true deepest (exact when the depth is unimodal
// around the sample found).
double deepest_over_motion(const MovingBody& body, const Motion& motion, double s0, const ConvexPolytope& obstacle) {
  if (s0 >= 1.0) return depth_at(body, motion.at(1.0), obstacle);
  constexpr int kSamples = 64;
  double best = 0.0, best_s = s0;
  for (int i = 0; i <= kSamples; ++i) {
    const double s = s0 + (1.0 - s0) * i / kSamples;
    const double d = depth_at(body, motion.at(s), obstacle);
    if (d > best) {
      best = d;
      best_s = s;
    }
  }
  double a = std::max(s0, best_s - (1.0 - s0) / kSamples), b = std::min(1.0, best_s + (1.0 - s0) / kSamples);
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double c = b - g * (b - a), d = a + g * (b - a);
  double fc = depth_at(body, motion.at(c), obstacle), fd = depth_at(body, motion.at(d), obstacle);
  const double rate = std::max(1e-12, motion.rate(body.points));
  while ((b - a) * rate > tolerances::kStepDepthResolutionMm) {
    if (fc > fd) {
      b = d;
      d = c;
      fd = fc;
      c = b - g * (b - a);
      fc = depth_at(body, motion.at(c), obstacle);
    } else {
      a = c;
      c = d;
      fc = fd;
      d = a + g * (b - a);
      fd = depth_at(body, motion.at(d), obstacle);
    }
  }
  return std::max({best, fc, fd});
}

// The version of a body that meets an obstacle: outside the intended contact layer, if any.
const MovingBody* version_for(const StepBody& body, const Obstacle& obstacle) {
  if (obstacle.support && body.rests_on_supports) {
    for (const auto& [top, below] : body.below_support)
      if (top == obstacle.top_z) return below ? &*below : nullptr;
    return nullptr;
  }
  if (obstacle.pressing && body.pressed_by_aba) return body.above_pressing ? &*body.above_pressing : nullptr;
  return &body.whole;
}

// Does the body (version) start inside the obstacle, or the obstacle inside it? Penetration beyond
// the contact layer's tolerance (for intended contact) or any at all otherwise.
bool starts_inside(const StepBody& body, const MovingBody& version, const Obstacle& obstacle, double& depth) {
  depth = 0.0;
  if (!body.whole.mesh->root_bounds().overlaps(obstacle.box)) return false;
  const bool intended = (obstacle.support && body.rests_on_supports) || (obstacle.pressing && body.pressed_by_aba);
  depth = depth_at(body.whole, RigidTransform{}, obstacle.shape);
  if (body.whole.plates.empty()) depth = depth_at(version, RigidTransform{}, obstacle.shape);
  return depth > (intended ? tolerances::kIntendedContactMm : 0.0);
}

}  // namespace

Result<StepAnswer> StepValidator::run_pipeline(const SheetPart& part, const BendStep& step, Figures figures) {
  const bool report = figures == Figures::kReport;
  StepAnswer answer;
  auto t = Clock::now();
  auto prepared_or = prepare(part, step);
  if (!prepared_or.ok()) return prepared_or.error();
  const Prepared& prep = *prepared_or.value();
  answer.times.prepare_us = us_since(t);

  if (prep.limit.limit != MachineLimit::kNone) {
    answer.verdict = Verdict::kInconclusive;
    answer.denial = DenialReason::kMachineLimit;
    answer.limit = prep.limit.limit;
    answer.decided_by = Stage::kLimits;
    answer.reason = std::string("beyond the machine's limits (") + to_string(prep.limit.limit) + "): " + prep.limit.detail;
    return answer;
  }

  const std::vector<Organ>& organs = scene_->organs();
  const double required = options_.required_clearance_mm + prep.extra_clearance_mm;
  const double contact = required + tolerances::kStepContactResolutionMm;
  const double window = tolerances::kClearanceReportWindowMm;
  const double step_rad = options_.hull_sample_step_deg * kPi / 180.0;
  const bool bend = is_bend(step.kind);
  const bool clamped = bend || step.kind == StepKind::kClamp;

  // The organs as obstacles for this step, raised with the blankholder while the part moves
  // beneath it. The lower blade is an obstacle where the state parks it in every step, a BEND_UP
  // included (the blade starts from there; its forming path to the flange is not modelled).
  auto lifted = [&](const Organ& o) { return o.relative_to_clamp && prep.lift_mm != 0.0; };
  auto box_of = [&](int i) {
    const Organ& o = organs[i];
    if (!lifted(o)) return o.box;
    Aabb b = o.box;
    b.min.z() += prep.lift_mm;
    b.max.z() += prep.lift_mm;
    return b;
  };
  auto obstacle_of = [&](int i) {
    const Organ& o = organs[i];
    Obstacle ob;
    ob.name = o.name;
    ob.mesh = o.mesh.get();
    ob.pose = lifted(o) ? RigidTransform::from_translation(Vec3(0, 0, prep.lift_mm)) * o.pose : o.pose;
    ob.box = box_of(i);
    ob.shape = ConvexPolytope::prism(o.profile_yz, o.x_min, o.x_max).transformed(ob.pose);
    ob.support = o.support;
    ob.top_z = o.box.max.z();
    ob.pressing = clamped && o.is_aba_segment && o.engaged;
    return ob;
  };

  // Clearance bookkeeping for a CLEAR answer: every pair's proven lower bound and measured value.
  double lower_bound = std::numeric_limits<double>::infinity();
  auto measured = [&](double d, const std::string& organ, const Vec3& point) {
    if (d < answer.min_clearance_mm) {
      answer.min_clearance_mm = d;
      answer.clearance_organ = organ;
      answer.clearance_point_mm = point;
    }
  };

  // 1. Bodies held still: the held side of the part and the manipulator in CLAMP and bends; and,
  // in every step, the manipulator against the part it holds (they move together): its cups stand
  // on the sheet's upper face, and nothing of it may come near what stands above that face.
  t = Clock::now();
  {
    const StepBody* part_body = nullptr;
    const StepBody* manipulator = nullptr;
    for (const StepBody& b : prep.bodies) {
      if (b.name == "part") part_body = &b;
      if (b.name == "manipulator") manipulator = &b;
    }
    if (part_body && manipulator && part_body->above_sheet &&
        manipulator->whole.mesh->root_bounds().expanded(window).overlaps(part_body->above_sheet->mesh->root_bounds())) {
      DistanceRequest req;
      req.upper_bound_mm = report ? window : contact;
      auto d = distance(*manipulator->whole.mesh, RigidTransform{}, *part_body->above_sheet->mesh, RigidTransform{}, req);
      if (!d.ok()) return d.error();
      double depth = 0.0;
      std::size_t deepest_cup = 0, deepest_feature = 0;
      std::vector<Aabb> part_boxes;
      for (const Plate& p : part_body->whole.plates) {
        Aabb box;
        for (const Vec3& c : p.corners()) box.extend(c);
        part_boxes.push_back(box);
      }
      for (std::size_t i = 0; i < manipulator->whole.plates.size(); ++i) {
        Aabb cup_box;
        for (const Vec3& c : manipulator->whole.plates[i].corners()) cup_box.extend(c);
        const ConvexPolytope cup = ConvexPolytope::plate(manipulator->whole.plates[i]);
        for (std::size_t j = 0; j < part_body->whole.plates.size(); ++j) {
          if (!cup_box.overlaps(part_boxes[j])) continue;  // boxes apart: depth 0, no SAT needed
          const double dij = penetration_depth(cup, ConvexPolytope::plate(part_body->whole.plates[j]));
          if (dij > depth) {
            depth = dij;
            deepest_cup = i;
            deepest_feature = j;
          }
        }
      }
      if (depth > tolerances::kIntendedContactMm || (d.value().found && d.value().distance_mm <= contact)) {
        StepCollision col;
        const Vec3 witness = d.value().found ? d.value().point_b : inside_point(part_body->whole, ConvexPolytope::plate(manipulator->whole.plates[deepest_cup]));
        const ConvexPolytope witness_point{{witness}, {}, {}};
        if (!(depth > tolerances::kIntendedContactMm)) {
          double nearest = std::numeric_limits<double>::infinity();
          for (std::size_t j = 0; j < part_body->whole.plates.size(); ++j) {
            const double dj = separation_lower_bound(witness_point, ConvexPolytope::plate(part_body->whole.plates[j]));
            if (dj < nearest) {
              nearest = dj;
              deepest_feature = j;
            }
          }
          deepest_cup = naming_plate(manipulator->whole, RigidTransform{}, ConvexPolytope::plate(part_body->whole.plates[deepest_feature]),
                                     d.value().point_a);
        }
        col.organ = part_body->whole.plates.empty() ? "part" : "part." + part_body->whole.plates[deepest_feature].label;
        col.body = manipulator->whole.plates[deepest_cup].label;
        col.point_mm = col.point_at_start_mm = d.value().found ? d.value().point_a : witness;
        col.organ_point_mm = witness;
        col.depth_mm = std::max(0.0, depth);
        answer.collisions.push_back(col);
      } else if (d.value().found) {
        measured(d.value().distance_mm, "part", d.value().point_a);
        lower_bound = std::min(lower_bound, d.value().distance_mm);
      }
    }
  }
  for (const StepBody& body : prep.bodies) {
    if (body.moves) continue;
    const Aabb reach = body.whole.mesh->root_bounds().expanded(window);
    for (int i : scene_->organs_overlapping(reach)) {
      // Which version of the body meets this organ is known from the organ alone: most organs a
      // flat held part meets are its contact organs, with nothing outside the contact layer.
      Obstacle probe;
      probe.support = organs[i].support;
      probe.top_z = organs[i].box.max.z();
      probe.pressing = clamped && organs[i].is_aba_segment && organs[i].engaged;
      if (!version_for(body, probe)) continue;
      const Obstacle ob = obstacle_of(i);
      const MovingBody* version = version_for(body, ob);
      double depth = 0.0;
      const bool inside = starts_inside(body, *version, ob, depth);
      DistanceRequest req;
      req.upper_bound_mm = report ? window : contact;
      auto d = distance(*version->mesh, RigidTransform{}, *ob.mesh, ob.pose, req);
      if (!d.ok()) return d.error();
      if (inside || (d.value().found && d.value().distance_mm <= contact)) {
        StepCollision col;
        col.organ = ob.name;
        col.body = body.name;
        col.point_mm = d.value().found ? d.value().point_a : inside_point(*version, ob.shape);
        col.organ_point_mm = d.value().found ? d.value().point_b : col.point_mm;
        col.depth_mm = depth;
        if (body.name == "manipulator") {  // one of its parts: named with its own depth
          const std::size_t k = naming_plate(body.whole, RigidTransform{}, ob.shape, col.point_mm);
          col.body = body.whole.plates[k].label;
          col.depth_mm = depth_at(plate_of(body.whole, k), RigidTransform{}, ob.shape);
        }
        col.point_at_start_mm = col.point_mm;
        answer.collisions.push_back(col);
        continue;
      }
      if (d.value().found) {
        measured(d.value().distance_mm, ob.name, d.value().point_a);
        lower_bound = std::min(lower_bound, d.value().distance_mm);
      }
    }
  }
  answer.times.static_us = us_since(t);
  if (!answer.collisions.empty()) {
    answer.verdict = Verdict::kCollision;
    answer.decided_by = Stage::kStatic;
    const StepCollision& first = answer.collisions.front();
    answer.reason = first.body + " stands in " + first.organ +
                    (first.organ.rfind("part", 0) == 0 ? ", which the manipulator holds"
                     : step.kind == StepKind::kClamp   ? " where the blankholder closes"
                                                       : " while the part is clamped");
    return answer;
  }

  // The bodies that move, and the box their whole sweep stays in.
  std::vector<const StepBody*> moving;
  for (const StepBody& b : prep.bodies)
    if (b.moves) moving.push_back(&b);
  Aabb swept;
  for (const StepBody* b : moving) swept.extend(swept_bounds({b->whole}, prep.motion, step_rad));
  // Organs nobody examines further are at least their box distance away from every body.
  auto bound_unexamined = [&](const std::vector<char>& examined) {
    for (std::size_t i = 0; i < organs.size(); ++i) {
      if (examined[i]) continue;
      const Aabb organ_box = box_of(static_cast<int>(i));
      for (const StepBody& b : prep.bodies) {
        const Aabb box = b.moves ? swept : b.whole.mesh->root_bounds();
        lower_bound = std::min(lower_bound, box.distance(organ_box));
      }
    }
  };
  auto finish_clear = [&](Stage stage, std::string reason) {
    answer.verdict = Verdict::kClear;
    answer.decided_by = stage;
    answer.reason = std::move(reason);
    answer.min_clearance_lower_mm = std::min(lower_bound, answer.min_clearance_mm);
    return answer;
  };
  std::vector<char> examined(organs.size(), 0);
  for (const StepBody& b : prep.bodies)
    if (!b.moves)
      for (int i : scene_->organs_overlapping(b.whole.mesh->root_bounds().expanded(window))) examined[i] = 1;
  if (moving.empty()) {
    bound_unexamined(examined);
    return finish_clear(Stage::kStatic, "the blankholder closes on the sheet, and nothing stands where it presses or elsewhere in the machine");
  }

  // 2. Global box: the whole motion against the whole machine.
  t = Clock::now();
  const Aabb query = swept.expanded(required);
  Aabb machine;
  for (std::size_t i = 0; i < organs.size(); ++i)
    machine.extend(box_of(static_cast<int>(i)));
  for (const Plate& p : prep.manipulator_plates)
    for (const Vec3& c : p.corners()) machine.extend(c);
  answer.times.global_box_us = us_since(t);
  if (!query.overlaps(machine)) {
    bound_unexamined(examined);
    return finish_clear(Stage::kGlobalBox, "the motion's box misses the machine's box");
  }

  // 3. Broad phase over the organ tree (boxes lowered by the lift, so raised organs are found).
  t = Clock::now();
  Aabb tree_query = query;
  tree_query.min.z() -= prep.lift_mm;
  std::vector<Obstacle> obstacles;
  for (int i : scene_->organs_overlapping(tree_query)) {
    if (!box_of(i).overlaps(query)) continue;
    examined[i] = 1;
    obstacles.push_back(obstacle_of(i));
  }
  for (std::size_t k = 0; k < prep.manipulator_plates.size(); ++k) {
    Obstacle ob;
    ob.name = prep.manipulator_plates[k].label;
    for (const Vec3& c : prep.manipulator_plates[k].corners()) ob.box.extend(c);
    if (!ob.box.overlaps(query)) {
      lower_bound = std::min(lower_bound, swept.distance(ob.box));
      continue;
    }
    if (!prep.manipulator_meshes[k]) {
      auto bvh = MeshBvh::build(std::make_shared<const TriangleMesh>(plates_mesh({prep.manipulator_plates[k]})));
      if (!bvh.ok()) return bvh.error();
      prep.manipulator_meshes[k] = bvh.value();
    }
    ob.mesh = prep.manipulator_meshes[k].get();
    ob.shape = ConvexPolytope::plate(prep.manipulator_plates[k]);
    obstacles.push_back(std::move(ob));
  }
  if (step.kind == StepKind::kBendDown) {
    // The cheap lowest-point check: a flange turning down about the X axis reaches its exact
    // lowest point analytically (each point on its circle); obstacles wholly below it drop out.
    std::vector<Vec3> points;
    for (const StepBody* b : moving) points.insert(points.end(), b->whole.points.begin(), b->whole.points.end());
    const double lowest = lowest_point_of_rotation(points, prep.motion);
    answer.lowest_point_mm = lowest;
    obstacles.erase(std::remove_if(obstacles.begin(), obstacles.end(),
                                   [&](const Obstacle& o) {
                                     if (o.box.max.z() >= lowest - required) return false;
                                     lower_bound = std::min(lower_bound, lowest - o.box.max.z());
                                     return true;
                                   }),
                    obstacles.end());
  }
  bound_unexamined(examined);
  answer.candidate_organs = static_cast<int>(obstacles.size());
  answer.times.broad_us = us_since(t);

  // The pairs: each moving body (the version outside any intended contact layer) and obstacle.
  struct Pair {
    const StepBody* body;
    const MovingBody* version;
    const Obstacle* obstacle;
  };
  std::vector<Pair> pairs;
  for (const StepBody* b : moving)
    for (const Obstacle& ob : obstacles)
      if (const MovingBody* v = version_for(*b, ob)) pairs.push_back({b, v, &ob});
  auto collide_now = [&](const Pair& p, double s, const Vec3& on_body, const Vec3& on_organ, const Vec3& normal,
                         const std::string& why) {
    StepCollision col;
    col.organ = p.obstacle->name;
    col.body = p.body->name;
    col.point_mm = on_body;
    col.point_at_start_mm = prep.motion.at(s).inverse().apply(on_body);
    col.organ_point_mm = on_organ;
    col.normal = normal;
    col.first_contact_fraction = s;
    col.first_contact_deg = prep.motion.rotation ? std::fabs(prep.motion.angle_rad) * 180.0 / kPi * s : 0.0;
    const MovingBody* deepest = &p.body->whole;
    MovingBody part_of_manipulator;
    if (p.body->name == "manipulator") {  // one of its parts: named, and measured, alone
      const std::size_t k = naming_plate(p.body->whole, prep.motion.at(s), p.obstacle->shape, col.point_at_start_mm);
      col.body = p.body->whole.plates[k].label;
      part_of_manipulator = plate_of(p.body->whole, k);
      deepest = &part_of_manipulator;
    }
    col.depth_mm = report ? deepest_over_motion(*deepest, prep.motion, s, p.obstacle->shape) : 0.0;
    answer.collisions.push_back(col);
    answer.verdict = Verdict::kCollision;
    answer.decided_by = Stage::kNarrow;
    answer.reason = why;
    return answer;
  };
  // A body that starts inside an obstacle has no surface pair to find.
  for (const Pair& p : pairs) {
    double depth = 0.0;
    if (starts_inside(*p.body, *p.version, *p.obstacle, depth)) {
      const Vec3 where = inside_point(p.body->whole, p.obstacle->shape);
      return collide_now(p, 0.0, where, where, Vec3::Zero(), p.body->name + " starts inside " + p.obstacle->name);
    }
  }
  if (pairs.empty()) return finish_clear(Stage::kBroadPhase, "no organ's box meets the motion's box");

  // 4. Hull level of detail, per body version.
  t = Clock::now();
  std::vector<double> pair_lower(pairs.size(), 0.0);
  std::vector<char> narrow(pairs.size(), 0), hulled(pairs.size(), 0);
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (hulled[i]) continue;
    std::vector<SweepOrgan> organs_of;
    std::vector<std::size_t> which;
    for (std::size_t j = i; j < pairs.size(); ++j)
      if (pairs[j].version == pairs[i].version) {
        organs_of.push_back({static_cast<int>(j), pairs[j].obstacle->mesh, pairs[j].obstacle->pose, &pairs[j].obstacle->shape});
        which.push_back(j);
        hulled[j] = 1;
      }
    auto lod = hull_lod({*pairs[i].version}, prep.motion, organs_of, required, step_rad);
    if (!lod.ok()) return lod.error();
    for (std::size_t k = 0; k < which.size(); ++k) pair_lower[which[k]] = lod.value().lower_bound_mm[k];
    for (int k : lod.value().remaining) narrow[which[k]] = 1;
  }
  answer.times.hull_us = us_since(t);

  // 5. Narrow phase: conservative advancement of every remaining pair (piece by piece).
  t = Clock::now();
  for (const StepBody* b : moving) {
    bool needed = false;  // only a body with a pair left for the narrow phase is cut
    for (std::size_t i = 0; i < pairs.size(); ++i) needed = needed || (narrow[i] && pairs[i].body == b && pairs[i].version == &b->whole);
    if (!needed || !b->pieces.empty()) continue;
    if (prep.motion.rotation && !b->whole.plates.empty()) {
      // Advancement steps by the fastest point of a body: cutting the plates into bands of growing
      // distance from the rotation axis lets the slow band next to a tool take long steps.
      for (const Plate& plate : b->whole.plates)
        for (const Plate& band : radial_bands(plate, prep.motion)) {
          auto piece = make_body(plates_mesh({band}), {band});
          if (!piece.ok()) return piece.error();
          b->pieces.push_back(std::move(piece).value());
        }
    } else {
      b->pieces.push_back(b->whole);
    }
  }
  std::vector<SweepPair> sweep_pairs;
  std::vector<std::size_t> sweep_owner;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    if (!narrow[i]) continue;
    const bool whole = pairs[i].version == &pairs[i].body->whole;
    const SweepOrgan organ{static_cast<int>(i), pairs[i].obstacle->mesh, pairs[i].obstacle->pose, &pairs[i].obstacle->shape};
    if (whole) {
      for (const MovingBody& piece : pairs[i].body->pieces) {
        sweep_pairs.push_back({&piece, organ});
        sweep_owner.push_back(i);
      }
    } else {
      sweep_pairs.push_back({pairs[i].version, organ});
      sweep_owner.push_back(i);
    }
  }
  AdvanceOptions adv;
  adv.required_clearance_mm = required;
  adv.contact_resolution_mm = tolerances::kStepContactResolutionMm;
  adv.body_hull_step_rad = step_rad;
  SweepOutcome out;
  if (!sweep_pairs.empty()) {
    auto swept_or = conservative_advance(sweep_pairs, prep.motion, adv);
    if (!swept_or.ok()) return swept_or.error();
    out = swept_or.value();
  }
  answer.narrow_steps = out.steps;
  answer.times.narrow_us = us_since(t);
  if (out.collided) {
    const Pair& p = pairs[sweep_owner[out.organ]];
    return collide_now(p, out.contact_s, out.point_on_body, out.point_on_organ, out.normal,
                       out.contact_s == 0.0 ? "already within the required clearance of " + p.obstacle->name + " at the start"
                                            : p.body->name + " reaches " + p.obstacle->name + " during the motion");
  }
  if (out.budget_exceeded) {
    answer.verdict = Verdict::kInconclusive;
    answer.denial = DenialReason::kSweepBudget;
    answer.decided_by = Stage::kNarrow;
    answer.reason = "the motion grazes an organ for too long to certify (advancement budget exhausted)";
    return answer;
  }

  // The clearance over the whole motion. Every pair has a proven lower bound (the hull's gap, or
  // the advancement's); the bodies whose bound is below the report window are then narrowed to a
  // bracket against all their obstacles at once (each sample's queries bounded by the nearest so
  // far, so many equal segments cost little more than one).
  t = Clock::now();
  if (out.min_clearance_organ >= 0)
    measured(out.min_clearance_mm, pairs[sweep_owner[out.min_clearance_organ]].obstacle->name, out.min_clearance_point);
  struct Group {  // a body version and the obstacles it meets
    const StepBody* body;
    const MovingBody* version;
    std::vector<const Obstacle*> obstacles;
    std::vector<SweepOrgan> organs;
    std::vector<ConvexPolytope> shapes;
  };
  std::vector<Group> groups;
  auto group_of = [&](const Pair& p) {
    for (std::size_t g = 0; g < groups.size(); ++g)
      if (groups[g].body == p.body && groups[g].version == p.version) return g;
    groups.push_back({p.body, p.version, {}, {}, {}});
    return groups.size() - 1;
  };
  std::vector<std::size_t> pair_group(pairs.size());
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    pair_group[i] = group_of(pairs[i]);
    Group& g = groups[pair_group[i]];
    g.obstacles.push_back(pairs[i].obstacle);
    g.organs.push_back({-1, pairs[i].obstacle->mesh, pairs[i].obstacle->pose, &pairs[i].obstacle->shape});
    g.shapes.push_back(pairs[i].obstacle->shape);
  }
  struct Target {  // a moving body (a version or one of its pieces) and its group's lower bound
    const MovingBody* body;
    std::size_t group;
    double lower;
  };
  std::vector<Target> targets;
  auto lower_target = [&](const MovingBody* body, std::size_t group, double lower) {
    for (Target& x : targets)
      if (x.body == body) {
        x.lower = std::min(x.lower, lower);
        return;
      }
    targets.push_back({body, group, lower});
  };
  for (std::size_t i = 0; i < pairs.size(); ++i)
    if (!narrow[i]) lower_target(pairs[i].version, pair_group[i], pair_lower[i]);
  for (std::size_t k = 0; k < sweep_pairs.size(); ++k)
    lower_target(sweep_pairs[k].body, pair_group[sweep_owner[k]], out.pair_lower_mm[k]);
  std::sort(targets.begin(), targets.end(), [](const Target& x, const Target& y) { return x.lower < y.lower; });
  int budget = options_.clearance_query_budget;
  for (Target& x : targets) {
    const double best = std::min(answer.min_clearance_mm, window);
    const double tolerance = std::max(tolerances::kClearanceBracketMm, tolerances::kClearanceBracketRelative * best);
    if (!report || budget <= 0 || x.lower >= best - tolerance) continue;
    const Group& g = groups[x.group];
    auto bracket = clearance_bracket(*x.body, prep.motion, g.organs, window, tolerances::kClearanceBracketMm,
                                     tolerances::kClearanceBracketRelative, budget, answer.min_clearance_mm, &g.shapes);
    if (!bracket.ok()) return bracket.error();
    budget -= bracket.value().queries;
    x.lower = std::max(x.lower, bracket.value().lower_mm);
    if (bracket.value().upper_mm < std::numeric_limits<double>::infinity())
      measured(bracket.value().upper_mm, g.obstacles[bracket.value().organ]->name, bracket.value().point_on_body);
  }
  for (const Target& x : targets) lower_bound = std::min(lower_bound, x.lower);
  answer.times.clearance_us = us_since(t);
  const bool narrowed = !sweep_pairs.empty();
  return finish_clear(narrowed ? Stage::kNarrow : Stage::kHullLod,
                      narrowed ? "the exact sweep keeps its clearance from every organ"
                               : "the swept hull (inflated by the sagitta) clears every candidate organ");
}

}  // namespace gk::p4
