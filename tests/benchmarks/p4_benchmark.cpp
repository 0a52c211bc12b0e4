// ValidateStep in process: a 2,000 mm panel getting four flanges, every step of its bend sequence
// (clamp, bend, rotate) against the default model's 50-segment ABA.
//   build/tests/benchmarks/p4_benchmark
// Modes: cold (every cache empty: geometry prepared and all stages run), geometry-warm (the
// part's bodies are prepared, the answer is not memoised: what a sequencer trying new machine
// states sees), and memo hit. Counters: p50/p99 per step in microseconds, mean per stage.
#include "machine_models/p4/step_validator.h"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>

namespace {

using namespace gk;
using namespace gk::p4;
using Clock = std::chrono::steady_clock;

struct SequenceStep {
  SheetPart part = SheetPart::from_plates({}, 1.0);
  BendStep step;
  MachineState state;
};

// The panel's sequence: for each side in turn, clamp and bend a 60 mm flange up 90 degrees, then
// rotate to the next side. The part grows its flanges as it goes.
std::vector<SequenceStep> panel_sequence(const MachineModel& model) {
  const double w = 2000.0, d = 1000.0, t = 1.5, h = 60.0;
  struct Side4 {
    Side side;
    Vec2 point, direction;
    double length;
  };
  const Side4 sides[4] = {{Side::kYMax, Vec2(0, d - h), Vec2(1, 0), w},
                          {Side::kYMin, Vec2(0, h), Vec2(-1, 0), w},
                          {Side::kXMax, Vec2(w - h, 0), Vec2(0, -1), d},
                          {Side::kXMin, Vec2(h, 0), Vec2(0, 1), d}};
  std::vector<SequenceStep> out;
  SheetPartSpec spec{w, d, t, {}, {}};
  for (int k = 0; k < 4; ++k) {
    const SheetPart part = SheetPart::create(spec).value();
    // The blankholder spans the bend, 70 mm short of each end to clear flanges already standing.
    MachineState state = MachineState::with_aba_span(model, -0.5 * sides[k].length + 70.0, 0.5 * sides[k].length - 70.0, t);
    BendStep base;
    base.bend_point_mm = sides[k].point;
    base.bend_direction = sides[k].direction;
    BendStep clamp = base, bend = base, rotate = base;
    clamp.kind = StepKind::kClamp;
    bend.kind = StepKind::kBendUp;
    bend.target_angle_deg = 90.0;
    out.push_back({part, clamp, state});
    out.push_back({part, bend, state});
    // The flat flange of the next state is the bent one: the flange is part of the blank until bent.
    spec.flanges.push_back({sides[k].side, h, 90.0, 0.0, 0.0});
    spec.width_mm = w;
    if (k < 3) {
      const SheetPart bent = SheetPart::create(spec).value();
      rotate.kind = StepKind::kRotate;
      rotate.rotate_angle_deg = k == 1 ? 90.0 : 180.0;
      MachineState rs = state;
      rs.manipulator_y_mm = -900.0;
      out.push_back({bent, rotate, rs});
    }
  }
  return out;
}

enum class Mode { kCold, kGeometryWarm, kMemoHit };

void run(benchmark::State& state, Mode mode) {
  const MachineModel model = default_machine_model().value();
  auto scene = MachineScene::build(model).value();
  StepValidator validator(scene);
  const auto sequence = panel_sequence(model);
  std::vector<double> totals;
  StageTimes sum;
  long long answers = 0, collisions = 0;
  // Prime the caches the mode keeps.
  for (const SequenceStep& s : sequence) {
    (void)validator.set_state(s.state);
    (void)validator.validate(s.part, s.step);
  }
  for (auto _ : state) {
    for (const SequenceStep& s : sequence) {
      (void)validator.set_state(s.state);
      if (mode == Mode::kCold) validator.clear_caches();
      if (mode == Mode::kGeometryWarm) validator.clear_memo();
      const auto t0 = Clock::now();
      auto a = validator.validate(s.part, s.step);
      totals.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
      if (!a.ok()) {
        state.SkipWithError(a.error().to_string().c_str());
        return;
      }
      const StageTimes& st = a.value().times;
      sum.cache_us += st.cache_us;
      sum.prepare_us += st.prepare_us;
      sum.global_box_us += st.global_box_us;
      sum.broad_us += st.broad_us;
      sum.hull_us += st.hull_us;
      sum.narrow_us += st.narrow_us;
      sum.static_us += st.static_us;
      sum.clearance_us += st.clearance_us;
      ++answers;
      collisions += a.value().verdict == Verdict::kClear ? 0 : 1;
    }
  }
  std::sort(totals.begin(), totals.end());
  const double n = static_cast<double>(answers);
  state.counters["steps_per_sequence"] = static_cast<double>(sequence.size());
  state.counters["p50_us"] = totals[totals.size() / 2];
  state.counters["p99_us"] = totals[totals.size() * 99 / 100];
  state.counters["max_us"] = totals.back();
  state.counters["stage_prepare_us"] = sum.prepare_us / n;
  state.counters["stage_global_us"] = sum.global_box_us / n;
  state.counters["stage_broad_us"] = sum.broad_us / n;
  state.counters["stage_hull_us"] = sum.hull_us / n;
  state.counters["stage_narrow_us"] = sum.narrow_us / n;
  state.counters["stage_static_us"] = sum.static_us / n;
  state.counters["stage_clearance_us"] = sum.clearance_us / n;
  state.counters["not_clear"] = static_cast<double>(collisions) / static_cast<double>(state.iterations());
}

void BM_P4Sequence_Cold(benchmark::State& s) { run(s, Mode::kCold); }
void BM_P4Sequence_GeometryWarm(benchmark::State& s) { run(s, Mode::kGeometryWarm); }
void BM_P4Sequence_MemoHit(benchmark::State& s) { run(s, Mode::kMemoHit); }

// A denied step: a 300 mm flange bent up hits the upper beam (first contact near 42.6 degrees).
// Cold every time; `corrections` says whether the correction search runs (the registered run: without).
void collision_step(benchmark::State& state, bool corrections) {
  const MachineModel model = default_machine_model().value();
  auto scene = MachineScene::build(model).value();
  ValidatorOptions options;
  options.compute_corrections = corrections;
  StepValidator validator(scene, options);
  MachineState s;
  s.clamp_z_mm = 1.5;
  (void)validator.set_state(s);
  const SheetPart part = SheetPart::create({1000.0, 800.0, 1.5, {}, {}}).value();
  BendStep step;
  step.kind = StepKind::kBendUp;
  step.bend_point_mm = Vec2(0.0, 500.0);
  step.target_angle_deg = 90.0;
  std::vector<double> totals;
  for (auto _ : state) {
    validator.clear_caches();
    const auto t0 = Clock::now();
    auto a = validator.validate(part, step);
    totals.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    if (!a.ok() || a.value().verdict != Verdict::kCollision) {
      state.SkipWithError("expected a collision");
      return;
    }
  }
  std::sort(totals.begin(), totals.end());
  state.counters["p50_us"] = totals[totals.size() / 2];
  state.counters["p99_us"] = totals[totals.size() * 99 / 100];
}

void BM_P4DeniedStep_Cold(benchmark::State& s) { collision_step(s, false); }

}  // namespace

BENCHMARK(BM_P4DeniedStep_Cold)->Unit(benchmark::kMicrosecond)->Iterations(1000);
BENCHMARK(BM_P4Sequence_Cold)->Unit(benchmark::kMillisecond)->Iterations(200);
BENCHMARK(BM_P4Sequence_GeometryWarm)->Unit(benchmark::kMillisecond)->Iterations(200);
BENCHMARK(BM_P4Sequence_MemoHit)->Unit(benchmark::kMillisecond)->Iterations(2000);

BENCHMARK_MAIN();
