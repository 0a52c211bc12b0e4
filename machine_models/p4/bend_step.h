// One step of a bend sequence, and where it puts the part in the machine.
#pragma once

#include "kernel/core/content_hash.h"
#include "kernel/core/rigid_transform.h"
#include "kernel/core/status.h"
#include "machine_models/p4/machine_model.h"
#include "machine_models/p4/sheet_part.h"

#include <cstdint>
#include <string>

namespace gk::p4 {

enum class StepKind { kClamp, kBendUp, kBendDown, kRotate, kApproach, kRetract };
const char* to_string(StepKind kind);

struct BendStep {
  StepKind kind = StepKind::kBendUp;
  // The bend line in part coordinates (on the blank); the moving side lies to its left. Every step
  // uses it to place the part: the bend line on the machine's, the moving side towards +Y.
  Vec2 bend_point_mm = Vec2::Zero();
  Vec2 bend_direction = Vec2::UnitX();
  double target_angle_deg = 90.0;  // BEND_UP / BEND_DOWN: magnitude, (0, max_bend_angle]
  double rotate_angle_deg = 90.0;  // ROTATE: about the vertical axis through the manipulator, signed
  Vec3 travel_mm = Vec3::Zero();   // APPROACH / RETRACT: how the part moves
  double lateral_shift_mm = 0.0;   // REPO: the part's shift along the bend line (machine X)
  // ROTATE, APPROACH, RETRACT: the manipulator (and the part it holds) stands this far back (-Y)
  // from the state's manipulator point when the motion starts: a ROTATE turns there.
  double retract_mm = 0.0;
  // APPROACH, RETRACT: the part and manipulator were turned by this about the vertical axis through
  // the manipulator point (after retract_mm) since the part was placed for this bend line, e.g. a
  // re-approach after a retracted ROTATE. [deg]
  double turned_deg = 0.0;

  Hash128 hash() const;
};

// Checks the step against the machine (angles in range, finite vectors, non-zero bend line).
Result<bool> validate_step(const MachineModel& model, const BendStep& step);

// Part coordinates -> machine coordinates for the step: the bend line onto the machine X axis,
// the moving side towards +Y, the blank's lower face on Z = 0, the part centred along X (plus the
// step's lateral shift).
RigidTransform part_placement(const SheetPart& part, const BendStep& step);

}  // namespace gk::p4
