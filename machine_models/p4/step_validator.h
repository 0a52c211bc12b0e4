// ValidateStep, in process: can the machine do this step with this part, and if not, what should
// the sequencer change? The lazy pipeline of seed 002 §4.3, made safe:
//   1 memo cache -> 2 global box -> 3 broad phase (organ BVH) -> 4 hull level of detail
//   -> 5 narrow phase (conservative advancement on the exact meshes) -> 6 exact B-Rep confirmation
// Every answer says which stage decided it and how long each stage took.
#pragma once

#include "kernel/contact_verdict.h"
#include "machine_models/p4/bend_step.h"
#include "machine_models/p4/machine_scene.h"
#include "machine_models/p4/motion_sweep.h"
#include "machine_models/p4/sheet_part.h"

#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace gk::p4 {

enum class Stage { kCache, kGlobalBox, kBroadPhase, kHullLod, kNarrow, kExact };
const char* to_string(Stage stage);

enum class CorrectionKind { kNone, kRepoShift, kChangeAba, kRetract, kFlip };
const char* to_string(CorrectionKind kind);

struct Correction {
  CorrectionKind kind = CorrectionKind::kNone;
  double lateral_shift_mm = 0.0;        // REPO: the new lateral shift of the part
  double retract_mm = 0.0;              // RETRACT: how far to pull the manipulator back before rotating
  std::vector<bool> engaged_segments;   // CHANGE_ABA: the segments to engage instead
  bool verified = false;                // the corrected step was validated again and is CLEAR
  std::string description;
};

struct StepCollision {
  std::string organ;                    // e.g. "aba.segment.12", "bed", "tower.left"
  Vec3 point_mm = Vec3::Zero();         // on the part, machine coordinates, at first contact
  Vec3 organ_point_mm = Vec3::Zero();   // on the organ
  Vec3 normal = Vec3::Zero();           // impact normal, from the organ towards the part
  double depth_mm = 0.0;                // deepest part vertex inside the organ at the step's end
  double first_contact_deg = 0.0;       // rotations: the largest angle this step can safely reach
  double first_contact_fraction = 0.0;  // of the motion, in [0, 1]
};

struct StageTimes {
  double cache_us = 0, prepare_us = 0, global_box_us = 0, broad_us = 0, hull_us = 0, narrow_us = 0, exact_us = 0, total_us = 0;
};

struct StepAnswer {
  Verdict verdict = Verdict::kInconclusive;  // CLEAR, COLLISION or INCONCLUSIVE (a denial)
  std::string reason;
  Stage decided_by = Stage::kNarrow;
  std::vector<StepCollision> collisions;
  double min_clearance_mm = std::numeric_limits<double>::infinity();  // when clear: smallest sampled clearance
  double certified_clearance_mm = std::numeric_limits<double>::infinity();
  std::string clearance_organ;
  Vec3 clearance_point_mm = Vec3::Zero();
  Correction correction;
  StageTimes times;
  double lowest_point_mm = std::numeric_limits<double>::quiet_NaN();  // BEND_DOWN: the sweep's lowest Z
  int candidate_organs = 0;
  int narrow_steps = 0;
};

struct ValidatorOptions {
  double required_clearance_mm = 0.1;     // seed 002 Table 1: minimum clearance about 0.1 mm
  double hull_sample_step_deg = 15.0;     // largest angle between hull samples
  double exact_window_mm = 0.05;          // confirm on B-Rep when the narrow clearance ends this close
  bool compute_corrections = true;
  std::size_t memo_capacity = 100000;
};

// Not thread-safe: give each thread its own validator (they may share nothing but the model).
class StepValidator {
 public:
  StepValidator(std::shared_ptr<MachineScene> scene, ValidatorOptions options = {});

  // The machine state (refits the organ tree); clears nothing: answers are keyed by state.
  Result<bool> set_state(const MachineState& state);
  const MachineScene& scene() const { return *scene_; }

  Result<StepAnswer> validate(const SheetPart& part, const BendStep& step);
  // The same, choosing per call whether a denied step gets a correction.
  Result<StepAnswer> validate(const SheetPart& part, const BendStep& step, bool with_corrections);

  std::size_t memo_size() const { return memo_.size(); }
  void clear_caches();  // answers and prepared geometry
  void clear_memo() { memo_.clear(); }

 private:
  struct Prepared;
  Result<StepAnswer> run_pipeline(const SheetPart& part, const BendStep& step);
  Result<std::shared_ptr<const Prepared>> prepare(const SheetPart& part, const BendStep& step);
  void add_correction(const SheetPart& part, const BendStep& step, StepAnswer& answer);

  std::shared_ptr<MachineScene> scene_;
  ValidatorOptions options_;
  std::unordered_map<std::uint64_t, StepAnswer> memo_;
  std::unordered_map<std::uint64_t, std::shared_ptr<const Prepared>> prepared_;
};

}  // namespace gk::p4
