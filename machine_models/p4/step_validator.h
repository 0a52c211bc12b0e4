// ValidateStep, in process: can the machine do this step with this part, and if not, what should
// the sequencer change? The lazy pipeline of seed 002 §4.3, made safe:
//   1 memo cache -> machine limits -> bodies held still (static check) -> 2 global box
//   -> 3 broad phase (organ BVH) -> 4 hull level of detail -> 5 narrow phase (conservative
//   advancement on the exact meshes: a parametric part's plates are exact polyhedra)
// Every body of the step is checked against every organ: the part (or, in a bend, its held side
// and its moving flange), the manipulator (cups, gripper frame, rotator column) and, in a bend,
// the manipulator as an obstacle of the flange. Intended contact is narrow: the part's lower face
// on a support's top face, its upper face under an engaged ABA segment (tolerances.h).
// Every answer says which stage decided it and how long each stage took.
#pragma once

#include "kernel/query/contact_verdict.h"
#include "kernel/core/tolerances.h"
#include "machine_models/p4/bend_step.h"
#include "machine_models/p4/machine_limits.h"
#include "machine_models/p4/machine_scene.h"
#include "machine_models/p4/motion_sweep.h"
#include "machine_models/p4/sheet_part.h"

#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

namespace gk::p4 {

enum class Stage { kCache, kLimits, kStatic, kGlobalBox, kBroadPhase, kHullLod, kNarrow };
const char* to_string(Stage stage);

// Why a step is denied without a collision (INCONCLUSIVE is a denial).
enum class DenialReason { kNone, kMachineLimit, kSweepBudget };
const char* to_string(DenialReason reason);

enum class CorrectionKind { kNone, kRepoShift, kChangeAba, kRetract, kFlip };
const char* to_string(CorrectionKind kind);

// One step of a corrected sub-sequence, with the machine state it runs in.
struct CorrectionStep {
  BendStep step;
  MachineState state;
  bool part_turned_over = false;  // FLIP: the step is for the part turned over
};

struct Correction {
  CorrectionKind kind = CorrectionKind::kNone;
  double lateral_shift_mm = 0.0;        // REPO: the new lateral shift of the part
  double shift_design_mm = 0.0;         // REPO: the design's shift (gap centre - feature centre)
  // REPO: the shifts that keep the feature in the gap with the required clearance; the returned
  // shift and both ends were validated CLEAR (the shifts between them were not each validated).
  double shift_range_mm[2] = {0, 0};
  double retract_mm = 0.0;              // RETRACT: how far to pull the manipulator back before rotating
  std::vector<bool> engaged_segments;   // CHANGE_ABA: the segments to engage instead
  // What to run instead of the denied step, in order; each was validated and is CLEAR when verified.
  std::vector<CorrectionStep> steps;
  bool verified = false;                // every step of `steps` was validated and is CLEAR
  std::string description;
};

struct StepCollision {
  std::string organ;                    // e.g. "aba.segment.12", "bed", "tower.left", "manipulator.rotator"
  std::string body;                     // what of the step hit it: "part", "flange", "manipulator.cup.0", ...
  Vec3 point_mm = Vec3::Zero();         // on the body, machine coordinates, at first contact
  Vec3 point_at_start_mm = Vec3::Zero();  // the same body point where it was when the step began
  Vec3 organ_point_mm = Vec3::Zero();   // on the organ
  Vec3 normal = Vec3::Zero();           // impact normal, from the organ towards the body
  double depth_mm = 0.0;                // deepest penetration found over the motion (0: within the clearance only)
  double first_contact_deg = 0.0;       // rotations: the largest angle this step can safely reach
  double first_contact_fraction = 0.0;  // of the motion, in [0, 1]
};

struct StageTimes {
  double cache_us = 0, prepare_us = 0, static_us = 0, global_box_us = 0, broad_us = 0, hull_us = 0, narrow_us = 0,
         clearance_us = 0, total_us = 0;
};

struct StepAnswer {
  Verdict verdict = Verdict::kInconclusive;  // CLEAR, COLLISION or INCONCLUSIVE (a denial)
  std::string reason;
  DenialReason denial = DenialReason::kNone;     // INCONCLUSIVE: why
  MachineLimit limit = MachineLimit::kNone;      // denial == kMachineLimit: which
  Stage decided_by = Stage::kNarrow;
  std::vector<StepCollision> collisions;
  // The smallest clearance over the whole step, between every body and every organ, as a proven
  // bracket: the true minimum lies in [min_clearance_lower_mm, min_clearance_mm]. min_clearance_mm
  // was measured (infinity: nothing was measured within the report window); the lower bound is
  // proven. Narrowed to tolerances::kClearanceBracket* within kClearanceReportWindowMm.
  double min_clearance_mm = std::numeric_limits<double>::infinity();
  double min_clearance_lower_mm = 0.0;
  std::string clearance_organ;
  Vec3 clearance_point_mm = Vec3::Zero();
  Correction correction;
  StageTimes times;
  double lowest_point_mm = std::numeric_limits<double>::quiet_NaN();  // BEND_DOWN: the sweep's lowest Z
  int candidate_organs = 0;
  int narrow_steps = 0;
};

struct ValidatorOptions {
  double required_clearance_mm = tolerances::kStepClearanceMm;
  double hull_sample_step_deg = 15.0;     // largest angle between hull samples
  int clearance_query_budget = 96;         // distance queries spent narrowing a CLEAR step's clearance
  int correction_search_budget = 16;       // steps validated (memo hits free) while searching a correction
  bool compute_corrections = true;
  std::size_t memo_capacity = 100000;     // answers kept (small)
  // Whether the answers validate() returns are memoised here. A caller with an answer cache of its
  // own (the engine's, engine/steps/step_answers) turns this off so that there is one; the
  // correction search's verdict-only answers are memoised either way.
  bool memoize_answers = true;
  std::size_t prepared_capacity = 2000;   // prepared steps kept...
  std::size_t prepared_triangle_budget = 1000000;  // ...and their bodies' triangles at most (about 250 MB)
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
  // What an answer carries besides its verdict: the figures a caller reads (the clearance bracket
  // over the motion, the depth of a collision), or none, for the correction search, which only
  // needs to know whether a candidate step is CLEAR and what it hits.
  enum class Figures { kReport, kVerdictOnly };
  Result<StepAnswer> answer_step(const SheetPart& part, const BendStep& step, bool with_corrections, Figures figures);
  Result<StepAnswer> run_pipeline(const SheetPart& part, const BendStep& step, Figures figures);
  Result<std::shared_ptr<const Prepared>> prepare(const SheetPart& part, const BendStep& step);
  void add_correction(const SheetPart& part, const BendStep& step, StepAnswer& answer);
  // Validates the steps in order, each in its state; true when every one is CLEAR. Restores the
  // scene's state.
  bool validate_sequence(const SheetPart& part, const std::vector<CorrectionStep>& steps);
  // validate() without corrections or figures, within the correction search's budget
  // (INCONCLUSIVE past it).
  Result<StepAnswer> validate_in_search(const SheetPart& part, const BendStep& step);
  int search_validations_left_ = 0;

  std::shared_ptr<MachineScene> scene_;
  ValidatorOptions options_;
  std::unordered_map<Hash128, StepAnswer, Hash128::Std> memo_;
  std::unordered_map<Hash128, std::shared_ptr<const Prepared>, Hash128::Std> prepared_;
  std::size_t prepared_triangles_ = 0;
};

}  // namespace gk::p4
