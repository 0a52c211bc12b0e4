// ValidateStep in process, cold (every cache emptied before each step), with every body (part,
// flange, manipulator) and every organ (supports and parked blade included):
//   build/tests/benchmarks/p4_benchmark [steps] [seed] [only_kind, e.g. ROTATE: for profiling]
// Populations:
//  - panel: a 2,000 mm panel's bend sequence (clamp, bend up, rotate) on the 50-segment ABA;
//  - random: random parts, states and steps of every kind (thickness 0.4-3.2 mm, angles to 135
//    degrees, random tabs, side flanges and ABA engagements) drawn from a seed, answered without
//    corrections; a third stop at a machine limit (mostly the manipulator point off the part) in
//    ~9 us, and "within limits" leaves those out;
//  - near_miss: steps that went to the narrow phase and came out CLEAR within 1 mm: those of the
//    random population, and those of ten times as many more random steps drawn from seed + 1
//    (near misses are rare: about 1 in 250 steps);
//  - denied_with_correction: the random steps denied by a collision, answered again with the
//    correction search (which validates every step of the sub-sequence it offers).
// Each line: count, p50, p90, p99, max in microseconds.
#include "machine_models/p4/step_validator.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <string>

namespace {

using namespace gk;
using namespace gk::p4;
using Clock = std::chrono::steady_clock;

struct Case {
  SheetPart part = SheetPart::from_plates({}, 1.0);
  BendStep step;
  MachineState state;
};

// The panel's sequence: for each side in turn, clamp and bend a 60 mm flange up 90 degrees, then
// rotate to the next side. The part grows its flanges as it goes.
std::vector<Case> panel_sequence(const MachineModel& model) {
  const double w = 2000.0, d = 1000.0, t = 1.5, h = 60.0;
  struct Side4 {
    Side side;
    Vec2 point, direction;
    double length, held;
  };
  const Side4 sides[4] = {{Side::kYMax, Vec2(0, d - h), Vec2(1, 0), w, d - h},
                          {Side::kYMin, Vec2(0, h), Vec2(-1, 0), w, d - 2 * h},
                          {Side::kXMax, Vec2(w - h, 0), Vec2(0, -1), d, w - h},
                          {Side::kXMin, Vec2(h, 0), Vec2(0, 1), d, w - 2 * h}};
  std::vector<Case> out;
  SheetPartSpec spec{w, d, t, {}, {}};
  for (int k = 0; k < 4; ++k) {
    const SheetPart part = SheetPart::create(spec).value();
    // The blankholder spans the bend, 70 mm short of each end to clear flanges already standing.
    MachineState state = MachineState::with_aba_span(model, -0.5 * sides[k].length + 70.0, 0.5 * sides[k].length - 70.0, t);
    state.manipulator_y_mm = -0.5 * sides[k].held;
    BendStep base;
    base.bend_point_mm = sides[k].point;
    base.bend_direction = sides[k].direction;
    BendStep clamp = base, bend = base, rotate = base;
    clamp.kind = StepKind::kClamp;
    bend.kind = StepKind::kBendUp;
    bend.target_angle_deg = 90.0;
    out.push_back({part, clamp, state});
    out.push_back({part, bend, state});
    spec.flanges.push_back({sides[k].side, h, 90.0, 0.0, 0.0});
    if (k < 3) {
      rotate.kind = StepKind::kRotate;
      rotate.rotate_angle_deg = k == 1 ? 90.0 : 180.0;
      out.push_back({SheetPart::create(spec).value(), rotate, state});
    }
  }
  return out;
}

// A random step of any kind on a random part; the manipulator mostly on the held side.
Case random_case(std::mt19937_64& rng, const MachineModel& model) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Case c;
  const double t = 0.4 + 2.8 * u(rng);
  SheetPartSpec spec{200.0 + 1800.0 * u(rng), 300.0 + 900.0 * u(rng), t, {}, {}};
  const double flange = 15.0 + 200.0 * u(rng);
  const double line = spec.depth_mm - flange;
  for (Side side : {Side::kXMin, Side::kXMax})
    if (u(rng) < 0.4)
      spec.flanges.push_back({side, 10.0 + 120.0 * u(rng), (u(rng) < 0.8 ? 1.0 : -1.0) * (30.0 + 100.0 * u(rng)), 0.0, std::max(1.0, line - 10.0)});
  if (u(rng) < 0.3) {
    const double x0 = spec.width_mm * u(rng) * 0.9;
    spec.tabs.push_back({x0, x0 + 10.0 + 60.0 * u(rng), std::max(0.0, line - 10.0 - 200.0 * u(rng)), 5.0 + 150.0 * u(rng)});
  }
  auto part = SheetPart::create(spec);
  if (!part.ok()) spec.tabs.clear();
  c.part = SheetPart::create(spec).value();
  const double pick = u(rng);
  c.step.kind = pick < 0.15 ? StepKind::kClamp
                : pick < 0.5 ? StepKind::kBendUp
                : pick < 0.7 ? StepKind::kBendDown
                : pick < 0.85 ? StepKind::kRotate
                : pick < 0.93 ? StepKind::kApproach
                              : StepKind::kRetract;
  c.step.bend_point_mm = Vec2(0.0, line);
  c.step.bend_direction = Vec2(1.0, 0.0);
  c.step.target_angle_deg = 10.0 + 125.0 * u(rng);
  c.step.rotate_angle_deg = (u(rng) < 0.5 ? -1.0 : 1.0) * (10.0 + 170.0 * u(rng));
  c.step.travel_mm = c.step.kind == StepKind::kApproach ? Vec3(-100.0 + 200.0 * u(rng), 300.0 * u(rng), 0.0)
                                                         : Vec3(-100.0 + 200.0 * u(rng), -300.0 * u(rng), 0.0);
  c.step.lateral_shift_mm = -200.0 + 400.0 * u(rng);
  c.state.clamp_z_mm = t;
  c.state.manipulator_x_mm = c.step.lateral_shift_mm + (-0.3 + 0.6 * u(rng)) * spec.width_mm;
  c.state.manipulator_x_mm = std::clamp(c.state.manipulator_x_mm, model.manipulator.travel_x_mm[0], model.manipulator.travel_x_mm[1]);
  c.state.manipulator_y_mm = std::clamp(-line * (0.3 + 0.7 * u(rng)) - 250.0 * u(rng), -1800.0, -50.0);
  c.state.engaged_segments.resize(model.aba.segment_widths_mm.size());
  for (std::size_t i = 0; i < c.state.engaged_segments.size(); ++i) c.state.engaged_segments[i] = u(rng) < 0.8;
  return c;
}

