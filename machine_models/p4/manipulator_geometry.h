// The manipulator's bodies where it stands: suction cups on the sheet's upper face, the gripper
// frame on them, the rotator column on the frame's centre (dimensions from the model file).
#pragma once

#include "machine_models/p4/machine_model.h"
#include "machine_models/p4/sheet_part.h"

#include <vector>

namespace gk::p4 {

// The bodies as plates in machine coordinates, the gripper centred on `point` (x, y), turned by
// rotation_deg about the vertical axis, the cups standing on z = sheet_top_z. Labels name them:
// "manipulator.cup.<i>", "manipulator.frame", "manipulator.rotator".
std::vector<Plate> manipulator_plates(const ManipulatorSpec& spec, const Vec2& point, double rotation_deg,
                                      double sheet_top_z);

}  // namespace gk::p4
