// Corrections the sequencer can apply after a collision. Each is a sub-sequence of steps that
// replaces the denied one, every motion it adds included; it is offered as verified only when
// every step of it was validated, in its own machine state, and is CLEAR.
#include "machine_models/p4/step_validator.h"
#include "kernel/core/tolerances.h"

#include <algorithm>
#include <cmath>

namespace gk::p4 {
namespace {

bool is_aba(const std::string& organ) { return organ.rfind("aba.segment.", 0) == 0; }

// How closely the smallest clearing retract is searched: a few validations fewer per halving. [mm]

// The x-range of the part's feature at a machine point: the plate nearest to it, placed for the step.
std::pair<double, double> feature_x_range(const SheetPart& part, const BendStep& step, const Vec3& point) {
  if (part.has_surface()) return {point.x(), point.x()};
  const RigidTransform placement = part_placement(part, step);
  double best = std::numeric_limits<double>::infinity();
  std::pair<double, double> range{point.x(), point.x()};
  for (const Plate& plate : part.plates()) {
    const Plate placed = plate.transformed(placement);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    Aabb box;
    for (const Vec3& c : placed.corners()) {
      lo = std::min(lo, c.x());
      hi = std::max(hi, c.x());
      box.extend(c);
    }
    double sq = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double gap = std::max({0.0, box.min[k] - point[k], point[k] - box.max[k]});
      sq += gap * gap;
    }
    // The blank runs under everything: prefer the smaller feature when two touch the point (squared
    // distances within 1e-9 mm^2 are a tie; which feature is named, not whether anything collides).
    constexpr double kTieMm2 = 1e-9;
    if (sq < best - kTieMm2 || (sq <= best + kTieMm2 && hi - lo < range.second - range.first)) {
      best = sq;
      range = {lo, hi};
    }
  }
  return range;
}

}  // namespace

Result<StepAnswer> StepValidator::validate_in_search(const SheetPart& part, const BendStep& step) {
  if (search_validations_left_ <= 0) {
    StepAnswer refused;
    refused.verdict = Verdict::kInconclusive;
    refused.reason = "the correction search's budget of validations is spent";
    return refused;
  }
  auto a = answer_step(part, step, false, Figures::kVerdictOnly);
  if (a.ok() && a.value().decided_by != Stage::kCache) --search_validations_left_;
  return a;
}

bool StepValidator::validate_sequence(const SheetPart& part, const std::vector<CorrectionStep>& steps) {
  const MachineState original = scene_->state();
  bool clear = true;
  for (const CorrectionStep& s : steps) {
    if (!scene_->apply_state(s.state).ok()) {
      clear = false;
      break;
    }
    auto r = validate_in_search(part, s.step);
    if (!r.ok() || r.value().verdict != Verdict::kClear) {
      clear = false;
      break;
    }
  }
  (void)scene_->apply_state(original);
  return clear;
}

