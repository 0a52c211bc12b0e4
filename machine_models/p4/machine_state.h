// What the sequencer sets between steps: engaged ABA segments, clamp height, manipulator pose,
// blade positions.
#pragma once

#include "kernel/core/content_hash.h"
#include "kernel/core/status.h"

#include <cstdint>
#include <string>
#include <vector>

namespace gk::p4 {

struct MachineModel;

struct MachineState {
  std::vector<bool> engaged_segments;  // one per ABA slot; empty means every segment engaged
  double clamp_z_mm = 1.0;             // blankholder height above the table: the sheet's upper face
  double manipulator_x_mm = 0.0;
  double manipulator_y_mm = -600.0;
  double manipulator_rotation_deg = 0.0;
  double lower_blade_z_offset_mm = 0.0;  // from its parked position, + up

  Hash128 hash() const;
  // Every field equal (a hash may collide: a validator is set to a state by equality).
  bool operator==(const MachineState& other) const;
  bool operator!=(const MachineState& other) const { return !(*this == other); }

  // Engages exactly the slots lying within [x_min, x_max] (a slot sticking out is left
  // disengaged) and disengages every other slot.
  static MachineState with_aba_span(const MachineModel& model, double x_min, double x_max, double clamp_z_mm);
};

// Checks the state against the model (slot count, finite values, manipulator travel).
Result<bool> validate_state(const MachineModel& model, const MachineState& state);

}  // namespace gk::p4
