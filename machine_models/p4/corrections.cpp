// Corrections the sequencer can apply after a collision, computed and then verified: the corrected
// step is validated again and only a CLEAR answer is offered as verified.
#include "machine_models/p4/step_validator.h"

#include <algorithm>
#include <cmath>
#include <set>

namespace gk::p4 {

void StepValidator::add_correction(const SheetPart& part, const BendStep& step, StepAnswer& answer) {
  const MachineModel& model = scene_->model();
  const MachineState original = scene_->state();
  Correction& c = answer.correction;
  auto clear_with = [&](const BendStep& s) {
    auto r = validate(part, s, false);
    return r.ok() && r.value().verdict == Verdict::kClear;
  };
  const std::string& organ = answer.collisions.empty() ? std::string() : answer.collisions.front().organ;
  const bool hit_aba = organ.rfind("aba.segment.", 0) == 0;

  if (step.kind == StepKind::kBendDown && !hit_aba) {
    // The flange cannot clear the machine below: turn the part over and bend it up instead.
    const Vec2 across(-step.bend_direction.y(), step.bend_direction.x());
    const SheetPart flipped = part.turned_over(step.bend_point_mm, across);
    BendStep up = step;
    up.kind = StepKind::kBendUp;
    c.kind = CorrectionKind::kFlip;
    c.verified = [&] {
      auto r = validate(flipped, up, false);
      return r.ok() && r.value().verdict == Verdict::kClear;
    }();
    c.description = c.verified ? "turn the part over and bend up instead" : "turning the part over does not clear it either";
    return;
  }

  if (step.kind == StepKind::kRotate) {
    // Pull the manipulator back before turning: the smallest retract (to 1 mm) that clears.
    const double max_retract = original.manipulator_y_mm - model.manipulator.travel_y_mm[0];
    BendStep s = step;
    double lo = step.retract_mm, hi = -1.0;
    for (double r = std::max(1.0, step.retract_mm * 2.0); r <= max_retract; r *= 2.0) {
      s.retract_mm = r;
      if (clear_with(s)) {
        hi = r;
        break;
      }
      lo = r;
    }
    if (hi < 0.0 && max_retract > lo) {
      s.retract_mm = max_retract;
      if (clear_with(s)) hi = max_retract;
    }
    if (hi < 0.0) {
      c.kind = CorrectionKind::kRetract;
      c.description = "no retract within the manipulator's travel clears the rotation";
      return;
    }
    while (hi - lo > 1.0) {
      s.retract_mm = 0.5 * (lo + hi);
      (clear_with(s) ? hi : lo) = s.retract_mm;
    }
    c.kind = CorrectionKind::kRetract;
    c.retract_mm = std::ceil(hi);
    s.retract_mm = c.retract_mm;
    c.verified = clear_with(s);
    c.description = "retract the manipulator " + std::to_string(c.retract_mm) + " mm before rotating";
    return;
  }

  if (hit_aba && step.kind == StepKind::kClamp) {
    // Disengage the segments the part runs into, as long as something still clamps.
    std::vector<bool> engaged = original.engaged_segments;
    if (engaged.empty()) engaged.assign(model.aba.segment_widths_mm.size(), true);
    StepAnswer current = answer;
    for (int round = 0; round < 8 && current.verdict == Verdict::kCollision; ++round) {
      bool changed = false;
      for (const StepCollision& col : current.collisions) {
        if (col.organ.rfind("aba.segment.", 0) != 0) break;
        const auto slot = static_cast<std::size_t>(std::stoul(col.organ.substr(12)));
        if (engaged[slot]) {
          engaged[slot] = false;
          changed = true;
        }
      }
      if (!changed) break;
      MachineState trial = original;
      trial.engaged_segments = engaged;
      if (!scene_->apply_state(trial).ok()) break;
      auto r = validate(part, step, false);
      if (!r.ok()) break;
      current = r.value();
    }
    (void)scene_->apply_state(original);
    c.kind = CorrectionKind::kChangeAba;
    c.engaged_segments = engaged;
    c.verified = current.verdict == Verdict::kClear;
    c.description = c.verified ? "engage a blankholder that leaves the colliding features free" : "no blankholder set found";
    return;
  }

  if (hit_aba) {
    // REPO: shift the part along the bend line so the colliding feature lands in a gap between
    // engaged segments or clear of them; candidates from the slot edges, nearest first.
    const double x = answer.collisions.empty() ? 0.0 : answer.collisions.front().point_mm.x();
    std::set<double> shifts;
    for (std::size_t i = 0; i < model.aba.segment_widths_mm.size(); ++i) {
      const bool on = original.engaged_segments.empty() || original.engaged_segments[i];
      if (on) continue;
      shifts.insert(0.5 * (model.slot_x_min(i) + model.slot_x_max(i)) - x);  // into a gap's middle
    }
    for (std::size_t i = 0; i < model.aba.segment_widths_mm.size(); ++i) {
      shifts.insert(model.slot_x_min(i) - 5.0 - x);
      shifts.insert(model.slot_x_max(i) + 5.0 - x);
    }
    std::vector<double> ordered(shifts.begin(), shifts.end());
    std::sort(ordered.begin(), ordered.end(), [](double a, double b) { return std::fabs(a) < std::fabs(b); });
    int tried = 0;
    for (double shift : ordered) {
      if (std::fabs(shift) < 1e-9 || ++tried > 24) continue;
      BendStep s = step;
      s.lateral_shift_mm = step.lateral_shift_mm + shift;
      if (std::fabs(s.lateral_shift_mm) > model.max_bend_length_mm) continue;
      if (clear_with(s)) {
        c.kind = CorrectionKind::kRepoShift;
        c.lateral_shift_mm = s.lateral_shift_mm;
        c.verified = true;
        c.description = "shift the part " + std::to_string(shift) + " mm along the bend line";
        return;
      }
    }
    c.kind = CorrectionKind::kNone;
    c.description = "no lateral shift among the candidates clears it";
    return;
  }
  c.kind = CorrectionKind::kNone;
  c.description = "no correction applies to a collision with " + organ + " in a " + to_string(step.kind) + " step";
}

}  // namespace gk::p4