void StepValidator::add_correction(const SheetPart& part, const BendStep& step, StepAnswer& answer) {
  const MachineModel& model = scene_->model();
  const MachineState original = scene_->state();
  Correction& c = answer.correction;
  if (answer.collisions.empty()) return;
  search_validations_left_ = options_.correction_search_budget;
  // Whatever the search ends with, say so when it ran out of validations.
  struct Note {
    const int& left;
    Correction& c;
    ~Note() {
      if (left <= 0 && !c.verified) c.description += " (the search stopped at its budget of validations)";
    }
  } note{search_validations_left_, c};
  const StepCollision& hit = answer.collisions.front();
  const bool bend = step.kind == StepKind::kBendUp || step.kind == StepKind::kBendDown;
  const bool part_hit = hit.body == "part" || hit.body == "flange";
  auto clamp_step = [&](const BendStep& s) {
    BendStep clamp = s;
    clamp.kind = StepKind::kClamp;
    return clamp;
  };

  if (step.kind == StepKind::kBendDown && !is_aba(hit.organ) && hit.body == "flange") {
    // The flange cannot clear the machine below: turn the part over and bend it up instead.
    const Vec2 across(-step.bend_direction.y(), step.bend_direction.x());
    const SheetPart flipped = part.turned_over(step.bend_point_mm, across);
    BendStep up = step;
    up.kind = StepKind::kBendUp;
    c.kind = CorrectionKind::kFlip;
    c.steps = {{up, original, true}};
    auto r = validate_in_search(flipped, up);
    c.verified = r.ok() && r.value().verdict == Verdict::kClear;
    c.description = c.verified ? "turn the part over and bend up instead" : "turning the part over does not clear it either";
    return;
  }

  if (step.kind == StepKind::kRotate) {
    // Pull the manipulator back, turn, and come back: the retract, the rotation and the
    // re-approach each validated. The smallest retract (to 8 mm) whose rotation clears is found
    // first, then grown until the three steps clear together.
    const double max_retract = original.manipulator_y_mm - model.manipulator.travel_y_mm[0];
    auto sequence = [&](double r) {
      BendStep back = step, turn = step, again = step;
      back.kind = StepKind::kRetract;
      back.travel_mm = Vec3(0, -r, 0);
      back.retract_mm = step.retract_mm;
      turn.retract_mm = step.retract_mm + r;
      again.kind = StepKind::kApproach;
      again.travel_mm = Vec3(0, r, 0);
      again.retract_mm = step.retract_mm + r;
      again.turned_deg = step.rotate_angle_deg;
      return std::vector<CorrectionStep>{{back, original, false}, {turn, original, false}, {again, original, false}};
    };
    auto turn_clears = [&](double r) {
      BendStep turn = step;
      turn.retract_mm = step.retract_mm + r;
      auto a = validate_in_search(part, turn);
      return a.ok() && a.value().verdict == Verdict::kClear;
    };
    c.kind = CorrectionKind::kRetract;
    double lo = 0.0, hi = -1.0;
    for (double r = 32.0; r <= max_retract; r *= 2.0) {
      if (turn_clears(r)) {
        hi = r;
        break;
      }
      lo = r;
    }
    if (hi < 0.0 && max_retract > lo && turn_clears(max_retract)) hi = max_retract;
    if (hi < 0.0) {
      c.description = "no retract within the manipulator's travel clears the rotation";
      return;
    }
    while (hi - lo > tolerances::kRetractResolutionMm) {
      const double mid = 0.5 * (lo + hi);
      (turn_clears(mid) ? hi : lo) = mid;
    }
    for (double r = std::min(std::ceil(hi), max_retract); r <= max_retract; r = std::min(max_retract, std::max(r + 1.0, r * 1.5))) {
      std::vector<CorrectionStep> steps = sequence(r);
      if (validate_sequence(part, steps)) {
        c.retract_mm = r;
        c.steps = std::move(steps);
        c.verified = true;
        c.description = "retract the manipulator " + std::to_string(r) + " mm, rotate, and approach again";
        return;
      }
      if (r >= max_retract) break;
    }
    c.retract_mm = std::ceil(hi);
    c.steps = sequence(c.retract_mm);
    c.description = "the rotation clears after a " + std::to_string(c.retract_mm) +
                    " mm retract, but the retract or the re-approach does not";
    return;
  }

  if (!(is_aba(hit.organ) && part_hit && (bend || step.kind == StepKind::kClamp))) {
    c.kind = CorrectionKind::kNone;
    c.description = "no correction applies to " + hit.body + " against " + hit.organ + " in a " + to_string(step.kind) + " step";
    return;
  }

  // REPO: shift the part along the bend line so that the colliding feature stands under a gap of
  // disengaged segments: the design's shift is (gap centre - feature centre); the clearing shift
  // nearest to it is returned with the interval of clearing shifts around it. The lateral move
  // (ABA open), the clamp and the step are validated at the new position.
  // (plain variables, not a structured binding: C++17 lambdas cannot capture those)
  const std::pair<double, double> feature = feature_x_range(part, step, hit.point_at_start_mm);
  const double fx0 = feature.first, fx1 = feature.second;
  const double feature_centre = 0.5 * (fx0 + fx1), feature_width = fx1 - fx0;
  const auto spans = model.slot_spans();
  std::vector<std::pair<double, double>> gaps;
  for (std::size_t i = 0; i < spans.size();) {
    const bool on = original.engaged_segments.empty() || original.engaged_segments[i];
    if (on) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j + 1 < spans.size() && !(original.engaged_segments[j + 1])) ++j;
    if (spans[j].second - spans[i].first >= feature_width + 2.0 * options_.required_clearance_mm)
      gaps.emplace_back(spans[i].first, spans[j].second);
    i = j + 1;
  }
  std::sort(gaps.begin(), gaps.end(), [&](const auto& a, const auto& b) {
    return std::fabs(0.5 * (a.first + a.second) - feature_centre) < std::fabs(0.5 * (b.first + b.second) - feature_centre);
  });
  // CHANGE_ABA: disengage the segments over the features that run into the blankholder, as long
  // as what is left still clamps the part: the new clamp and the step are validated.
  auto try_change_aba = [&]() {
    std::vector<bool> engaged = original.engaged_segments;
    if (engaged.empty()) engaged.assign(model.aba.segment_widths_mm.size(), true);
    StepAnswer current = answer;
    std::vector<CorrectionStep> steps;
    bool clear = false;
    for (int round = 0; round < 6 && current.verdict == Verdict::kCollision; ++round) {
      bool changed = false;
      for (const StepCollision& col : current.collisions) {
        if (!is_aba(col.organ) || (col.body != "part" && col.body != "flange")) continue;
        const auto [x0, x1] = feature_x_range(part, step, col.point_at_start_mm);
        const double margin = options_.required_clearance_mm + 1.0;
        for (std::size_t i = 0; i < engaged.size(); ++i)
          if (engaged[i] && spans[i].second > x0 - margin && spans[i].first < x1 + margin) {
            engaged[i] = false;
            changed = true;
          }
      }
      if (!changed) break;
      MachineState trial = original;
      trial.engaged_segments = engaged;
      steps = {{clamp_step(step), trial, false}};
      if (bend) steps.push_back({step, trial, false});
      if (!scene_->apply_state(trial).ok()) break;
      auto clamp_answer = validate_in_search(part, clamp_step(step));
      auto r = bend && clamp_answer.ok() && clamp_answer.value().verdict == Verdict::kClear ? validate_in_search(part, step)
                                                                                             : clamp_answer;
      (void)scene_->apply_state(original);
      if (!r.ok()) break;
      current = r.value();
      clear = current.verdict == Verdict::kClear;
    }
    if (clear && validate_sequence(part, steps)) {
      c.kind = CorrectionKind::kChangeAba;
      c.engaged_segments = engaged;
      c.steps = std::move(steps);
      c.verified = true;
      c.description = "engage a blankholder that leaves the colliding features free";
      return true;
    }
    return false;
  };

  auto repo_steps = [&](double shift) {
    BendStep move = step, shifted = step;
    move.kind = StepKind::kApproach;
    move.travel_mm = Vec3(shift, 0, 0);
    move.retract_mm = 0.0;
    move.turned_deg = 0.0;
    shifted.lateral_shift_mm = step.lateral_shift_mm + shift;
    MachineState there = original;
    there.manipulator_x_mm += shift;
    std::vector<CorrectionStep> steps = {{move, original, false}, {clamp_step(shifted), there, false}};
    if (bend) steps.push_back({shifted, there, false});
    return steps;
  };
  // Only the step at the new position while searching: with the part held where the clamp holds
  // it, a clear bend implies a clear clamp. The whole sub-sequence is validated once at the end.
  auto step_clears = [&](double shift) {
    if (std::fabs(step.lateral_shift_mm + shift) > model.max_bend_length_mm) return false;
    BendStep shifted = step;
    shifted.lateral_shift_mm = step.lateral_shift_mm + shift;
    MachineState there = original;
    there.manipulator_x_mm += shift;
    return validate_sequence(part, {{shifted, there, false}});
  };
  auto try_repo = [&]() {
    for (std::size_t g = 0; g < gaps.size() && g < 2; ++g) {
      const double design = 0.5 * (gaps[g].first + gaps[g].second) - feature_centre;
      // The shifts the rule allows: the feature inside the gap, the required clearance from its edges.
      const double margin = options_.required_clearance_mm + 2.0 * tolerances::kStepContactResolutionMm;
      double lo = gaps[g].first + margin - fx0, hi = gaps[g].second - margin - fx1;
      if (lo > hi) continue;
      // The clearing shift nearest the design's: the design itself, or the nearest of a few probes.
      std::vector<double> probes = {design, 0.5 * (lo + design), 0.5 * (hi + design), lo, hi};
      std::sort(probes.begin() + 1, probes.end(), [&](double x, double y) { return std::fabs(x - design) < std::fabs(y - design); });
      double found = std::numeric_limits<double>::quiet_NaN();
      for (double x : probes)
        if (std::isnan(found) && x >= lo && x <= hi && step_clears(x)) found = x;
      if (std::isnan(found)) continue;
      // The range's ends, validated: an end that does not clear is pulled halfway to the shift
      // found, three times at most.
      auto settle = [&](double end) {
        for (int k = 0; k < 3 && end != found; ++k, end = 0.5 * (end + found))
          if (step_clears(end)) return end;
        return found;
      };
      lo = settle(lo);
      hi = settle(hi);
      std::vector<CorrectionStep> steps = repo_steps(found);
      if (!validate_sequence(part, steps)) continue;  // the lateral move or the clamp does not clear
      c.lateral_shift_mm = step.lateral_shift_mm + found;
      c.shift_design_mm = design;
      c.shift_range_mm[0] = step.lateral_shift_mm + lo;
      c.shift_range_mm[1] = step.lateral_shift_mm + hi;
      c.steps = std::move(steps);
      c.verified = true;
      c.kind = CorrectionKind::kRepoShift;
      c.description = "shift the part " + std::to_string(found) + " mm along the bend line (the design's " +
                      std::to_string(design) + " mm: gap centre - feature centre)";
      return true;
    }
    return false;
  };
  // The sequencer's blankholder has a gap that fits the feature: move the part to it first;
  // otherwise change the blankholder.
  if (!gaps.empty() && try_repo()) return;
  if (try_change_aba()) return;
  c.kind = CorrectionKind::kNone;
  c.description = gaps.empty() ? "no gap of disengaged segments is wide enough for the feature, and no blankholder change clears it"
                               : "no shift into a gap of disengaged segments clears it, nor does a blankholder change";
}

}  // namespace gk::p4