struct Population {
  std::vector<double> us;
  void add(double v) { us.push_back(v); }
  void print(const char* name) {
    if (us.empty()) {
      std::printf("%-24s %6d\n", name, 0);
      return;
    }
    std::sort(us.begin(), us.end());
    auto at = [&](double q) { return us[std::min(us.size() - 1, static_cast<std::size_t>(q * static_cast<double>(us.size())))]; };
    std::printf("%-24s %6zu %9.1f %9.1f %9.1f %9.1f\n", name, us.size(), at(0.5), at(0.9), at(0.99), us.back());
  }
};

double time_us(StepValidator& v, const Case& c, bool corrections, StepAnswer* answer) {
  (void)v.set_state(c.state);
  v.clear_caches();
  const auto t0 = Clock::now();
  auto a = v.validate(c.part, c.step, corrections);
  const double us = std::chrono::duration<double, std::micro>(Clock::now() - t0).count();
  if (!a.ok()) return -1.0;
  if (answer) *answer = a.value();
  return us;
}

}  // namespace

int main(int argc, char** argv) {
  const int count = argc > 1 ? std::atoi(argv[1]) : 3000;
  const unsigned long long seed = argc > 2 ? std::strtoull(argv[2], nullptr, 10) : 20261122ull;
  const std::string only = argc > 3 ? argv[3] : "";
  const MachineModel model = default_machine_model().value();
  auto scene = MachineScene::build(model).value();
  StepValidator validator(scene);

  Population panel, all, geometric, clear, collision, limit, near_miss, denied_corrected;
  std::map<std::string, Population> by_kind;
  const std::vector<Case> sequence = panel_sequence(model);
  std::vector<Population> panel_steps(sequence.size());
  std::vector<StepAnswer> panel_answers(sequence.size());
  for (int round = 0; round < 50; ++round)
    for (std::size_t k = 0; k < sequence.size(); ++k) {
      const double us = time_us(validator, sequence[k], false, &panel_answers[k]);
      panel.add(us);
      panel_steps[k].add(us);
    }

  std::mt19937_64 rng(seed);
  std::vector<Case> denied;
  StageTimes stage_sum;
  int errors = 0, verified = 0;
  std::map<std::string, int> outcomes;
  for (int i = 0; i < count; ++i) {
    const Case c = random_case(rng, model);
    if (!only.empty() && only != to_string(c.step.kind)) continue;
    StepAnswer a;
    const double us = time_us(validator, c, false, &a);
    if (us < 0.0) {
      ++errors;
      continue;
    }
    all.add(us);
    if (a.limit == MachineLimit::kNone) geometric.add(us);  // the steps whose geometry is examined
    by_kind[to_string(c.step.kind)].add(us);
    stage_sum.prepare_us += a.times.prepare_us;
    stage_sum.static_us += a.times.static_us;
    stage_sum.global_box_us += a.times.global_box_us;
    stage_sum.broad_us += a.times.broad_us;
    stage_sum.hull_us += a.times.hull_us;
    stage_sum.narrow_us += a.times.narrow_us;
    stage_sum.clearance_us += a.times.clearance_us;
    ++outcomes[std::string(to_string(a.verdict)) + (a.limit != MachineLimit::kNone ? std::string(" ") + to_string(a.limit) : "")];
    if (a.verdict == Verdict::kClear) clear.add(us);
    if (a.verdict == Verdict::kCollision) {
      collision.add(us);
      denied.push_back(c);
    }
    if (a.verdict == Verdict::kInconclusive) limit.add(us);
    if (a.verdict == Verdict::kClear && a.decided_by == Stage::kNarrow && a.min_clearance_mm < 1.0) {
      near_miss.add(us);
      ++outcomes["near miss at " + a.clearance_organ];
    }
  }
  // More near misses: a second, larger stream of random steps, of which only the near misses count.
  std::mt19937_64 more(seed + 1);
  StageTimes near_sum;
  for (int i = 0; i < 10 * count; ++i) {
    const Case c = random_case(more, model);
    if (!only.empty() && only != to_string(c.step.kind)) continue;
    StepAnswer a;
    const double us = time_us(validator, c, false, &a);
    if (us >= 0.0 && a.verdict == Verdict::kClear && a.decided_by == Stage::kNarrow && a.min_clearance_mm < 1.0) {
      near_miss.add(us);
      near_sum.prepare_us += a.times.prepare_us;
      near_sum.static_us += a.times.static_us;
      near_sum.hull_us += a.times.hull_us;
      near_sum.narrow_us += a.times.narrow_us;
      near_sum.clearance_us += a.times.clearance_us;
    }
  }
  std::map<std::string, Population> by_correction;
  for (const Case& c : denied) {
    StepAnswer a;
    const double us = time_us(validator, c, true, &a);
    if (us < 0.0) continue;
    denied_corrected.add(us);
    by_correction[std::string(to_string(c.step.kind)) + " -> " + to_string(a.correction.kind) +
                  (a.correction.verified ? " (verified)" : "")]
        .add(us);
    verified += a.correction.verified ? 1 : 0;
  }

  std::printf("p4_benchmark: %d random steps, seed %llu (cold: every cache emptied before each step)\n", count, seed);
  std::printf("%-24s %6s %9s %9s %9s %9s\n", "population", "count", "p50 us", "p90 us", "p99 us", "max us");
  panel.print("panel sequence");
  for (std::size_t k = 0; k < sequence.size(); ++k) {
    const StepAnswer& a = panel_answers[k];
    char label[160];
    std::snprintf(label, sizeof label, "  %zu %s: %s by %s, clearance [%.3g, %.3g] mm at %s", k, to_string(sequence[k].step.kind),
                  to_string(a.verdict), to_string(a.decided_by), a.min_clearance_lower_mm, a.min_clearance_mm,
                  a.clearance_organ.c_str());
    std::printf("%s\n", label);
    panel_steps[k].print("");
  }
  all.print("random, all");
  geometric.print("random, within limits");
  for (auto& [kind, p] : by_kind) p.print(("  " + kind).c_str());
  clear.print("  CLEAR");
  collision.print("  COLLISION");
  limit.print("  INCONCLUSIVE (limits)");
  near_miss.print("near miss (< 1 mm)");
  denied_corrected.print("denied + correction");
  for (auto& [kind, p] : by_correction) p.print(("  " + kind).c_str());
  std::printf("corrections verified: %d of %zu denied steps\n", verified, denied.size());
  const double n = static_cast<double>(std::max<std::size_t>(1, all.us.size()));
  std::printf("random steps, mean per stage (us): prepare %.1f, static %.1f, global box %.1f, broad %.1f, hull %.1f, "
              "narrow %.1f, clearance bracket %.1f\n",
              stage_sum.prepare_us / n, stage_sum.static_us / n, stage_sum.global_box_us / n, stage_sum.broad_us / n,
              stage_sum.hull_us / n, stage_sum.narrow_us / n, stage_sum.clearance_us / n);
  const double m = static_cast<double>(std::max<std::size_t>(1, near_miss.us.size()));
  std::printf("near misses of the second stream, mean per stage (us): prepare %.1f, static %.1f, hull %.1f, narrow %.1f, "
              "clearance bracket %.1f\n",
              near_sum.prepare_us / m, near_sum.static_us / m, near_sum.hull_us / m, near_sum.narrow_us / m, near_sum.clearance_us / m);
  for (const auto& [what, times] : outcomes) std::printf("  outcome %-40s %d\n", what.c_str(), times);
  if (errors) std::printf("  rejected as invalid input: %d\n", errors);
  return 0;
}
